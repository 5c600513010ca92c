//! Progressive accumulation: a compensated sum per pixel.

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

/// The samples of one pixel in one frame.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct PixelSamples {
    /// Sum of the finite sample radiances.
    pub sum: Vec3,
    /// Number of finite samples in `sum`.
    pub valid: u32,
    /// Number of samples discarded because a channel was NaN or infinite.
    pub non_finite: u32,
}

/// One pixel of the accumulation buffer.
///
/// The running sum is Kahan-compensated: a plain f32 sum stops growing once
/// it is 2^24 times a sample, which would freeze a progressive image; with
/// the compensation term the mean stays accurate to a few ulps whatever the
/// sample count (Kahan 1965; Higham, "Accuracy and Stability", 4.3).
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AccumPixel {
    /// Sum of accepted sample radiances, linear RGB.
    pub sum: Vec3,
    /// Number of accepted samples.
    pub samples: u32,
    /// Kahan compensation: the low-order part lost from `sum`, negated.
    pub compensation: Vec3,
    /// Number of samples discarded as NaN or infinite.
    pub non_finite: u32,
}

/// Adds `x` to the compensated sum (`sum`, `compensation`): Kahan's
/// summation.
///
/// `keep` must be true, from a value the shader compiler cannot know (one
/// read from the parameter buffer that no pipeline compiles in, as
/// `FrameParams::keeps_sums`). SPIR-V arithmetic without the NoContraction decoration may be
/// reassociated by the driver (Mesa's NIR does, in lavapipe), which folds
/// `(t - sum) - y` to zero and silently turns Kahan's sum into a plain one.
/// Passing `t` through a select on `keep` hides that `t == sum + y` (the
/// "select trick" from the WebGPU precise-math discussion, gpuweb#2080).
pub fn kahan_add(sum: &mut Vec3, compensation: &mut Vec3, x: Vec3, keep: bool) {
    let y = x - *compensation;
    let t = *sum + y;
    let t = if keep { t } else { Vec3::ZERO };
    *compensation = (t - *sum) - y;
    *sum = t;
}

impl AccumPixel {
    /// Adds one frame's samples. `keep` is true (see [`kahan_add`]).
    pub fn add(&mut self, s: PixelSamples, keep: bool) {
        kahan_add(&mut self.sum, &mut self.compensation, s.sum, keep);
        self.samples += s.valid;
        self.non_finite += s.non_finite;
    }

    /// Mean radiance of the accepted samples (zero when there are none).
    pub fn mean(&self) -> Vec3 {
        if self.samples == 0 {
            Vec3::ZERO
        } else {
            // sum - compensation carries the bits the plain sum lost.
            (self.sum - self.compensation) / self.samples as f32
        }
    }
}

/// Whether every channel is finite. Tested on the bit pattern, which no
/// driver's fast-math can fold away (unlike `x == x`).
pub fn is_finite(v: Vec3) -> bool {
    let m = 0x7f80_0000;
    (v.x.to_bits() & m) != m && (v.y.to_bits() & m) != m && (v.z.to_bits() & m) != m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_stays_right_after_2_pow_25_samples() {
        // Case: a plain f32 sum of 0.1s stalls at 2^21 (where 0.1 is below
        // half an ulp of the sum); the compensated mean must stay within
        // 1e-5 relative of the f64 sum.
        let mut p = AccumPixel::default();
        let x = Vec3::new(0.1, 1.7, 3.3e-3);
        let per_frame = 8;
        let frames = (1u32 << 25) / per_frame;
        for _ in 0..frames {
            p.add(PixelSamples { sum: x * per_frame as f32, valid: per_frame, non_finite: 0 }, true);
        }
        assert_eq!(p.samples, 1 << 25);
        let m = p.mean();
        for (got, want) in [(m.x, x.x), (m.y, x.y), (m.z, x.z)] {
            assert!(((got - want) / want).abs() < 1e-5, "mean {got} vs {want}");
        }
    }

    #[test]
    fn non_finite_is_detected_on_every_channel() {
        assert!(is_finite(Vec3::new(1.0, -2.0, f32::MAX)));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert!(!is_finite(Vec3::new(bad, 0.0, 0.0)));
            assert!(!is_finite(Vec3::new(0.0, bad, 0.0)));
            assert!(!is_finite(Vec3::new(0.0, 0.0, bad)));
        }
    }

    #[test]
    fn empty_pixel_has_zero_mean() {
        assert_eq!(AccumPixel::default().mean(), Vec3::ZERO);
    }
}
