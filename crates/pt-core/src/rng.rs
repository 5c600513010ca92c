//! Random numbers: a PCG hash of (pixel, frame, sample) seeds a PCG32 stream.
//!
//! Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 9(3), 2020:
//! `pcg4d` decorrelates the four inputs (neighbouring pixels, consecutive
//! frames and samples get unrelated streams), then each dimension of the
//! path draws the next output of a PCG RXS-M-XS 32-bit generator.

use spirv_std::glam::{UVec4, Vec2};

/// `pcg` one-dimensional hash (Jarzynski and Olano 2020).
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// `pcg4d` four-dimensional hash (Jarzynski and Olano 2020).
pub fn pcg4d(v: UVec4) -> UVec4 {
    // Wrapping, as the reference's unsigned arithmetic (and not a panic in
    // builds with overflow checks).
    let mut v = v.wrapping_mul(UVec4::splat(1_664_525)).wrapping_add(UVec4::splat(1_013_904_223));
    v.x = v.x.wrapping_add(v.y.wrapping_mul(v.w));
    v.y = v.y.wrapping_add(v.z.wrapping_mul(v.x));
    v.z = v.z.wrapping_add(v.x.wrapping_mul(v.y));
    v.w = v.w.wrapping_add(v.y.wrapping_mul(v.z));
    v ^= v >> 16;
    v.x = v.x.wrapping_add(v.y.wrapping_mul(v.w));
    v.y = v.y.wrapping_add(v.z.wrapping_mul(v.x));
    v.z = v.z.wrapping_add(v.x.wrapping_mul(v.y));
    v.w = v.w.wrapping_add(v.y.wrapping_mul(v.z));
    v
}

/// A PCG RXS-M-XS 32/32 generator: one stream per camera sample.
#[derive(Copy, Clone, Debug)]
pub struct Rng {
    state: u32,
}

impl Rng {
    /// The stream of camera sample `sample` of pixel (`x`, `y`) in frame
    /// `frame`, for the user's `seed`. Distinct inputs give unrelated streams.
    pub fn new(x: u32, y: u32, frame: u32, sample: u32, seed: u32) -> Self {
        Self::with_seed_hash(x, y, frame, sample, pcg_hash(seed))
    }

    /// [`Rng::new`] given `pcg_hash(seed)`, which a pixel's samples share.
    pub(crate) fn with_seed_hash(x: u32, y: u32, frame: u32, sample: u32, seed_hash: u32) -> Self {
        let h = pcg4d(UVec4::new(x, y, frame, sample ^ seed_hash));
        Self { state: h.x ^ h.y.rotate_left(16) ^ h.z ^ h.w.rotate_left(8) }
    }

    /// The stream whose state is `state`, which must already be a hash.
    pub(crate) fn from_state(state: u32) -> Self {
        Self { state }
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        self.state = self.state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        let s = self.state;
        let word = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
        (word >> 22) ^ word
    }

    /// A uniform float in [0, 1): the top 24 bits, so every value is exact.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform floats in [0, 1), in the order drawn.
    pub fn next_pair(&mut self) -> Vec2 {
        let u = self.next_f32();
        Vec2::new(u, self.next_f32())
    }
}

/// Pearson correlation of the first draw of pixel (x, y) in frame 3 with
/// that of pixel (x + `dx`, y) in frame 3 + `dframe`, over `n` pixels of a
/// 500-wide image: near 0 (standard error 1/sqrt(n)) for a good hash.
#[cfg(not(target_arch = "spirv"))]
pub fn stream_correlation(n: u32, dx: u32, dframe: u32) -> f64 {
    let (mut sa, mut sb, mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        let (x, y) = (i % 500, i / 500);
        let a = Rng::new(x, y, 3, 0, 0).next_f32() as f64;
        let b = Rng::new(x + dx, y, 3 + dframe, 0, 0).next_f32() as f64;
        sa += a;
        sb += b;
        sab += a * b;
        saa += a * a;
        sbb += b * b;
    }
    let nf = n as f64;
    let cov = sab / nf - sa * sb / (nf * nf);
    cov / ((saa / nf - (sa / nf).powi(2)) * (sbb / nf - (sb / nf).powi(2))).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_hash_matches_the_reference_implementation() {
        // Values of the JCGT 2020 reference code `pcg(v)`, computed by hand
        // from its definition for v = 0 and v = 1.
        let reference = |v: u32| {
            let state = (v as u64 * 747_796_405 + 2_891_336_453) as u32;
            let word = (((state >> ((state >> 28) + 4)) ^ state) as u64 * 277_803_737) as u32;
            (word >> 22) ^ word
        };
        for v in [0, 1, 2, 12345, u32::MAX] {
            assert_eq!(pcg_hash(v), reference(v));
        }
    }

    #[test]
    fn floats_are_uniform_in_unit_interval() {
        // 16 bins, 1.6e5 draws: chi-square with 15 dof; 37.7 is its 0.999 quantile.
        let mut rng = Rng::new(1, 2, 3, 4, 5);
        let mut bins = [0u32; 16];
        let n = 160_000;
        for _ in 0..n {
            let u = rng.next_f32();
            assert!((0.0..1.0).contains(&u));
            bins[(u * 16.0) as usize] += 1;
        }
        let e = n as f64 / 16.0;
        let chi2: f64 = bins.iter().map(|&b| (b as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 37.7, "chi2 = {chi2}");
    }

    #[test]
    fn neighbouring_pixels_and_frames_are_uncorrelated() {
        // Over 1e5 pixels: |r| < 5 / sqrt(n) = 0.016.
        let n = 100_000u32;
        for (dx, dframe) in [(1, 0), (0, 1)] {
            let r = stream_correlation(n, dx, dframe);
            assert!(r.abs() < 5.0 / (n as f64).sqrt(), "dx {dx} dframe {dframe}: r = {r}");
        }
    }

    #[test]
    fn distinct_inputs_give_distinct_streams() {
        let first = |x, y, f, s, seed| Rng::new(x, y, f, s, seed).next_u32();
        let base = first(10, 20, 30, 0, 0);
        assert_ne!(base, first(11, 20, 30, 0, 0));
        assert_ne!(base, first(10, 21, 30, 0, 0));
        assert_ne!(base, first(10, 20, 31, 0, 0));
        assert_ne!(base, first(10, 20, 30, 1, 0));
        assert_ne!(base, first(10, 20, 30, 0, 1));
    }

    /// Case: 1,000,000 floats in 1000 equal bins pass a chi-square test.
    #[test]
    fn floats_pass_chi_square_in_a_thousand_bins() {
        use crate::test_support::chi2::chi2_test;
        use crate::test_support::chi2_alpha;
        let mut rng = Rng::new(1, 2, 3, 4, 5);
        let mut observed = vec![0.0; 1000];
        for _ in 0..1_000_000 {
            observed[(rng.next_f32() * 1000.0) as usize] += 1.0;
        }
        let r = chi2_test(&observed, &vec![1000.0; 1000]);
        assert!(r.p_value >= chi2_alpha(), "chi2 {:.1}, p = {:.2e}", r.chi2, r.p_value);
    }
}
