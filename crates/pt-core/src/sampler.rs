//! Sample generators for the path loop: independent PCG numbers, or
//! randomised Sobol points.
//!
//! The Sobol sampler is "padded 2D": every pair of dimensions the path asks
//! for (pixel jitter, then per bounce the light sample and the BSDF sample)
//! is the 2D Sobol (0,2)-sequence at the pixel's sample index shuffled by
//! Owen scrambling (Burley, "Practical Hash-based Owen Scrambling", JCGT
//! 9(4), 2020), its values then randomised by a digital shift (an xor),
//! each with seeds hashed from the pixel, the user seed and the pair
//! number. Each pair is then stratified at every power-of-two sample count,
//! and pairs are decorrelated from each other and across pixels.
//!
//! The values take a digital shift, not Burley's Owen scrambling: both keep
//! every block of 2^m points a (0, m, 2)-net and make each point uniform,
//! so the estimate stays unbiased, and at the sample counts the renderer
//! runs (tens to hundreds per pixel, integrands cut by the edges of shadows
//! and walls) relMSE was the same within a few per cent on the suite's
//! scenes, while the shift saves the eight integer multiplies of two
//! Laine-Karras hashes per draw (docs/ARCHITECTURE.md, "Samples", has the
//! figures). The index shuffle keeps Owen scrambling: an xor of the index
//! would only shift the values of a digital sequence again, and leave
//! padded pairs correlated.
//!
//! One run of draws is jointly stratified instead of padded: the first
//! bounce's direction and every draw of the vertex it finds, through that
//! vertex's own direction ([`joint_draws`]). Each takes the 2D point at its
//! own transform of the unshuffled index ([`joint_index`]), chosen so that
//! the run's numbers, taken together, are stratified: 64 samples put one
//! point in each half of each of the six dimensions' 64 combinations (1,024
//! samples, ten dimensions, with connections). Light reached through the
//! first bounce is then integrated over strata of whole two-vertex paths,
//! not over strata of each pair matched at random; the first bounce
//! carries most of the noise that remains around large lights.
//!
//! Without connections the draws before the run, the pixel jitter and the
//! first light sample, take the two transforms the run leaves
//! ([`joint_transform`]): every Sobol draw of such a path is then part of
//! one jointly stratified set, the pixel's footprint and the first light
//! sample too. That took relMSE at 64 spp a further 2% to 3% lower around
//! the lights of the suite's held-out scenes.
//!
//! Only the first [`SOBOL_DRAWS`] draws of a path are Sobol points; later
//! ones, deep in the path, come from an independent PCG stream, which costs
//! a quarter of the integer multiplies.

use spirv_std::glam::Vec2;

use crate::params::{FLAG_CONNECT, FLAG_NEE, FrameParams};
use crate::rng::{Rng, pcg_hash};

/// What the path loop draws its random numbers from.
///
/// A draw takes what the pixel's samples share (`Self::Pixel`) as an
/// argument instead of keeping it in the sample's state: the path loop
/// carries its state from one pass to the next, and lavapipe folds nothing
/// that goes round a loop, not even a constant of the flags compiled into
/// the small-scene kernels (docs/ARCHITECTURE.md, "The small-scene
/// kernel"), where the pixel's part, made before the loop, is folded.
pub trait Sampler {
    /// What the generators of one pixel's camera samples share in a frame
    /// (hashes of the pixel and the seed): worked out once per pixel, not
    /// once per sample.
    type Pixel: Copy;
    /// The shared part for pixel (`x`, `y`) in the frame that `params`
    /// describes.
    fn for_pixel(x: u32, y: u32, params: &FrameParams) -> Self::Pixel;
    /// The generator for camera sample `s` of the pixel `pixel` was made for.
    fn for_camera_sample(pixel: Self::Pixel, s: u32, params: &FrameParams) -> Self;
    /// The next number in [0, 1), for a sample of the pixel whose shared
    /// part is `pixel`.
    fn next_1d(&mut self, pixel: Self::Pixel) -> f32;
    /// The next pair of numbers in [0, 1)^2, for a sample of the pixel
    /// whose shared part is `pixel`.
    fn next_2d(&mut self, pixel: Self::Pixel) -> Vec2;
}

impl Sampler for Rng {
    /// The pixel's coordinates and the hash of the seed.
    type Pixel = (u32, u32, u32);

    fn for_pixel(x: u32, y: u32, params: &FrameParams) -> Self::Pixel {
        (x, y, pcg_hash(params.seed))
    }

    fn for_camera_sample((x, y, seed_hash): Self::Pixel, s: u32, params: &FrameParams) -> Self {
        Rng::with_seed_hash(x, y, params.frame, s, seed_hash)
    }

    fn next_1d(&mut self, _: Self::Pixel) -> f32 {
        self.next_f32()
    }

    fn next_2d(&mut self, _: Self::Pixel) -> Vec2 {
        self.next_pair()
    }
}

/// Burley's (2020) improvement of the Laine-Karras hash: a permutation of
/// u32 where each bit depends only on the bits below it.
pub fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Nested uniform (Owen) scrambling of a 32-bit fraction (Burley 2020).
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// The first two Sobol dimensions at `index`, as 32-bit fractions:
/// van der Corput, and the dimension with direction numbers v_i = v_{i-1}
/// xor (v_{i-1} >> 1), v_0 = 2^31 (Joe and Kuo's first polynomial).
pub fn sobol_2d(index: u32) -> (u32, u32) {
    let mut y = 0u32;
    let mut v = 1u32 << 31;
    let mut i = index;
    while i != 0 {
        if i & 1 != 0 {
            y ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    (index.reverse_bits(), y)
}

/// The two values of the 2D Sobol point whose index bit-reversed is
/// `index_reversed`, each shifted by an xor with its own seed (a digital
/// shift), as 32-bit fractions: dimension 0 is the reversed index itself,
/// dimension 1 [`sobol_dim1`] of it. The seeds must be independent and
/// uniform for the points to be. The sampler keeps its indices reversed,
/// so that no draw reverses bits (several vector instructions each).
#[inline]
pub fn shifted_sobol_2d(index_reversed: u32, seed_0: u32, seed_1: u32) -> (u32, u32) {
    (index_reversed ^ seed_0, sobol_dim1(index_reversed) ^ seed_1)
}

/// The second Sobol dimension at the index whose bit reversal is
/// `index_reversed`: the same as `sobol_2d(index).1`, without a loop.
///
/// Its direction numbers, read from the top bit down, are v_k = (1 + x)^k
/// over GF(2), whose coefficient j is 1 exactly when j is a submask of k
/// (Lucas). In the reversed index, bit 31 - k is index bit k; with the
/// complements of the five-bit positions, bit m of the value is the xor of
/// the reversed index's bits l that are submasks of m: a subset-sum
/// transform, five shift-and-mask steps.
pub fn sobol_dim1(index_reversed: u32) -> u32 {
    let mut y = index_reversed;
    y ^= (y << 1) & 0xaaaa_aaaa;
    y ^= (y << 2) & 0xcccc_cccc;
    y ^= (y << 4) & 0xf0f0_f0f0;
    y ^= (y << 8) & 0xff00_ff00;
    y ^= (y << 16) & 0xffff_0000;
    y
}

/// The jointly stratified draws of a path under integrator `flags`: the
/// number of the first (the pixel jitter is draw 1), which is also how many
/// there are. They run from the first vertex's BSDF direction through the
/// second vertex's: the second vertex draws what the first did (its light
/// sample, and with connections the connection's two pairs), so the run is
/// one draw longer than the draws before it. Without connections that is 3
/// (a BSDF direction, a light sample, a BSDF direction: six dimensions),
/// with them 5 (ten), without NEE 2 (two BSDF directions).
///
/// Russian roulette from the first or second bounce draws a number inside
/// the run, which then ends a draw early, and a path that ends at its first
/// vertex leaves the run unused; every draw stays uniform whatever the
/// pattern, so the estimate is unbiased under any flags.
#[inline]
pub fn joint_draws(flags: u32) -> u32 {
    if flags & FLAG_NEE == 0 {
        2
    } else if flags & FLAG_CONNECT != 0 {
        5
    } else {
        3
    }
}

/// The index at which draw `g` (from 0) of the jointly stratified run takes
/// its 2D Sobol point, for sample index `i`: `i` xor some right shifts of
/// it. Each transform maps every aligned block of 2^m indices onto an
/// aligned block (output bit k depends on input bits k and above), so each
/// draw alone is still a (0, 2)-sequence over the pixel's samples; the
/// shifts, found by a search over up to three shifts of at most 9, make the
/// leading bits of the run's dimensions independent linear functions of
/// the index's low bits: 2^(2n) samples fill every half-cell of the first
/// n draws' 2n dimensions (n up to 5), and 256 fill every quarter-cell of
/// the first two draws' four (and half of those of the other pairs among
/// the first three, twice each, as Sobol's own dimensions 0 to 3 do).
/// Shifts and xors, where a Sobol dimension beyond the second would take a
/// table walk per draw, which made lavapipe's frames 1.7 to 1.9 times as
/// long in a trial. The sampler takes it bit-reversed
/// ([`joint_index_reversed`]).
#[inline]
pub fn joint_index(g: u32, i: u32) -> u32 {
    joint_index_reversed(g, i.reverse_bits()).reverse_bits()
}

/// [`joint_index`] bit-reversed, from the index bit-reversed (`r`): a right
/// shift of the index is the same left shift of its reversal.
/// `pt-render`'s eight-lane sampler writes the same shifts out; its tests
/// compare the two bit for bit.
#[inline]
pub fn joint_index_reversed(g: u32, r: u32) -> u32 {
    match g {
        0 => r,
        1 => r ^ (r << 2) ^ (r << 6) ^ (r << 7),
        2 => r ^ (r << 1) ^ (r << 4) ^ (r << 7),
        3 => r ^ (r << 1) ^ (r << 5) ^ (r << 8),
        _ => r ^ (r << 3) ^ (r << 7),
    }
}

/// How many transforms [`joint_index`] has.
pub const JOINT_TRANSFORMS: u32 = 5;

/// Which of [`joint_index`]'s transforms draw `pair` (from 1, the pixel
/// jitter) takes when the jointly stratified run starts at draw `joint`
/// ([`joint_draws`]); [`JOINT_TRANSFORMS`] or more where it takes none (a
/// shuffled index). The run's draws take the first transforms in order;
/// the draws before the run take those the run leaves, in order, as far as
/// they go: without connections the pixel jitter and the first light sample
/// take the last two, so every Sobol draw of the path is stratified jointly
/// with the others (2^10 samples fill every half-cell of the ten
/// dimensions); with connections, whose run takes all five, the draws
/// before it are padded.
#[inline]
pub fn joint_transform(pair: u32, joint: u32) -> u32 {
    if pair < joint {
        pair + joint - 1
    } else if pair < 2 * joint {
        pair - joint
    } else {
        JOINT_TRANSFORMS
    }
}

/// Whether all of the `draws` Sobol draws of a path whose jointly
/// stratified run starts at draw `joint` take a transform
/// ([`joint_transform`]): then none needs the shuffle, and a kernel whose
/// flags are compiled in leaves its code out (on lavapipe every line of
/// the loop costs its time in every pass, taken or not). True of the
/// default sampler without connections: its five draws take the five
/// transforms.
#[inline]
pub fn all_draws_joint(draws: u32, joint: u32) -> bool {
    joint > 0 && 2 * joint - 2 < JOINT_TRANSFORMS && draws < 2 * joint
}

/// The digital shift of a draw's first value, from the draw's seed (which
/// the index shuffle takes as it is).
#[inline]
pub fn value_seed_0(seed: u32) -> u32 {
    seed ^ 0xa511_e9b3
}

/// The digital shift of a draw's second value: the seed times an odd
/// constant, a bijection whose leading bits, those that move the value
/// most, depend on all of the seed's bits, where the first value's shift
/// takes them as they are.
#[inline]
pub fn value_seed_1(seed: u32) -> u32 {
    seed.wrapping_mul(0x2c1b_3c6d) ^ 0x297a_2d39
}

fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Draws of a path (1D or 2D) that the default sampler takes from the
/// Sobol sequence: the pixel jitter, then the light and BSDF samples of the
/// first two vertices. Later draws use an independent PCG stream.
///
/// Stratification pays where it shapes the image most: the pixel, the
/// direct light and the first indirect bounce, whose BSDF sample aims the
/// glow lobe at the bright ceiling. Deeper, each pair is stratified alone
/// but not jointly with the earlier ones, and gains little, while a Sobol
/// draw costs 4 to 8 integer multiplies and no bit reversal against 2 to 4
/// multiplies for PCG. Five draws gave the lowest relMSE x
/// time of the counts measured, when the values were Owen-scrambled and a
/// draw cost 11 to 16 multiplies (CHANGELOG.md has the figures);
/// `pathtracer bench` compares it with Sobol everywhere (`FLAG_SOBOL_DEEP`).
pub const SOBOL_DRAWS: u32 = 5;

/// What the Sobol samples of one pixel share: [`Sampler::Pixel`] of
/// [`SobolSampler`].
#[derive(Copy, Clone, Debug)]
pub struct SobolPixel {
    /// Hash of pixel and user seed.
    seed: u32,
    /// The first jointly stratified draw, and how many there are
    /// ([`joint_draws`]).
    joint: u32,
}

impl SobolPixel {
    /// Pixel (`x`, `y`) for user seed `seed`, for the draws of integrator
    /// `flags` ([`joint_draws`]).
    pub fn new(x: u32, y: u32, seed: u32, flags: u32) -> Self {
        Self { seed: pcg_hash(pcg_hash(x ^ pcg_hash(y ^ pcg_hash(seed)))), joint: joint_draws(flags) }
    }
}

/// Padded 2D Sobol samples (the index Owen-scrambled, the values digitally
/// shifted) for one camera sample, for its first `DRAWS` draws, then
/// independent PCG numbers. `SobolSampler<{ u32::MAX }>` draws every number
/// from the Sobol sequence.
#[derive(Copy, Clone, Debug)]
pub struct SobolSampler<const DRAWS: u32 = SOBOL_DRAWS> {
    /// Index of this sample among the pixel's samples (across frames),
    /// bit-reversed: every draw works on the reversed index.
    index_reversed: u32,
    /// Draws made so far (the number of the next pair, from 0).
    pair: u32,
    /// The stream of the draws after the first `DRAWS`.
    tail: Rng,
}

impl<const DRAWS: u32> SobolSampler<DRAWS> {
    /// The sampler of sample `index` of the pixel `pixel`.
    pub fn new(pixel: SobolPixel, index: u32) -> Self {
        // Seeded by a hash of pixel, seed and index: distinct samples get
        // unrelated streams. Not needed when every draw is a Sobol point.
        let tail = if DRAWS == u32::MAX { 0 } else { pcg_hash(pixel.seed ^ index.wrapping_mul(0x9e37_79b9)) };
        Self { index_reversed: index.reverse_bits(), pair: 0, tail: Rng::from_state(tail) }
    }

    /// The seed of the next dimension (pair) of a sample of `pixel`: one
    /// hash per draw.
    fn next_seed(&mut self, pixel: SobolPixel) -> u32 {
        self.pair += 1;
        pcg_hash(pixel.seed ^ self.pair.wrapping_mul(0x9e37_79b9))
    }

    /// The index of the 2D Sobol point of the draw just counted, whose seed
    /// is `seed`, bit-reversed: the index shuffled with that seed (Burley's
    /// padding: Owen scrambling, `reverse(LK(reverse(i)))`, so reversed
    /// the Laine-Karras permutation of the reversed index alone), or for
    /// the jointly stratified draws the unshuffled index's own transform
    /// ([`joint_index_reversed`]). The joint draws need no shuffle to keep
    /// apart from the padded ones, whose own shuffles pair their samples
    /// with the run's at random; the shifts of their values, seeded per
    /// draw, decorrelate them from other pixels.
    fn point_index_reversed(&self, pixel: SobolPixel, seed: u32) -> u32 {
        let g = joint_transform(self.pair, pixel.joint);
        if g < JOINT_TRANSFORMS || all_draws_joint(DRAWS, pixel.joint) {
            joint_index_reversed(g, self.index_reversed)
        } else {
            laine_karras_permutation(self.index_reversed, seed)
        }
    }
}

impl<const DRAWS: u32> Sampler for SobolSampler<DRAWS> {
    type Pixel = SobolPixel;

    fn for_pixel(x: u32, y: u32, params: &FrameParams) -> Self::Pixel {
        SobolPixel::new(x, y, params.seed, params.flags)
    }

    fn for_camera_sample(pixel: Self::Pixel, s: u32, params: &FrameParams) -> Self {
        // The index runs on across frames: stratified over the whole render.
        Self::new(pixel, params.sample_offset + s)
    }

    fn next_1d(&mut self, pixel: Self::Pixel) -> f32 {
        if self.pair >= DRAWS {
            return self.tail.next_f32();
        }
        // One dimension: the digitally shifted van der Corput sequence at
        // the shuffled index (the first value of the pair `next_2d` draws).
        let seed = self.next_seed(pixel);
        to_unit(self.point_index_reversed(pixel, seed) ^ value_seed_0(seed))
    }

    fn next_2d(&mut self, pixel: Self::Pixel) -> Vec2 {
        if self.pair >= DRAWS {
            return self.tail.next_pair();
        }
        let seed = self.next_seed(pixel);
        // Shuffle the index (Burley's padding) or transform it (a joint
        // draw), then shift each value with its own seed.
        let (a, b) = shifted_sobol_2d(self.point_index_reversed(pixel, seed), value_seed_0(seed), value_seed_1(seed));
        Vec2::new(to_unit(a), to_unit(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::FLAGS_DEFAULT;

    /// A Sobol sample with its pixel's shared part, for tests that draw
    /// from one sample at a time.
    struct Bound<const DRAWS: u32> {
        sampler: SobolSampler<DRAWS>,
        pixel: SobolPixel,
    }

    impl<const DRAWS: u32> Bound<DRAWS> {
        /// Sample `index` of pixel (`x`, `y`) for `seed` under `flags`.
        fn new(x: u32, y: u32, index: u32, seed: u32, flags: u32) -> Self {
            let pixel = SobolPixel::new(x, y, seed, flags);
            Self { sampler: SobolSampler::new(pixel, index), pixel }
        }

        fn next_1d(&mut self) -> f32 {
            self.sampler.next_1d(self.pixel)
        }

        fn next_2d(&mut self) -> Vec2 {
            self.sampler.next_2d(self.pixel)
        }
    }

    /// Whether the points fill every elementary interval of area 1/n of
    /// every shape (2^k x 2^(m-k)) with exactly one point: the (0, m, 2)-net
    /// property of the first n = 2^m points.
    fn is_02_net(points: &[(u32, u32)], m: u32) -> bool {
        (0..=m).all(|k| {
            let mut seen = vec![false; 1 << m];
            // The top `bits` bits of a 32-bit fraction.
            let top = |v: u32, bits: u32| if bits == 0 { 0 } else { (v >> (32 - bits)) as usize };
            points.iter().all(|&(a, b)| {
                let cell = (top(a, k) << (m - k)) | top(b, m - k);
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    #[test]
    fn sobol_2d_is_a_02_sequence() {
        let pts: Vec<_> = (0..256).map(sobol_2d).collect();
        for m in 0..=8 {
            for start in (0..256).step_by(1 << m) {
                assert!(is_02_net(&pts[start..start + (1 << m)], m), "m {m} start {start}");
            }
        }
        assert_eq!(sobol_2d(1), (1 << 31, 1 << 31));
        assert_eq!(sobol_2d(2), (1 << 30, 3 << 30));
    }

    #[test]
    fn shifted_points_are_sobols_shifted_and_keep_the_net_property() {
        for seed in [1u32, 77, 0xdead_beef] {
            let (s0, s1) = (value_seed_0(seed), value_seed_1(seed));
            let pts: Vec<_> = (0..128u32).map(|i| shifted_sobol_2d(i.reverse_bits(), s0, s1)).collect();
            for (i, &(a, b)) in pts.iter().enumerate() {
                let (x, y) = sobol_2d(i as u32);
                assert_eq!((a, b), (x ^ s0, y ^ s1), "seed {seed} index {i}");
            }
            // Every aligned block of 2^m points stays a (0, m, 2)-net.
            for m in 0..=7 {
                for start in (0..128).step_by(1 << m) {
                    assert!(is_02_net(&pts[start..start + (1 << m)], m), "seed {seed} m {m} start {start}");
                }
            }
        }
    }

    #[test]
    fn shuffled_index_permutes_each_power_of_two_block() {
        // Owen-scrambling the index maps the first 2^m indices to numbers
        // whose low m bits are a permutation of 0..2^m; the Sobol matrices
        // are triangular, so the first m bits of the points (the strata at
        // 2^m samples) depend on those bits only: stratification is kept.
        let seed = 12345;
        let mut v: Vec<u32> = (0..64).map(|i| nested_uniform_scramble(i, seed) & 63).collect();
        v.sort_unstable();
        assert_eq!(v, (0..64).collect::<Vec<_>>());
        // And the shuffled, scrambled points of a block still form a net.
        let pts: Vec<_> = (0..64).map(|i| sobol_2d(nested_uniform_scramble(i, seed))).collect();
        assert!(is_02_net(&pts, 6));
    }

    #[test]
    fn dimension_1_from_the_reversed_index_matches() {
        for i in [0u32, 1, 2, 3, 77, 1023, 0xdead_beef, u32::MAX].into_iter().chain(0..4096) {
            assert_eq!(sobol_dim1(i.reverse_bits()), sobol_2d(i).1, "index {i}");
        }
    }

    #[test]
    fn reversed_joint_transforms_are_the_transforms_reversed() {
        // joint_index is defined through the reversed form; check it
        // against the right shifts it stands for.
        let shifts: [&[u32]; 5] = [&[], &[2, 6, 7], &[1, 4, 7], &[1, 5, 8], &[3, 7]];
        for (g, shifts) in shifts.iter().enumerate() {
            for i in [0u32, 1, 77, 1023, 0xdead_beef, u32::MAX].into_iter().chain(0..4096) {
                let right = shifts.iter().fold(i, |acc, &k| acc ^ (i >> k));
                assert_eq!(joint_index(g as u32, i), right, "transform {g} index {i}");
            }
        }
    }

    #[test]
    fn sampler_pairs_are_stratified_over_a_pixels_samples() {
        // The first 256 samples of a pixel: each dimension pair is a
        // (0, 8, 2)-net at 24-bit resolution.
        for pair in 0..4 {
            let pts: Vec<(u32, u32)> = (0..256)
                .map(|i| {
                    let mut s = Bound::<SOBOL_DRAWS>::new(7, 9, i, 3, FLAGS_DEFAULT);
                    for _ in 0..pair {
                        s.next_2d();
                    }
                    let u = s.next_2d();
                    (((u.x * 16_777_216.0) as u32) << 8, ((u.y * 16_777_216.0) as u32) << 8)
                })
                .collect();
            assert!(is_02_net(&pts, 8), "pair {pair}");
        }
    }

    #[test]
    fn per_pixel_part_gives_the_streams_of_the_direct_constructors() {
        // The per-pixel hashes are a hoisting, not a change of streams:
        // sample s of a frame is index sample_offset + s (Sobol) and stream
        // (x, y, frame, s, seed) (PCG), bit for bit.
        let params = FrameParams { seed: 42, frame: 3, sample_offset: 1000, ..FrameParams::default() };
        for (x, y) in [(0u32, 0u32), (5, 9), (255, 17)] {
            let (sobol, pcg) = (SobolSampler::<SOBOL_DRAWS>::for_pixel(x, y, &params), Rng::for_pixel(x, y, &params));
            for s in [0u32, 1, 63] {
                let mut split: SobolSampler = SobolSampler::for_camera_sample(sobol, s, &params);
                let mut direct = Bound::<SOBOL_DRAWS>::new(x, y, 1000 + s, 42, 0);
                let mut split_pcg = Rng::for_camera_sample(pcg, s, &params);
                let mut direct_pcg = Rng::new(x, y, 3, s, 42);
                // Past SOBOL_DRAWS: the PCG tail is the same too.
                for _ in 0..SOBOL_DRAWS + 3 {
                    assert_eq!(split.next_2d(sobol), direct.next_2d(), "pixel ({x}, {y}) sample {s}");
                    assert_eq!(split_pcg.next_u32(), direct_pcg.next_u32(), "pixel ({x}, {y}) sample {s}");
                }
            }
        }
    }

    /// The draw number `draw` (from 0, all 2D) of sample `index` of pixel
    /// (`x`, 5), seed 1, from the default sampler.
    fn nth_draw(x: u32, index: u32, draw: u32) -> Vec2 {
        let mut s = Bound::<SOBOL_DRAWS>::new(x, 5, index, 1, FLAGS_DEFAULT);
        for _ in 0..draw {
            s.next_2d();
        }
        s.next_2d()
    }

    #[test]
    fn the_first_draws_are_sobol_points_and_later_ones_are_not() {
        // The default sampler is the all-Sobol one cut short: the same first
        // SOBOL_DRAWS draws (mixed 1D and 2D), then other numbers.
        for index in [0u32, 1, 77] {
            let mut short = Bound::<SOBOL_DRAWS>::new(3, 4, index, 6, FLAGS_DEFAULT);
            let mut deep = Bound::<{ u32::MAX }>::new(3, 4, index, 6, FLAGS_DEFAULT);
            for draw in 0..SOBOL_DRAWS {
                if draw == 2 {
                    assert_eq!(short.next_1d(), deep.next_1d(), "index {index} draw {draw}");
                } else {
                    assert_eq!(short.next_2d(), deep.next_2d(), "index {index} draw {draw}");
                }
            }
            assert_ne!(short.next_2d(), deep.next_2d(), "index {index}: still Sobol after SOBOL_DRAWS draws");
        }
    }

    #[test]
    fn later_draws_are_uniform_and_independent_across_samples_and_pixels() {
        // The tail draw SOBOL_DRAWS + 1 of 40000 samples: 16 x 16 bins of its
        // pair, chi-square with 255 dof (330 is its 0.999 quantile); Pearson
        // correlation with the same draw of the next sample and of the next
        // pixel's same sample, |r| < 5 / sqrt(n) = 0.025.
        let n = 40_000u32;
        let mut bins = [0u32; 256];
        let (mut next_sample, mut next_pixel) = (Vec::new(), Vec::new());
        for i in 0..n {
            let (x, index) = (i % 200, i / 200);
            let u = nth_draw(x, index, SOBOL_DRAWS + 1);
            assert!((0.0..1.0).contains(&u.x) && (0.0..1.0).contains(&u.y));
            bins[(u.x * 16.0) as usize * 16 + (u.y * 16.0) as usize] += 1;
            next_sample.push((u.x as f64, nth_draw(x, index + 1, SOBOL_DRAWS + 1).x as f64));
            next_pixel.push((u.y as f64, nth_draw(x + 1, index, SOBOL_DRAWS + 1).y as f64));
        }
        let e = n as f64 / 256.0;
        let chi2: f64 = bins.iter().map(|&b| (b as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 330.0, "chi2 = {chi2}");
        let correlation = |pairs: &[(f64, f64)]| {
            let m = pairs.len() as f64;
            let (ma, mb) = (pairs.iter().map(|p| p.0).sum::<f64>() / m, pairs.iter().map(|p| p.1).sum::<f64>() / m);
            let cov = pairs.iter().map(|p| (p.0 - ma) * (p.1 - mb)).sum::<f64>();
            let va = pairs.iter().map(|p| (p.0 - ma).powi(2)).sum::<f64>();
            let vb = pairs.iter().map(|p| (p.1 - mb).powi(2)).sum::<f64>();
            cov / (va * vb).sqrt()
        };
        for (what, pairs) in [("next sample", &next_sample), ("next pixel", &next_pixel)] {
            let r = correlation(pairs);
            assert!(r.abs() < 5.0 / (n as f64).sqrt(), "{what}: r = {r}");
        }
    }

    #[test]
    fn sampler_values_are_in_unit_square_and_pairs_differ() {
        let mut s = Bound::<SOBOL_DRAWS>::new(3, 4, 5, 6, FLAGS_DEFAULT);
        let a = s.next_2d();
        let b = s.next_2d();
        assert!(a.x >= 0.0 && a.x < 1.0 && a.y >= 0.0 && a.y < 1.0);
        assert_ne!(a, b);
    }

    #[test]
    fn joint_transforms_map_every_aligned_block_onto_one() {
        // Each draw of the run alone stays a (0, 2)-sequence: the indices
        // of an aligned block of 2^m samples go to an aligned block.
        for g in 0..5 {
            for m in 0..=10u32 {
                for start in [0u32, 1 << m, 5 << m, 0xfff0_0000 & !((1 << m) - 1)] {
                    let mut v: Vec<u32> = (start..start + (1 << m)).map(|i| joint_index(g, i)).collect();
                    v.sort_unstable();
                    let first = v[0];
                    assert_eq!(first % (1 << m), 0, "draw {g}, block {start} of 2^{m}");
                    assert_eq!(v, (first..first + (1 << m)).collect::<Vec<_>>(), "draw {g}, block {start} of 2^{m}");
                }
            }
        }
    }

    /// The numbers of the jointly stratified run of `samples` samples of a
    /// pixel under `flags`, each as its top `bits` bits, draws before the
    /// run made as the path makes them (all 2D).
    fn joint_cells(flags: u32, samples: u32, bits: u32) -> Vec<Vec<u32>> {
        let first = joint_draws(flags);
        (0..samples)
            .map(|i| {
                let mut s = Bound::<{ u32::MAX }>::new(11, 4, i, 9, flags);
                for _ in 1..first {
                    s.next_2d();
                }
                (0..first)
                    .flat_map(|_| {
                        let u = s.next_2d();
                        [u.x, u.y].map(|v| (v * (1u32 << bits) as f32) as u32)
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn without_connections_every_sobol_draw_is_jointly_stratified() {
        // The jitter and the first light sample take the transforms the run
        // leaves: 2^(2n) samples fill every half-cell of all n draws from
        // the jitter on (5 with NEE, 3 without), where padding leaves about
        // a third of them empty.
        for (flags, n) in [(FLAGS_DEFAULT, 5u32), (0, 3)] {
            let mut cells: Vec<Vec<u32>> = (0..1u32 << (2 * n))
                .map(|i| {
                    let mut s = Bound::<{ u32::MAX }>::new(2, 8, i, 4, flags);
                    (0..n)
                        .flat_map(|_| {
                            let u = s.next_2d();
                            [u.x, u.y].map(|v| (v * 2.0) as u32)
                        })
                        .collect()
                })
                .collect();
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(cells.len(), 1 << (2 * n), "flags {flags:#x}");
        }
        // With connections the run takes all five transforms and the draws
        // before it are padded.
        assert_eq!(joint_transform(1, 5), JOINT_TRANSFORMS);
        assert_eq!((1..8).map(|p| joint_transform(p, 3)).collect::<Vec<_>>(), [3, 4, 0, 1, 2, 5, 5]);
        // Which samplers need no shuffle: exactly those whose every Sobol
        // draw takes a transform.
        for joint in [2, 3, 5] {
            for draws in [1, 3, 5, 6, 9, u32::MAX] {
                let every = (1..=draws.min(64)).all(|p| joint_transform(p, joint) < JOINT_TRANSFORMS);
                assert_eq!(all_draws_joint(draws, joint), every, "joint {joint}, draws {draws}");
            }
        }
        assert!(all_draws_joint(SOBOL_DRAWS, joint_draws(FLAGS_DEFAULT)));
    }

    #[test]
    fn the_joint_run_fills_every_half_cell_of_its_dimensions() {
        // 2^(2n) samples of a run of n draws (2n dimensions) put exactly one
        // point in each cell that halves every dimension: a padded sampler
        // matches the draws' strata at random and leaves about a third of
        // them empty (1 - 1/e). Scrambling keeps it: each scramble flips a
        // dimension's top bit, a permutation of the cells.
        for (flags, n) in [(FLAGS_DEFAULT, 3u32), (FLAGS_DEFAULT | FLAG_CONNECT, 5), (0, 2)] {
            assert_eq!(joint_draws(flags), n);
            let mut cells: Vec<Vec<u32>> = joint_cells(flags, 1 << (2 * n), 1);
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(cells.len(), 1 << (2 * n), "flags {flags:#x}");
        }
        // Two draws of the first three, cut in quarters along each of their
        // four dimensions: 256 samples put one point in each of the 256
        // cells for the first two, and two in each of half of them for the
        // others (as Sobol's own dimensions 0 to 3 do).
        let cells = joint_cells(FLAGS_DEFAULT, 256, 2);
        for (a, b, per_cell) in [(0, 1, 1), (0, 2, 2), (1, 2, 2)] {
            let mut count = std::collections::HashMap::new();
            for c in &cells {
                *count.entry([c[2 * a], c[2 * a + 1], c[2 * b], c[2 * b + 1]]).or_insert(0) += 1;
            }
            assert_eq!(count.len(), 256 / per_cell, "draws {a} and {b}");
            assert!(count.values().all(|&n| n == per_cell), "draws {a} and {b}");
        }
    }
}
