//! Random numbers: a PCG hash of (pixel, frame, sample) seeds a PCG32 stream.
//!
//! Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 9(3), 2020:
//! `pcg4d` decorrelates the four inputs (neighbouring pixels, consecutive
//! frames and samples get unrelated streams), then each dimension of the
//! path draws the next output of a PCG RXS-M-XS 32-bit generator.

use spirv_std::glam::UVec4;

/// `pcg` one-dimensional hash (Jarzynski and Olano 2020).
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// `pcg4d` four-dimensional hash (Jarzynski and Olano 2020).
pub fn pcg4d(v: UVec4) -> UVec4 {
    let mut v = v * 1_664_525 + UVec4::splat(1_013_904_223);
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
        let h = pcg4d(UVec4::new(x, y, frame, sample ^ pcg_hash(seed)));
        Self {
            state: h.x ^ h.y.rotate_left(16) ^ h.z ^ h.w.rotate_left(8),
        }
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        self.state = self
            .state
            .wrapping_mul(747_796_405)
            .wrapping_add(2_891_336_453);
        let s = self.state;
        let word = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
        (word >> 22) ^ word
    }

    /// A uniform float in [0, 1): the top 24 bits, so every value is exact.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}
