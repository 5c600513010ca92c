//! The CPU renderer's path loop, eight paths at a time.
//!
//! The GPU kernel runs [`pt_core::integrator`] once per pixel, and a GPU (or
//! lavapipe, with 8-wide AVX2 vectors) runs many pixels in lock-step. On the
//! CPU that code runs one path at a time and leaves most of each core's
//! vector width idle. This module is the same path loop written over AVX2
//! registers of eight lanes, one pixel per lane: each operation of
//! [`pt_core::integrator::Path::step`] is done for eight paths at once, and
//! lanes on the other side of a branch are masked off. A lane whose path
//! ends starts its pixel's next sample at once, as the scalar loop does.
//!
//! It is the same estimator, sample for sample: every lane does the scalar
//! code's floating-point operations in the same order (no fused
//! multiply-adds; sine and cosine by the polynomial of
//! [`pt_core::sampling::sin_cos_turn`], the logarithm and exponential of
//! the glow lobe by those of [`pt_core::sampling::ln_poly`] and
//! [`pt_core::sampling::exp_poly`]), draws the same random numbers, and
//! ends and restarts its paths where the scalar loop does. Each pixel's
//! samples are therefore bit for bit what
//! [`pt_core::integrator::render_pixel`] returns, which the tests check on
//! every integrator flag and on scenes that reach every branch; a change
//! to the path loop is made in both places, and those tests say where they
//! differ.
//!
//! x86-64 only, and only where the CPU has AVX2 ([`available`]); elsewhere
//! the CPU renderer runs `render_pixel` per pixel.

use core::arch::x86_64::*;
use core::array::from_fn;
use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use pt_core::FrameParams;
use pt_core::accum::PixelSamples;
use pt_core::bsdf::glow_probability;
use pt_core::camera::LightEdge;
use pt_core::geometry::{Geometry, MAX_SPHERES, MAX_WALLS};
use pt_core::glam::Vec3;
use pt_core::integrator::{RR_MIN_SURVIVAL, light_edge};
use pt_core::light::{GLOW_MIN_SCALE, GLOW_REACH};
use pt_core::params::{FLAG_MIS, FLAG_NEE, FLAG_NEE_PROJECTED, FLAG_RR_LUMINANCE, FLAG_SOBOL, FLAG_SOBOL_DEEP};
use pt_core::query::ShadowWalls;
use pt_core::ray::HIT_ERROR_EPS;
use pt_core::sampler::{JOINT_TRANSFORMS, SOBOL_DRAWS, all_draws_joint, joint_draws};
use pt_core::sampling::{PI, exp_reduced, exp_split, ln_reduced, ln_split, sin_cos_taylor};
use pt_core::wall::EDGE_SLACK;

/// Paths per group: the eight f32 lanes of an AVX2 register.
const LANES: usize = 8;

/// One f32 per lane.
#[derive(Copy, Clone)]
struct F(__m256);

/// One u32 per lane.
#[derive(Copy, Clone)]
struct U(__m256i);

/// One flag per lane: all bits set or none.
#[derive(Copy, Clone)]
struct M(__m256i);

// Every operation below is `#[inline(always)]`: inlined into the AVX2 entry
// point ([`render_row`]), the intrinsics they call inline too, and the
// whole path loop compiles to AVX2 code.

impl F {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Self(unsafe { _mm256_set1_ps(v) })
    }
    #[inline(always)]
    fn from_array(a: [f32; LANES]) -> Self {
        Self(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        let mut a = [0.0; LANES];
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }
    /// The comparison `P` (ordered, quiet: false where a lane is NaN, as
    /// Rust's operators are).
    #[inline(always)]
    fn cmp<const P: i32>(self, o: Self) -> M {
        M(unsafe { _mm256_castps_si256(_mm256_cmp_ps::<P>(self.0, o.0)) })
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M {
        self.cmp::<_CMP_GT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M {
        self.cmp::<_CMP_EQ_OQ>(o)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(unsafe { _mm256_sqrt_ps(self.0) })
    }
    /// `f32::max` against `o`, which is never NaN here: `maxps` returns
    /// its second operand where the first is NaN, as `f32::max` does.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(unsafe { _mm256_max_ps(self.0, o.0) })
    }
    /// `f32::min` against `o`, never NaN (see [`F::max`]).
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(unsafe { _mm256_min_ps(self.0, o.0) })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(unsafe { _mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff))) })
    }
    /// `f32::clamp`: NaN stays NaN.
    #[inline(always)]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        let v = sel(self.lt(F::splat(lo)), F::splat(lo), self);
        sel(v.gt(F::splat(hi)), F::splat(hi), v)
    }
    /// Whether the lane is finite (exponent bits not all set), as
    /// `pt_core::accum::is_finite` tests each component.
    #[inline(always)]
    fn finite(self) -> M {
        let e = U::splat(0x7f80_0000);
        !U(unsafe { _mm256_castps_si256(self.0) }).and(e).eq(e)
    }
}

/// `if m { a } else { b }`, lane by lane.
#[inline(always)]
fn sel(m: M, a: F, b: F) -> F {
    F(unsafe { _mm256_blendv_ps(b.0, a.0, _mm256_castsi256_ps(m.0)) })
}

#[inline(always)]
fn selu(m: M, a: U, b: U) -> U {
    U(unsafe { _mm256_blendv_epi8(b.0, a.0, m.0) })
}

macro_rules! float_ops {
    ($($tr:ident $f:ident $intr:ident),*) => {$(
        impl $tr for F {
            type Output = F;
            #[inline(always)]
            fn $f(self, o: F) -> F { F(unsafe { $intr(self.0, o.0) }) }
        }
        impl $tr<f32> for F {
            type Output = F;
            #[inline(always)]
            fn $f(self, o: f32) -> F { self.$f(F::splat(o)) }
        }
        impl $tr<F> for f32 {
            type Output = F;
            #[inline(always)]
            fn $f(self, o: F) -> F { F::splat(self).$f(o) }
        }
    )*};
}
float_ops!(Add add _mm256_add_ps, Sub sub _mm256_sub_ps, Mul mul _mm256_mul_ps, Div div _mm256_div_ps);

impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        F(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
    }
}

impl U {
    #[inline(always)]
    fn splat(v: u32) -> Self {
        Self(unsafe { _mm256_set1_epi32(v as i32) })
    }
    #[inline(always)]
    fn from_array(a: [u32; LANES]) -> Self {
        Self(unsafe { _mm256_loadu_si256(a.as_ptr().cast()) })
    }
    #[inline(always)]
    fn to_array(self) -> [u32; LANES] {
        let mut a = [0; LANES];
        unsafe { _mm256_storeu_si256(a.as_mut_ptr().cast(), self.0) };
        a
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self(unsafe { _mm256_add_epi32(self.0, o.0) })
    }
    /// Wrapping subtraction.
    #[inline(always)]
    fn wsub(self, o: Self) -> Self {
        Self(unsafe { _mm256_sub_epi32(self.0, o.0) })
    }
    #[inline(always)]
    fn wmul(self, o: Self) -> Self {
        Self(unsafe { _mm256_mullo_epi32(self.0, o.0) })
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        Self(unsafe { _mm256_xor_si256(self.0, o.0) })
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        Self(unsafe { _mm256_and_si256(self.0, o.0) })
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        Self(unsafe { _mm256_or_si256(self.0, o.0) })
    }
    #[inline(always)]
    fn shr<const K: i32>(self) -> Self {
        Self(unsafe { _mm256_srli_epi32::<K>(self.0) })
    }
    #[inline(always)]
    fn shl<const K: i32>(self) -> Self {
        Self(unsafe { _mm256_slli_epi32::<K>(self.0) })
    }
    /// Shift right by each lane's count (below 32).
    #[inline(always)]
    fn shr_var(self, k: Self) -> Self {
        Self(unsafe { _mm256_srlv_epi32(self.0, k.0) })
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M {
        M(unsafe { _mm256_cmpeq_epi32(self.0, o.0) })
    }
    /// Unsigned `self < o`: signed comparison with the top bits flipped.
    #[inline(always)]
    fn lt(self, o: Self) -> M {
        let flip = U::splat(0x8000_0000);
        M(unsafe { _mm256_cmpgt_epi32(o.xor(flip).0, self.xor(flip).0) })
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M {
        !self.lt(o)
    }
    /// `u32::reverse_bits`: each byte's bits reversed through a nibble
    /// table, then the bytes of each lane in reverse order.
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        unsafe {
            let table = _mm256_setr_epi8(
                0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf, 0x0, 0x8, 0x4, 0xc,
                0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf,
            );
            let nibble = _mm256_set1_epi8(0x0f);
            let lo = _mm256_and_si256(self.0, nibble);
            let hi = _mm256_and_si256(_mm256_srli_epi16::<4>(self.0), nibble);
            let bytes =
                _mm256_or_si256(_mm256_slli_epi16::<4>(_mm256_shuffle_epi8(table, lo)), _mm256_shuffle_epi8(table, hi));
            let order = _mm256_setr_epi8(
                3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13,
                12,
            );
            Self(_mm256_shuffle_epi8(bytes, order))
        }
    }
    #[inline(always)]
    fn rotate_left<const K: i32, const R: i32>(self) -> Self {
        self.shl::<K>().or(self.shr::<R>())
    }
    /// The lanes as floats; exact below 2^24, which every caller's are.
    #[inline(always)]
    fn to_f32(self) -> F {
        F(unsafe { _mm256_cvtepi32_ps(self.0) })
    }
}

impl M {
    #[inline(always)]
    fn splat(v: bool) -> Self {
        Self(unsafe { _mm256_set1_epi32(if v { -1 } else { 0 }) })
    }
    #[inline(always)]
    fn any(self) -> bool {
        unsafe { _mm256_testz_si256(self.0, self.0) == 0 }
    }
}

impl BitAnd for M {
    type Output = M;
    #[inline(always)]
    fn bitand(self, o: M) -> M {
        M(unsafe { _mm256_and_si256(self.0, o.0) })
    }
}

impl BitOr for M {
    type Output = M;
    #[inline(always)]
    fn bitor(self, o: M) -> M {
        M(unsafe { _mm256_or_si256(self.0, o.0) })
    }
}

impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        M(unsafe { _mm256_xor_si256(self.0, _mm256_set1_epi32(-1)) })
    }
}

/// A `Vec3` per lane, operations in glam's order.
#[derive(Copy, Clone)]
struct V3 {
    x: F,
    y: F,
    z: F,
}

impl V3 {
    #[inline(always)]
    fn splat(v: Vec3) -> Self {
        Self { x: F::splat(v.x), y: F::splat(v.y), z: F::splat(v.z) }
    }
    #[inline(always)]
    fn from_arrays(a: [[f32; LANES]; 3]) -> Self {
        Self { x: F::from_array(a[0]), y: F::from_array(a[1]), z: F::from_array(a[2]) }
    }
    #[inline(always)]
    fn dot(self, o: Self) -> F {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Self { x: self.y * o.z - o.y * self.z, y: self.z * o.x - o.z * self.x, z: self.x * o.y - o.x * self.y }
    }
    #[inline(always)]
    fn scale(self, k: F) -> Self {
        Self { x: self.x * k, y: self.y * k, z: self.z * k }
    }
    #[inline(always)]
    fn div(self, k: F) -> Self {
        Self { x: self.x / k, y: self.y / k, z: self.z / k }
    }
    #[inline(always)]
    fn mulv(self, o: Vec3) -> Self {
        Self { x: self.x * o.x, y: self.y * o.y, z: self.z * o.z }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self { x: self.x.abs(), y: self.y.abs(), z: self.z.abs() }
    }
    #[inline(always)]
    fn normalize(self) -> Self {
        self.scale(1.0 / self.dot(self).sqrt())
    }
    /// glam's `max_element`: `max(x, max(y, z))` with `a > b ? a : b`.
    #[inline(always)]
    fn max_element(self) -> F {
        let m = |a: F, b: F| sel(a.gt(b), a, b);
        m(self.x, m(self.y, self.z))
    }
    #[inline(always)]
    fn at(self, dir: Self, t: F) -> Self {
        self + dir.scale(t)
    }
    #[inline(always)]
    fn finite(self) -> M {
        self.x.finite() & self.y.finite() & self.z.finite()
    }
}

impl Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
}

impl Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}

impl Mul for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 { x: self.x * o.x, y: self.y * o.y, z: self.z * o.z }
    }
}

impl Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3 { x: -self.x, y: -self.y, z: -self.z }
    }
}

#[inline(always)]
fn selv(m: M, a: V3, b: V3) -> V3 {
    V3 { x: sel(m, a.x, b.x), y: sel(m, a.y, b.y), z: sel(m, a.z, b.z) }
}

/// `pt_core::rng::pcg_hash` on every lane.
#[inline(always)]
fn pcg_hash(v: U) -> U {
    let state = v.wmul(U::splat(747_796_405)).add(U::splat(2_891_336_453));
    pcg_output(state)
}

/// The output permutation of PCG RXS-M-XS.
#[inline(always)]
fn pcg_output(state: U) -> U {
    let word = state.shr_var(state.shr::<28>().add(U::splat(4))).xor(state).wmul(U::splat(277_803_737));
    word.shr::<22>().xor(word)
}

/// `pt_core::sampler::laine_karras_permutation` on every lane.
#[inline(always)]
fn laine_karras(x: U, seed: U) -> U {
    let mut x = x.add(seed);
    x = x.xor(x.wmul(U::splat(0x6c50_b47c)));
    x = x.xor(x.wmul(U::splat(0xb82f_1e52)));
    x = x.xor(x.wmul(U::splat(0xc7af_e638)));
    x.xor(x.wmul(U::splat(0x8d22_f6e6)))
}

/// `pt_core::sampler::sobol_dim1` on every lane.
#[inline(always)]
fn sobol_dim1(r: U) -> U {
    let mut y = r;
    y = y.xor(y.shl::<1>().and(U::splat(0xaaaa_aaaa)));
    y = y.xor(y.shl::<2>().and(U::splat(0xcccc_cccc)));
    y = y.xor(y.shl::<4>().and(U::splat(0xf0f0_f0f0)));
    y = y.xor(y.shl::<8>().and(U::splat(0xff00_ff00)));
    y.xor(y.shl::<16>().and(U::splat(0xffff_0000)))
}

/// `to_unit` of the samplers: the top 24 bits as a fraction.
#[inline(always)]
fn to_unit(x: U) -> F {
    x.shr::<8>().to_f32() * (1.0 / 16_777_216.0)
}

/// `Rng::next_u32` on the lanes in `m`; the others' states stay.
#[inline(always)]
fn pcg_next(state: &mut U, m: M) -> U {
    let next = state.wmul(U::splat(747_796_405)).add(U::splat(2_891_336_453));
    *state = selu(m, next, *state);
    pcg_output(next)
}

/// `pt_core::rng::pcg4d` on every lane.
#[inline(always)]
fn pcg4d(v: [U; 4]) -> [U; 4] {
    let mut v = v.map(|a| a.wmul(U::splat(1_664_525)).add(U::splat(1_013_904_223)));
    let round = |v: &mut [U; 4]| {
        v[0] = v[0].add(v[1].wmul(v[3]));
        v[1] = v[1].add(v[2].wmul(v[0]));
        v[2] = v[2].add(v[0].wmul(v[1]));
        v[3] = v[3].add(v[1].wmul(v[2]));
    };
    round(&mut v);
    v = v.map(|a| a.xor(a.shr::<16>()));
    round(&mut v);
    v
}

/// The sampler of [`pt_core::sampler`] for eight lanes: `SobolSampler<DRAWS>`
/// when `PCG` is false, `Rng` (every draw from the PCG stream) when true.
#[derive(Copy, Clone)]
struct Sampler<const DRAWS: u32, const PCG: bool> {
    index_reversed: U,
    seed: U,
    pair: U,
    /// `joint_draws` of the frame's flags: the same on every lane.
    joint: u32,
    tail: U,
}

impl<const DRAWS: u32, const PCG: bool> Sampler<DRAWS, PCG> {
    /// `Sampler::for_pixel`: `SobolPixel`'s seed (Sobol) or the seed's
    /// hash (PCG, whose stream also takes the pixel's coordinates).
    /// `SobolPixel`'s joint count, the same on every lane, stays in the
    /// sampler (`joint`): one scalar for the eight lanes, which costs no
    /// vector work, where lavapipe holds every value of the scalar
    /// sampler's state eight wide.
    #[inline(always)]
    fn for_pixel(x: U, y: U, params: &FrameParams) -> U {
        let seed_hash = U::splat(pt_core::rng::pcg_hash(params.seed));
        if PCG { seed_hash } else { pcg_hash(pcg_hash(x.xor(pcg_hash(y.xor(seed_hash))))) }
    }

    /// `Sampler::for_camera_sample` of sample `s` in each lane.
    #[inline(always)]
    fn for_camera_sample(pixel: U, x: U, y: U, s: U, params: &FrameParams) -> Self {
        if PCG {
            // Rng::with_seed_hash: pcg4d of (x, y, frame, s ^ seed hash).
            let h = pcg4d([x, y, U::splat(params.frame), s.xor(pixel)]);
            let tail = h[0].xor(h[1].rotate_left::<16, 16>()).xor(h[2]).xor(h[3].rotate_left::<8, 24>());
            let zero = U::splat(0);
            Self { index_reversed: zero, seed: zero, pair: zero, joint: 0, tail }
        } else {
            let index = s.add(U::splat(params.sample_offset));
            let tail =
                if DRAWS == u32::MAX { U::splat(0) } else { pcg_hash(pixel.xor(index.wmul(U::splat(0x9e37_79b9)))) };
            let joint = joint_draws(params.flags);
            Self { index_reversed: index.reverse_bits(), seed: pixel, pair: U::splat(0), joint, tail }
        }
    }

    /// Whether each lane's next draw is a Sobol point.
    #[inline(always)]
    fn sobol(&self) -> M {
        if PCG { M::splat(false) } else { self.pair.lt(U::splat(DRAWS)) }
    }

    /// `next_seed` on the lanes in `m`: the pair count advances there.
    #[inline(always)]
    fn next_seed(&mut self, m: M) -> U {
        let pair = self.pair.add(U::splat(1));
        self.pair = selu(m, pair, self.pair);
        pcg_hash(self.seed.xor(pair.wmul(U::splat(0x9e37_79b9))))
    }

    /// `SobolSampler::point_index_reversed` on every lane, with
    /// `pt_core::sampler::joint_index_reversed` written out for the lanes.
    #[inline(always)]
    fn point_index_reversed(&self, seed: U) -> U {
        let (joint, i) = (self.joint, self.index_reversed);
        // `pt_core::sampler::joint_transform` on every lane.
        let before = self.pair.lt(U::splat(joint));
        let g = selu(before, self.pair.add(U::splat(joint.wrapping_sub(1))), self.pair.wsub(U::splat(joint)));
        let g = selu(self.pair.lt(U::splat(2 * joint)), g, U::splat(JOINT_TRANSFORMS));
        let t1 = i.xor(i.shl::<2>()).xor(i.shl::<6>()).xor(i.shl::<7>());
        let t2 = i.xor(i.shl::<1>()).xor(i.shl::<4>()).xor(i.shl::<7>());
        let t3 = i.xor(i.shl::<1>()).xor(i.shl::<5>()).xor(i.shl::<8>());
        let t4 = i.xor(i.shl::<3>()).xor(i.shl::<7>());
        let at = |n: u32| g.eq(U::splat(n));
        let transformed = selu(at(0), i, selu(at(1), t1, selu(at(2), t2, selu(at(3), t3, t4))));
        if all_draws_joint(DRAWS, joint) {
            transformed
        } else {
            selu(g.lt(U::splat(JOINT_TRANSFORMS)), transformed, laine_karras(i, seed))
        }
    }

    /// `next_1d` on the lanes in `m`; the others draw nothing.
    #[inline(always)]
    fn next_1d(&mut self, m: M) -> F {
        let sobol = self.sobol();
        let (ms, mt) = (m & sobol, m & !sobol);
        let mut out = F::splat(0.0);
        if ms.any() {
            let seed = self.next_seed(ms);
            let v = self.point_index_reversed(seed).xor(seed.xor(U::splat(0xa511_e9b3)));
            out = sel(ms, to_unit(v), out);
        }
        if mt.any() {
            out = sel(mt, to_unit(pcg_next(&mut self.tail, mt)), out);
        }
        out
    }

    /// `next_2d` on the lanes in `m`; the others draw nothing.
    #[inline(always)]
    fn next_2d(&mut self, m: M) -> (F, F) {
        let sobol = self.sobol();
        let (ms, mt) = (m & sobol, m & !sobol);
        let (mut a, mut b) = (F::splat(0.0), F::splat(0.0));
        if ms.any() {
            let seed = self.next_seed(ms);
            let r = self.point_index_reversed(seed);
            // `pt_core::sampler::shifted_sobol_2d` with `value_seed_0` and
            // `value_seed_1`.
            let x = r.xor(seed.xor(U::splat(0xa511_e9b3)));
            let y_seed = seed.wmul(U::splat(0x2c1b_3c6d)).xor(U::splat(0x297a_2d39));
            let y = sobol_dim1(r).xor(y_seed);
            a = sel(ms, to_unit(x), a);
            b = sel(ms, to_unit(y), b);
        }
        if mt.any() {
            let u = to_unit(pcg_next(&mut self.tail, mt));
            let v = to_unit(pcg_next(&mut self.tail, mt));
            a = sel(mt, u, a);
            b = sel(mt, v, b);
        }
        (a, b)
    }

    #[inline(always)]
    fn select(m: M, a: Self, b: Self) -> Self {
        Self {
            index_reversed: selu(m, a.index_reversed, b.index_reversed),
            seed: selu(m, a.seed, b.seed),
            pair: selu(m, a.pair, b.pair),
            joint: a.joint,
            tail: selu(m, a.tail, b.tail),
        }
    }
}

/// What a lane's ray hit: [`pt_core::query::HitKind`] as a number.
const NOTHING: u32 = 0;
const WALL: u32 = 1;
const SPHERE: u32 = 2;
const LIGHT: u32 = 3;

/// `NO_WALL` of [`pt_core::query`].
const NO_WALL: u32 = u32::MAX;

/// The frame's uniform inputs: parameters, flags and the scene.
struct Frame<'a> {
    params: &'a FrameParams,
    geometry: &'a Geometry,
    walls: u32,
    spheres: u32,
    /// Each wall's `Wall::normal_axis`: where it has one, its test is
    /// `intersect_wall_on_axis`, the same `t` in fewer operations.
    wall_axes: [Option<u32>; MAX_WALLS],
    /// The walls that can block a shadow ray (`ShadowWalls`), in order.
    shadow_walls: [u32; MAX_WALLS],
    shadow_wall_count: usize,
    nee: bool,
    /// Connections through lit wall points (`FLAG_CONNECT`, with NEE, where
    /// no wall shadows the light).
    connect: bool,
    projected: bool,
    /// NEE's control variate (`pt_core::integrator::nee_control`).
    control: bool,
    mis: bool,
    glow: bool,
    /// The glow lobe's probability where it is on.
    glow_probability: f32,
    luminance_rr: bool,
    black_background: bool,
}

impl<'a> Frame<'a> {
    fn new(params: &'a FrameParams, geometry: &'a Geometry) -> Self {
        let (walls, spheres) = pt_core::query::counts(params);
        // The scalar loop's mask, as a list the shadow test runs through.
        let mask = ShadowWalls::new(params, geometry);
        let glow = glow_probability(params.flags);
        let mut shadow_walls = [0; MAX_WALLS];
        let mut shadow_wall_count = 0;
        for i in (0..walls).filter(|&i| mask.contains(i)) {
            shadow_walls[shadow_wall_count] = i;
            shadow_wall_count += 1;
        }
        Self {
            params,
            geometry,
            walls,
            spheres,
            wall_axes: geometry.walls.map(|w| w.normal_axis()),
            shadow_walls,
            shadow_wall_count,
            nee: params.flags & FLAG_NEE != 0,
            connect: pt_core::integrator::connects(params.flags) && mask.is_empty(),
            projected: params.flags & FLAG_NEE_PROJECTED != 0,
            control: pt_core::integrator::nee_control(params.flags),
            mis: params.flags & FLAG_MIS != 0,
            glow: glow > 0.0,
            glow_probability: glow,
            luminance_rr: params.flags & FLAG_RR_LUMINANCE != 0,
            black_background: params.background.max_element() == 0.0,
        }
    }
}

/// `intersect_wall` in (0, `t_max`) per lane: the hit's `t`, or `t_max`.
#[inline(always)]
fn intersect_wall(w: &pt_core::Wall, o: V3, d: V3, t_max: F) -> F {
    let n = V3::splat(w.normal);
    let corner = V3::splat(w.corner);
    let denom = n.dot(d);
    let t = n.dot(corner - o) / denom;
    let q = o.at(d, t) - corner;
    let a = q.dot(V3::splat(w.coord_u));
    let b = q.dot(V3::splat(w.coord_v));
    let (lo, hi) = (F::splat(-EDGE_SLACK), F::splat(1.0 + EDGE_SLACK));
    let ok = !denom.eq(F::splat(0.0)) & t.gt(F::splat(0.0)) & t.lt(t_max) & a.ge(lo) & a.le(hi) & b.ge(lo) & b.le(hi);
    sel(ok, t, t_max)
}

/// `pt_core::wall::intersect_wall_on_axis` in (0, `t_max`) per lane, for a
/// wall whose normal lies on axis `k`: what [`intersect_wall`] returns.
#[inline(always)]
fn intersect_wall_on_axis(w: &pt_core::Wall, k: u32, o: V3, d: V3, t_max: F) -> F {
    let axis = |v: V3, k: u32| match k {
        0 => v.x,
        1 => v.y,
        _ => v.z,
    };
    let (i, j) = match k {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let (corner, u, v) = (w.corner.to_array(), w.coord_u.to_array(), w.coord_v.to_array());
    let denom = axis(d, k);
    let t = (F::splat(corner[k as usize]) - axis(o, k)) / denom;
    let qi = (axis(o, i) + axis(d, i) * t) - F::splat(corner[i as usize]);
    let qj = (axis(o, j) + axis(d, j) * t) - F::splat(corner[j as usize]);
    let a = qi * F::splat(u[i as usize]) + qj * F::splat(u[j as usize]);
    let b = qi * F::splat(v[i as usize]) + qj * F::splat(v[j as usize]);
    let (lo, hi) = (F::splat(-EDGE_SLACK), F::splat(1.0 + EDGE_SLACK));
    let ok = !denom.eq(F::splat(0.0)) & t.gt(F::splat(0.0)) & t.lt(t_max) & a.ge(lo) & a.le(hi) & b.ge(lo) & b.le(hi);
    sel(ok, t, t_max)
}

/// Wall `i` of the frame met in (0, `t_max`) per lane, by the test on its
/// axis where it has one.
#[inline(always)]
fn wall_t(frame: &Frame, i: u32, o: V3, d: V3, t_max: F) -> F {
    let w = &frame.geometry.walls[i as usize];
    match frame.wall_axes[i as usize] {
        Some(k) => intersect_wall_on_axis(w, k, o, d, t_max),
        None => intersect_wall(w, o, d, t_max),
    }
}

/// `intersect_sphere` in (0, `t_max`) per lane.
#[inline(always)]
fn intersect_sphere(center: Vec3, radius: f32, o: V3, d: V3, t_max: F) -> F {
    let f = o - V3::splat(center);
    let b = -f.dot(d);
    let perp = f + d.scale(b);
    let r2 = radius * radius;
    let disc = r2 - perp.dot(perp);
    let c = f.dot(f) - r2;
    let sign_b = sel(b.ge(F::splat(0.0)), F::splat(1.0), F::splat(-1.0));
    let q = b + sign_b * disc.sqrt();
    let zero = q.eq(F::splat(0.0));
    let other = c / q;
    let other_first = other.lt(q);
    let t0 = sel(zero, F::splat(0.0), sel(other_first, other, q));
    let t1 = sel(zero, F::splat(0.0), sel(other_first, q, other));
    let zero_t = F::splat(0.0);
    let in0 = t0.gt(zero_t) & t0.lt(t_max);
    let in1 = t1.gt(zero_t) & t1.lt(t_max);
    let t = sel(in0, t0, sel(in1, t1, t_max));
    sel(disc.lt(zero_t), t_max, t)
}

/// `sphere_meets_segment` per lane.
#[inline(always)]
fn sphere_meets_segment(center: Vec3, radius: f32, o: V3, d: V3, t_max: F) -> M {
    let f = o - V3::splat(center);
    let foot = -f.dot(d);
    let t = sel(foot.gt(F::splat(0.0)), foot, F::splat(0.0));
    let t = sel(t.lt(t_max), t, t_max);
    let nearest = f + d.scale(t);
    let r2 = F::splat(radius * radius);
    let c = f.dot(f) - r2;
    let both_inside = c.lt(F::splat(0.0)) & (c + t_max * (t_max - F::splat(2.0) * foot)).lt(F::splat(0.0));
    nearest.dot(nearest).lt(r2) & !both_inside
}

/// `power_heuristic` per lane.
#[inline(always)]
fn power_heuristic(f: F, g: F) -> F {
    let (f2, g2) = (f * f, g * g);
    let s = f2 + g2;
    sel(s.gt(F::splat(0.0)), f2 / s, F::splat(0.0))
}

/// `about_axis` per lane: `cos` and `sin` of the polar angle, `u` the turn.
#[inline(always)]
fn about_axis(axis: V3, cos_theta: F, sin_theta: F, u: F) -> V3 {
    let (sin_phi, cos_phi) = sin_cos_turn(u);
    // orthonormal_basis (Duff et al. 2017).
    let n = axis;
    let sign = sel(n.z.ge(F::splat(0.0)), F::splat(1.0), F::splat(-1.0));
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = V3 { x: 1.0 + sign * n.x * n.x * a, y: sign * b, z: -sign * n.x };
    let bb = V3 { x: b, y: sign + n.y * n.y * a, z: -n.y };
    t.scale(sin_theta * cos_phi) + bb.scale(sin_theta * sin_phi) + axis.scale(cos_theta)
}

/// `pt_core::sampling::sin_cos_turn` on every lane, in the same operations.
#[inline(always)]
fn sin_cos_turn(u: F) -> (F, F) {
    let t = 4.0 * u;
    let q = F(unsafe { _mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(t.0) });
    let (s, c) = sin_cos_taylor((t - q) * (PI / 2.0));
    let q = U(unsafe { _mm256_cvtps_epi32(q.0) });
    let odd = q.and(U::splat(1)).eq(U::splat(1));
    // Quarter turns 2 and 3 negate the sine, 1 and 2 the cosine.
    let sign = |bit: U| F(unsafe { _mm256_castsi256_ps(bit.and(U::splat(2)).shl::<30>().0) });
    let flip = |v: F, s: F| F(unsafe { _mm256_xor_ps(v.0, s.0) });
    let sin = flip(sel(odd, c, s), sign(q));
    let cos = flip(sel(odd, s, c), sign(q.add(U::splat(1))));
    (sin, cos)
}

/// The light's cone from each lane's point ([`pt_core::light::LightCone`]).
#[derive(Copy, Clone)]
struct Cone {
    axis: V3,
    dist: F,
    sin2_max: F,
    one_minus_cos_max: F,
    empty: M,
}

#[inline(always)]
fn light_cone(frame: &Frame, p: V3) -> Cone {
    let light = &frame.params.light;
    let to_center = V3::splat(light.center) - p;
    let d2 = to_center.dot(to_center);
    let r2 = light.radius * light.radius;
    let seen = d2.gt(F::splat(r2));
    let dist = d2.sqrt();
    let sin2_max = r2 / d2;
    let cos_max = (1.0 - sin2_max).max(F::splat(0.0)).sqrt();
    let omc = sin2_max / (1.0 + cos_max);
    let zero = F::splat(0.0);
    Cone {
        axis: selv(seen, to_center.div(dist), V3::splat(Vec3::Z)),
        dist: sel(seen, dist, zero),
        sin2_max: sel(seen, sin2_max, zero),
        one_minus_cos_max: sel(seen, omc, zero),
        // is_empty: one_minus_cos_max <= 0.
        empty: sel(seen, omc, zero).le(zero),
    }
}

impl Cone {
    #[inline(always)]
    fn pdf(&self) -> F {
        sel(self.empty, F::splat(0.0), 1.0 / (2.0 * PI * self.one_minus_cos_max))
    }

    #[inline(always)]
    fn sample(&self, u1: F, u2: F) -> (V3, F) {
        let one_minus_cos = u1 * self.one_minus_cos_max;
        let cos_theta = 1.0 - one_minus_cos;
        let sin2 = one_minus_cos * (2.0 - one_minus_cos);
        let sin_theta = sin2.max(F::splat(0.0)).sqrt();
        let dir = about_axis(self.axis, cos_theta, sin_theta, u2);
        (dir, self.near_distance(one_minus_cos))
    }

    #[inline(always)]
    fn near_distance(&self, one_minus_cos: F) -> F {
        let sin2 = one_minus_cos * (2.0 - one_minus_cos);
        self.dist * ((1.0 - one_minus_cos) - (self.sin2_max - sin2).max(F::splat(0.0)).sqrt())
    }

    #[inline(always)]
    fn above_horizon(&self, n: V3) -> M {
        let c = n.dot(self.axis);
        !self.empty & c.gt(F::splat(0.0)) & (c * c).ge(self.sin2_max)
    }

    #[inline(always)]
    fn control_weight(&self, n: V3) -> F {
        let t = (F::splat(0.5) + F::splat(0.5) * n.dot(self.axis) / self.sin2_max.sqrt()).clamp(0.0, 1.0);
        t * t * (F::splat(3.0) - F::splat(2.0) * t)
    }

    #[inline(always)]
    fn projected_over_pi(&self, n: V3) -> F {
        self.sin2_max * n.dot(self.axis)
    }

    #[inline(always)]
    fn sample_projected(&self, n: V3, u1: F, u2: F) -> (V3, F) {
        let c = n.dot(self.axis);
        let toward = self.axis - n.scale(c);
        let s2 = toward.dot(toward);
        let tilted = s2.gt(F::splat(1e-12));
        let t1 = toward.div(s2.sqrt());
        let t2 = n.cross(t1);
        // orthonormal_basis(n) where the light is at the zenith.
        let sign = sel(n.z.ge(F::splat(0.0)), F::splat(1.0), F::splat(-1.0));
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let b1 = V3 { x: 1.0 + sign * n.x * n.x * a, y: sign * b, z: -sign * n.x };
        let b2 = V3 { x: b, y: sign + n.y * n.y * a, z: -n.y };
        let (t1, t2) = (selv(tilted, t1, b1), selv(tilted, t2, b2));
        let sin_half = self.sin2_max.sqrt();
        let cos_half = 1.0 - self.one_minus_cos_max;
        let r = u1.sqrt();
        let (sin_phi, cos_phi) = sin_cos_turn(u2);
        let x = cos_half * s2.sqrt() + sin_half * c * (r * cos_phi);
        let y = sin_half * (r * sin_phi);
        let h = (1.0 - x * x - y * y).max(F::splat(0.0)).sqrt();
        let dir = t1.scale(x) + t2.scale(y) + n.scale(h);
        let chord = dir - self.axis;
        (dir, self.near_distance(0.5 * chord.dot(chord)))
    }
}

/// [`pt_core::bsdf::Scatter`] per lane: the cosine lobe about `n` mixed
/// with the glow lobe where `glow_probability` is not 0.
struct Scatter {
    n: V3,
    axis: V3,
    scale: F,
    reach: F,
    log_ratio: F,
    glow_probability: F,
}

impl Scatter {
    #[inline(always)]
    fn new(n: V3, cone: &Cone, glow: M, probability: f32) -> Self {
        let glow = glow & !cone.empty;
        let (mut scale, mut reach, mut log_ratio) = (F::splat(1.0), F::splat(1.0), F::splat(1.0));
        let mut axis = V3::splat(Vec3::Z);
        let mut glow_probability = F::splat(0.0);
        if glow.any() {
            let s = cone.one_minus_cos_max.max(F::splat(GLOW_MIN_SCALE));
            let r = s + GLOW_REACH;
            // ln_poly's operations: its exponent and mantissa split lane by
            // lane, its polynomial on the vectors (lanes without the lobe
            // compute it too, and drop it below).
            let ratio = (r / s).to_array();
            let split: [(f32, f32); 8] = from_fn(|i| ln_split(ratio[i]));
            let l = ln_reduced(F::from_array(from_fn(|i| split[i].0)), F::from_array(from_fn(|i| split[i].1)));
            scale = sel(glow, s, scale);
            reach = sel(glow, r, reach);
            log_ratio = sel(glow, l, log_ratio);
            axis = selv(glow, cone.axis, axis);
            // below_horizon: reach < 1 and n . axis < -sqrt(reach (2 - reach)).
            let below = reach.lt(F::splat(1.0)) & n.dot(axis).lt(-(reach * (2.0 - reach)).sqrt());
            glow_probability = sel(glow & !below, F::splat(probability), glow_probability);
        }
        Self { n, axis, scale, reach, log_ratio, glow_probability }
    }

    #[inline(always)]
    fn sample(&self, u1: F, u2: F) -> V3 {
        let p = self.glow_probability;
        let pick = u1.lt(p);
        let mut cos_theta = (1.0 - (u1 - p) / (1.0 - p)).sqrt();
        let mut sin_theta = ((u1 - p) / (1.0 - p)).sqrt();
        let mut axis = self.n;
        if pick.any() {
            // GlowLobe::polar(u1 / p), with exp_poly's operations as ln's
            // above (lanes that did not pick the lobe drop theirs below).
            let arg = u1 / p * self.log_ratio;
            let args = arg.to_array();
            let split: [(f32, f32); 8] = from_fn(|i| exp_split(args[i]));
            let e = exp_reduced(arg, F::from_array(from_fn(|i| split[i].0)), F::from_array(from_fn(|i| split[i].1)));
            let x = (self.scale * e).min(self.reach);
            cos_theta = sel(pick, 1.0 - x, cos_theta);
            sin_theta = sel(pick, (x * (2.0 - x)).max(F::splat(0.0)).sqrt(), sin_theta);
            axis = selv(pick, self.axis, axis);
        }
        about_axis(axis, cos_theta, sin_theta, u2)
    }

    #[inline(always)]
    fn pdf(&self, dir: V3) -> F {
        let p = self.glow_probability;
        let cosine = self.n.dot(dir).max(F::splat(0.0)) * (1.0 / PI);
        let chord = dir - self.axis;
        let x = 0.5 * chord.dot(chord);
        let inside = x.le(self.reach) & x.ge(self.scale);
        let glow = sel(inside, 1.0 / (2.0 * PI * self.log_ratio * x), F::splat(0.0));
        let glow = sel(p.gt(F::splat(0.0)), glow, F::splat(0.0));
        (1.0 - p) * cosine + p * glow
    }
}

/// [`LightEdge`] per lane: each lane's pixel's ellipse, computed by the
/// scalar code, so the lanes add the scalar loop's terms bit for bit.
struct Edge {
    a00: F,
    a01: F,
    a11: F,
    y0x: F,
    y0y: F,
    share: F,
    radiance: V3,
}

impl Edge {
    /// The edges of pixels `x0`, `x0 + 1`, ... of row `y`
    /// ([`light_edge`]).
    #[inline(always)]
    fn of_pixels(x0: u32, y: u32, params: &FrameParams) -> Self {
        let e: [LightEdge; LANES] = from_fn(|i| light_edge(x0 + i as u32, y, params));
        let lanes = |f: fn(&LightEdge) -> f32| F::from_array(from_fn(|i| f(&e[i])));
        Self {
            a00: lanes(|e| e.a00),
            a01: lanes(|e| e.a01),
            a11: lanes(|e| e.a11),
            y0x: lanes(|e| e.y0.x),
            y0y: lanes(|e| e.y0.y),
            share: lanes(|e| e.share),
            radiance: V3 { x: lanes(|e| e.radiance.x), y: lanes(|e| e.radiance.y), z: lanes(|e| e.radiance.z) },
        }
    }

    /// `LightEdge::term` for the jitters (`ux`, `uy`).
    #[inline(always)]
    fn term(&self, ux: F, uy: F) -> V3 {
        let (zx, zy) = (ux - 0.5, uy - 0.5);
        let yx = self.a00 * zx + self.a01 * zy + self.y0x;
        let yy = self.a11 * zy + self.y0y;
        let inside = sel((yx * yx + yy * yy).le(F::splat(1.0)), F::splat(1.0), F::splat(0.0));
        self.radiance.scale(self.share - inside)
    }
}

/// Eight paths in flight: [`pt_core::integrator::Path`] per lane.
#[derive(Copy, Clone)]
struct Paths<const DRAWS: u32, const PCG: bool> {
    origin: V3,
    dir: V3,
    radiance: V3,
    throughput: V3,
    bounces: U,
    skip_wall: U,
    bsdf_pdf: F,
    nee_pdf: F,
    scatter_pdf: F,
    direct_weight: F,
    sampler: Sampler<DRAWS, PCG>,
}

impl<const DRAWS: u32, const PCG: bool> Paths<DRAWS, PCG> {
    /// `Path::camera` for sample `s` of each lane's pixel.
    #[inline(always)]
    fn camera(x: U, y: U, pixel: U, s: U, edge: &Edge, params: &FrameParams) -> Self {
        let mut sampler = Sampler::for_camera_sample(pixel, x, y, s, params);
        let (ux, uy) = sampler.next_2d(M::splat(true));
        let radiance = edge.term(ux, uy);
        let cam = &params.camera;
        let fx = x.to_f32() + ux;
        let fy = y.to_f32() + uy;
        let sx = 2.0 * fx / params.width as f32 - 1.0;
        let sy = 1.0 - 2.0 * fy / params.height as f32;
        let dir = (V3::splat(cam.forward) + V3::splat(cam.right).scale(sx) + V3::splat(cam.up).scale(sy)).normalize();
        Self {
            origin: V3::splat(cam.position),
            dir,
            radiance,
            throughput: V3::splat(Vec3::ONE),
            bounces: U::splat(0),
            skip_wall: U::splat(NO_WALL),
            bsdf_pdf: F::splat(0.0),
            nee_pdf: F::splat(0.0),
            scatter_pdf: F::splat(0.0),
            direct_weight: F::splat(1.0),
            sampler,
        }
    }

    #[inline(always)]
    fn select(m: M, a: Self, b: Self) -> Self {
        Self {
            origin: selv(m, a.origin, b.origin),
            dir: selv(m, a.dir, b.dir),
            radiance: selv(m, a.radiance, b.radiance),
            throughput: selv(m, a.throughput, b.throughput),
            bounces: selu(m, a.bounces, b.bounces),
            skip_wall: selu(m, a.skip_wall, b.skip_wall),
            bsdf_pdf: sel(m, a.bsdf_pdf, b.bsdf_pdf),
            nee_pdf: sel(m, a.nee_pdf, b.nee_pdf),
            scatter_pdf: sel(m, a.scatter_pdf, b.scatter_pdf),
            direct_weight: sel(m, a.direct_weight, b.direct_weight),
            sampler: Sampler::select(m, a.sampler, b.sampler),
        }
    }

    /// `Path::step` on the lanes in `act`: returns the lanes whose path
    /// ended.
    #[inline(always)]
    fn step(&mut self, frame: &Frame, act: M) -> M {
        let params = frame.params;
        let geometry = frame.geometry;
        let light = &params.light;
        let (o, d) = (self.origin, self.dir);

        // closest_hit: walls, spheres, then the light, strictly nearer.
        let (mut t, mut index, on_wall) = nearest_wall(frame, o, d, self.skip_wall);
        let mut kind = selu(on_wall, U::splat(WALL), U::splat(NOTHING));
        for i in 0..frame.spheres {
            let s = &geometry.spheres[i as usize];
            let ti = intersect_sphere(s.center, s.radius, o, d, t);
            let nearer = ti.lt(t);
            t = sel(nearer, ti, t);
            kind = selu(nearer, U::splat(SPHERE), kind);
            index = selu(nearer, U::splat(i), index);
        }
        let tl = intersect_sphere(light.center, light.radius, o, d, t);
        let nearer = tl.lt(t);
        t = sel(nearer, tl, t);
        kind = selu(nearer, U::splat(LIGHT), kind);

        let is = |k: u32| kind.eq(U::splat(k));
        let nothing = act & is(NOTHING);
        let lit = act & is(LIGHT);
        let background = self.throughput.mulv(params.background);
        self.radiance = selv(nothing, self.radiance + background, self.radiance);
        if lit.any() {
            let front = d.dot(o.at(d, t) - V3::splat(light.center)).lt(F::splat(0.0));
            let direct = self.bounces.eq(U::splat(0)) | M::splat(!frame.nee) | self.nee_pdf.eq(F::splat(0.0));
            let weight = if frame.mis { power_heuristic(self.bsdf_pdf, self.nee_pdf) } else { F::splat(0.0) };
            let weight = sel(direct, F::splat(1.0), weight);
            let add = self.throughput.mulv(light.radiance).scale(weight * self.direct_weight);
            self.radiance = selv(lit & front, self.radiance + add, self.radiance);
        }
        let object = act & !nothing & !lit;
        let deep = self.bounces.ge(U::splat(params.max_bounces));
        let mut ended = nothing | lit | (object & deep);
        let mut live = object & !deep;
        if !live.any() {
            return ended;
        }

        // surface(): walls and spheres each worked out for every lane, then
        // picked by what the lane hit.
        let hit_wall = is(WALL);
        let p_ray = o.at(d, t);
        let wall_magnitude = o.abs() + d.scale(t).abs();
        let mut normal = [[0.0; LANES]; 3];
        let mut albedo = [[0.0; LANES]; 3];
        let mut center = [[0.0; LANES]; 3];
        let mut radius = [0.0; LANES];
        let (index_lanes, live_lanes, wall_lanes) = (index.to_array(), U(live.0).to_array(), U(hit_wall.0).to_array());
        for k in 0..LANES {
            if live_lanes[k] == 0 {
                continue;
            }
            let i = index_lanes[k] as usize;
            let (n, a) = if wall_lanes[k] != 0 {
                let w = &geometry.walls[i.min(MAX_WALLS - 1)];
                (w.normal, w.albedo)
            } else {
                let s = &geometry.spheres[i.min(MAX_SPHERES - 1)];
                (center[0][k], center[1][k], center[2][k]) = (s.center.x, s.center.y, s.center.z);
                radius[k] = s.radius;
                (Vec3::ZERO, s.albedo)
            };
            (normal[0][k], normal[1][k], normal[2][k]) = (n.x, n.y, n.z);
            (albedo[0][k], albedo[1][k], albedo[2][k]) = (a.x, a.y, a.z);
        }
        let (normal, albedo, center) = (V3::from_arrays(normal), V3::from_arrays(albedo), V3::from_arrays(center));
        let radius = F::from_array(radius);
        // sphere_hit_point: the point re-projected onto the sphere.
        let to_p = p_ray - center;
        let len = to_p.dot(to_p).sqrt();
        let sphere_normal = selv(len.gt(F::splat(0.0)), to_p.div(len), V3::splat(Vec3::Y));
        let sphere_point = center + sphere_normal.scale(radius);
        let sphere_magnitude = center.abs() + V3 { x: radius, y: radius, z: radius };
        let p = selv(hit_wall, p_ray, sphere_point);
        let normal = selv(hit_wall, normal, sphere_normal);
        let magnitude = selv(hit_wall, wall_magnitude, sphere_magnitude);
        let wall_index = selu(hit_wall, index, U::splat(NO_WALL));

        let n = selv(normal.dot(d).lt(F::splat(0.0)), normal, -normal);
        // offset_origin.
        let err = magnitude.scale(F::splat(HIT_ERROR_EPS));
        let origin = p + n.scale(n.abs().dot(err));
        if frame.connect {
            // The share of this vertex's direct light a connection from the
            // vertex before leaves to this path (`Path::step`).
            let to_light = V3::splat(light.center) - p;
            let d2 = to_light.dot(to_light);
            let cos_light = n.dot(to_light);
            let cos_in = -n.dot(d);
            let bsdf_area = self.scatter_pdf * cos_in / (t * t);
            let weight = power_heuristic(bsdf_area, connection_pdf(cos_light / d2.sqrt(), d2));
            let applies = !self.bounces.eq(U::splat(0)) & hit_wall & cos_light.gt(F::splat(0.0));
            self.direct_weight = sel(applies, weight, F::splat(1.0));
        }

        let cone = light_cone(frame, p);
        let cone_pdf = cone.pdf();
        let last = if frame.nee {
            !cone.empty & self.bounces.add(U::splat(1)).ge(U::splat(params.max_bounces))
        } else {
            M::splat(false)
        };
        let scatter = Scatter::new(n, &cone, M::splat(frame.glow) & !last & live, frame.glow_probability);
        let projected = if frame.nee && frame.projected { cone.above_horizon(n) } else { M::splat(false) };
        let control = if frame.control { !cone.empty } else { M::splat(false) };
        if frame.nee {
            let m = live & !cone.empty;
            let (u1, u2) = self.sampler.next_2d(m);
            // Each sampler only where a lane takes it: where the light is
            // above every lane's horizon the uniform one is not run.
            let projected = projected & m;
            let (mut dir, mut dist) = (V3::splat(Vec3::ZERO), F::splat(0.0));
            if (m & !projected).any() {
                (dir, dist) = cone.sample(u1, u2);
            }
            if projected.any() {
                let (p_dir, p_dist) = cone.sample_projected(n, u1, u2);
                (dir, dist) = (selv(projected, p_dir, dir), sel(projected, p_dist, dist));
            }
            let cos = n.dot(dir);
            // The control variate's lanes count a blocked ray too.
            let control = control & m;
            let shoot = m & (cos.gt(F::splat(0.0)) | control);
            if shoot.any() {
                let blocked = occluded(frame, origin, dir, wall_index, dist, shoot);
                let bsdf = cos * (1.0 / PI);
                let weight = if frame.mis {
                    sel(last, F::splat(1.0), power_heuristic(cone_pdf, scatter.pdf(dir)))
                } else {
                    F::splat(1.0)
                };
                let whole = cone.projected_over_pi(n);
                let value = sel(projected, whole, bsdf * weight / cone_pdf);
                let kept = sel(blocked | cos.le(F::splat(0.0)), F::splat(0.0), F::splat(1.0));
                let beta = cone.control_weight(n);
                let value = sel(control, beta * whole + (bsdf / cone_pdf) * (kept - beta), value);
                let add = (self.throughput * albedo).mulv(light.radiance).scale(value * self.direct_weight);
                self.radiance = selv(shoot & (!blocked | control), self.radiance + add, self.radiance);
            }
        }
        if frame.connect {
            let m = live & self.bounces.add(U::splat(1)).lt(U::splat(params.max_bounces));
            if m.any() {
                let u = self.sampler.next_2d(m);
                let v = self.sampler.next_2d(m);
                let (through, ok) = connection(frame, n, origin, &scatter, u, v, m);
                let add = (self.throughput * albedo) * through;
                self.radiance = selv(ok, self.radiance + add, self.radiance);
            }
        }

        if frame.black_background {
            ended = ended | (live & last);
            live = live & !last;
        }

        let (u1, u2) = self.sampler.next_2d(live);
        let dir = scatter.sample(u1, u2);
        let cos = n.dot(dir);
        let pdf = scatter.pdf(dir);
        let ok = cos.gt(F::splat(0.0)) & pdf.gt(F::splat(0.0));
        ended = ended | (live & !ok);
        live = live & ok;
        self.bsdf_pdf = sel(live, sel(last | projected | control, F::splat(0.0), pdf), self.bsdf_pdf);
        self.nee_pdf = sel(live, cone_pdf, self.nee_pdf);
        self.scatter_pdf = sel(live, pdf, self.scatter_pdf);
        let throughput = self.throughput * albedo.scale(cos * (1.0 / PI) / pdf);
        self.throughput = selv(live, throughput, self.throughput);
        self.bounces = selu(live, self.bounces.add(U::splat(1)), self.bounces);

        let rr = live & self.bounces.ge(U::splat(params.rr_start));
        if rr.any() {
            let tp = self.throughput;
            let follow = if frame.luminance_rr {
                tp.dot(V3::splat(Vec3::new(0.2126, 0.7152, 0.0722)))
            } else {
                tp.max_element()
            };
            let survive = follow.clamp(RR_MIN_SURVIVAL, 1.0);
            let u = self.sampler.next_1d(rr);
            let die = rr & u.ge(survive);
            ended = ended | die;
            live = live & !die;
            self.throughput = selv(rr & !die, self.throughput.div(survive), self.throughput);
        }

        self.origin = selv(live, origin, self.origin);
        self.dir = selv(live, dir, self.dir);
        self.skip_wall = selu(live, wall_index, self.skip_wall);
        ended
    }
}

/// The nearest wall hit per lane but each lane's `skip_wall` (`nearest_wall`
/// of `pt_core::query`): its `t` (`T_FAR` where none), index, and the lanes
/// that hit one.
#[inline(always)]
fn nearest_wall(frame: &Frame, o: V3, d: V3, skip_wall: U) -> (F, U, M) {
    let mut t = F::splat(pt_core::query::T_FAR);
    let mut index = U::splat(0);
    let mut found = M::splat(false);
    for i in 0..frame.walls {
        let ti = wall_t(frame, i, o, d, t);
        let nearer = ti.lt(t) & !skip_wall.eq(U::splat(i));
        t = sel(nearer, ti, t);
        index = selu(nearer, U::splat(i), index);
        found = found | nearer;
    }
    (t, index, found)
}

/// `connection_pdf` of `pt_core::integrator` per lane.
#[inline(always)]
fn connection_pdf(cos: F, d2: F) -> F {
    cos / ((4.0 * PI) * d2)
}

/// `connection` of `pt_core::integrator` on the lanes in `m`: the radiance
/// over the vertex's albedo, and the lanes where it is not 0 (the others
/// returned 0 there).
#[inline(always)]
fn connection(frame: &Frame, n: V3, origin: V3, scatter: &Scatter, u: (F, F), v: (F, F), m: M) -> (V3, M) {
    let params = frame.params;
    let geometry = frame.geometry;
    let light = &params.light;
    let z = 1.0 - 2.0 * u.0;
    let s = (1.0 - z * z).max(F::splat(0.0)).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turn(u.1);
    let c = V3::splat(light.center);
    let dc = V3 { x: s * cos_phi, y: s * sin_phi, z };
    // first_wall: every wall, none skipped.
    let (t, index, found) = nearest_wall(frame, c, dc, U::splat(NO_WALL));
    let mut m = m & found;
    if !m.any() {
        return (V3::splat(Vec3::ZERO), m);
    }
    let mut normal = [[0.0; LANES]; 3];
    let mut albedo = [[0.0; LANES]; 3];
    let (index_lanes, lanes) = (index.to_array(), U(m.0).to_array());
    for k in 0..LANES {
        if lanes[k] != 0 {
            let w = &geometry.walls[(index_lanes[k] as usize).min(MAX_WALLS - 1)];
            (normal[0][k], normal[1][k], normal[2][k]) = (w.normal.x, w.normal.y, w.normal.z);
            (albedo[0][k], albedo[1][k], albedo[2][k]) = (w.albedo.x, w.albedo.y, w.albedo.z);
        }
    }
    let (normal, wall_albedo) = (V3::from_arrays(normal), V3::from_arrays(albedo));
    let y = c.at(dc, t);
    let magnitude = c.abs() + dc.scale(t).abs();
    let ny = selv(normal.dot(dc).lt(F::splat(0.0)), normal, -normal);
    let pdf_area = connection_pdf(-ny.dot(dc), t * t);
    let to_y = y - origin;
    let d2 = to_y.dot(to_y);
    let dist = d2.sqrt();
    let dir = to_y.div(dist);
    let (cos_p, cos_y) = (n.dot(dir), -ny.dot(dir));
    let zero = F::splat(0.0);
    let cone = light_cone(frame, y);
    m = m & cos_p.gt(zero) & cos_y.gt(zero) & pdf_area.gt(zero) & !cone.empty;
    if !m.any() {
        return (V3::splat(Vec3::ZERO), m);
    }
    let hides = sphere_meets_segment(light.center, light.radius, origin, dir, dist);
    m = m & !hides & !occluded(frame, origin, dir, index, dist, m);
    if !m.any() {
        return (V3::splat(Vec3::ZERO), m);
    }
    let projected = if frame.projected { cone.above_horizon(ny) & m } else { M::splat(false) };
    let (mut to_light, mut light_dist) = (V3::splat(Vec3::ZERO), zero);
    if (m & !projected).any() {
        (to_light, light_dist) = cone.sample(v.0, v.1);
    }
    if projected.any() {
        let (p_dir, p_dist) = cone.sample_projected(ny, v.0, v.1);
        (to_light, light_dist) = (selv(projected, p_dir, to_light), sel(projected, p_dist, light_dist));
    }
    let cos_light = ny.dot(to_light);
    m = m & cos_light.gt(zero);
    if !m.any() {
        return (V3::splat(Vec3::ZERO), m);
    }
    let err = magnitude.scale(F::splat(HIT_ERROR_EPS));
    let shadow_origin = y + ny.scale(ny.abs().dot(err));
    m = m & !occluded(frame, shadow_origin, to_light, index, light_dist, m);
    let direct = sel(projected, cone.projected_over_pi(ny), cos_light * (1.0 / PI) / cone.pdf());
    let bsdf_area = scatter.pdf(dir) * cos_y / d2;
    let weight = power_heuristic(pdf_area, bsdf_area);
    let geometry_term = cos_p * cos_y / (PI * d2 * pdf_area);
    (wall_albedo.mulv(light.radiance).scale(direct * geometry_term * weight), m)
}

/// `occluded` per lane, for the lanes in `m`: the walls that can shadow the
/// light (bar each lane's own), then the spheres.
#[inline(always)]
fn occluded(frame: &Frame, o: V3, d: V3, skip_wall: U, t_max: F, m: M) -> M {
    let mut blocked = M::splat(false);
    for &i in &frame.shadow_walls[..frame.shadow_wall_count] {
        let t = wall_t(frame, i, o, d, t_max);
        blocked = blocked | (t.lt(t_max) & !skip_wall.eq(U::splat(i)));
    }
    for s in &frame.geometry.spheres[..frame.spheres as usize] {
        blocked = blocked | sphere_meets_segment(s.center, s.radius, o, d, t_max);
    }
    blocked & m
}

/// The frame's samples of pixels `x0`, `x0 + 1`, ... `x0 + count - 1` of
/// row `y` (`count` at most [`LANES`]), as `render_pixel` gives each.
#[inline(always)]
fn group<const DRAWS: u32, const PCG: bool>(frame: &Frame, x0: u32, y: u32, count: usize) -> [PixelSamples; LANES] {
    let params = frame.params;
    let x = U::from_array(from_fn(|i| x0 + i as u32));
    let pixel = Sampler::<DRAWS, PCG>::for_pixel(x, U::splat(y), params);
    let spp = params.samples_per_frame;
    let mut s = U::splat(0);
    let mut act = M(U::from_array(from_fn(|i| if i < count && spp > 0 { u32::MAX } else { 0 })).0);
    let edge = Edge::of_pixels(x0, y, params);
    let y = U::splat(y);
    let mut paths = Paths::<DRAWS, PCG>::camera(x, y, pixel, s, &edge, params);
    let mut sum = V3::splat(Vec3::ZERO);
    let mut compensation = V3::splat(Vec3::ZERO);
    let mut valid = U::splat(0);
    let mut non_finite = U::splat(0);
    while act.any() {
        let ended = paths.step(frame, act) & act;
        if !ended.any() {
            continue;
        }
        let l = paths.radiance;
        let ok = ended & l.finite();
        // kahan_add.
        let yk = l - compensation;
        let tk = sum + yk;
        compensation = selv(ok, (tk - sum) - yk, compensation);
        sum = selv(ok, tk, sum);
        valid = selu(ok, valid.add(U::splat(1)), valid);
        non_finite = selu(ended & !ok, non_finite.add(U::splat(1)), non_finite);
        s = selu(ended, s.add(U::splat(1)), s);
        let more = s.lt(U::splat(spp));
        act = act & !(ended & !more);
        let restart = ended & more;
        if restart.any() {
            paths = Paths::select(restart, Paths::camera(x, y, pixel, s, &edge, params), paths);
        }
    }
    let (sx, sy, sz) = (sum.x.to_array(), sum.y.to_array(), sum.z.to_array());
    let (valid, non_finite) = (valid.to_array(), non_finite.to_array());
    from_fn(|i| PixelSamples { sum: Vec3::new(sx[i], sy[i], sz[i]), valid: valid[i], non_finite: non_finite[i] })
}

/// Calls `f` with each group of up to [`LANES`] pixels of row `y` of
/// `width` pixels from column `x0`, and the group's samples.
#[inline(always)]
fn row_with<const DRAWS: u32, const PCG: bool>(
    frame: &Frame,
    x0: u32,
    y: u32,
    width: u32,
    out: &mut impl FnMut(usize, PixelSamples),
) {
    let mut x = 0;
    while x < width {
        let count = (width - x).min(LANES as u32) as usize;
        let samples = group::<DRAWS, PCG>(frame, x0 + x, y, count);
        for (k, s) in samples.into_iter().take(count).enumerate() {
            out(x as usize + k, s);
        }
        x += LANES as u32;
    }
}

#[inline(always)]
fn row_any(
    params: &FrameParams,
    geometry: &Geometry,
    x0: u32,
    y: u32,
    width: u32,
    out: &mut impl FnMut(usize, PixelSamples),
) {
    let frame = Frame::new(params, geometry);
    if params.flags & FLAG_SOBOL != 0 {
        if params.flags & FLAG_SOBOL_DEEP != 0 {
            row_with::<{ u32::MAX }, false>(&frame, x0, y, width, out)
        } else {
            row_with::<SOBOL_DRAWS, false>(&frame, x0, y, width, out)
        }
    } else {
        row_with::<0, true>(&frame, x0, y, width, out)
    }
}

/// Whether this CPU runs [`render_row`].
pub fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// The frame's samples of `width` pixels of row `y` from column `x0`, eight
/// at a time: `out(i, samples)` for pixel `x0 + i`, exactly what
/// `render_pixel(x0 + i, y, params, geometry)` returns.
///
/// # Safety
/// The CPU must have AVX2: [`available`] says so.
#[target_feature(enable = "avx2")]
pub unsafe fn render_row(
    params: &FrameParams,
    geometry: &Geometry,
    x0: u32,
    y: u32,
    width: u32,
    mut out: impl FnMut(usize, PixelSamples),
) {
    row_any(params, geometry, x0, y, width, &mut out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{RenderSettings, Scene};
    use pt_core::integrator::render_pixel;
    use pt_core::params::FLAG_CONNECT;
    use pt_core::params::{FLAG_GLOW, FLAG_GLOW_SPARSE};
    use pt_core::{Sphere, Wall};

    /// The scenes the comparison runs on: the default scene; the same with
    /// a grey background (paths that leave the room count, and the last
    /// vertex's BSDF ray is traced); a tiny light in a corner; a partition
    /// and a ninth wall, so that shadow rays test walls too and the
    /// closest-hit loop runs past eight walls; and a camera inside a sphere.
    fn scenes() -> Vec<(&'static str, FrameParams, Geometry)> {
        let base = Scene::default_scene();
        let settings = RenderSettings { width: 21, height: 6, spp: 0, max_bounces: 5, rr_start: 2 };
        let params = |s: &Scene| s.frame_params(&settings, 7, 3);
        let mut out = vec![("default", params(&base), base.geometry().unwrap())];

        let mut grey = params(&base);
        grey.background = Vec3::splat(0.3);
        out.push(("grey background", grey, base.geometry().unwrap()));

        let mut corner = params(&base);
        corner.light = pt_core::SphereLight::new(Vec3::new(-0.95, 1.95, -0.95), 0.02, Vec3::splat(3000.0));
        out.push(("tiny light in a corner", corner, base.geometry().unwrap()));

        let mut walls = base.gpu_walls();
        let v = Vec3::new;
        walls.push(Wall::new(v(-0.6, 0.0, 0.2), v(0.9, 0.0, -0.6), v(0.0, 1.3, 0.0), Vec3::splat(0.5)));
        for k in 0..3 {
            walls.push(Wall::new(
                v(0.2 + 0.1 * k as f32, 1.2, -0.5),
                v(0.3, 0.0, 0.1),
                v(0.0, 0.2, 0.2),
                Vec3::splat(0.8),
            ));
        }
        let mut spheres = base.gpu_spheres();
        spheres.push(Sphere::new(v(0.4, 1.1, -0.4), 0.15, v(0.9, 0.8, 0.2)));
        let geometry = Geometry::new(&walls, &spheres).unwrap();
        let mut many = params(&base);
        (many.wall_count, many.sphere_count) = (walls.len() as u32, spheres.len() as u32);
        out.push(("partition and nine walls", many, geometry));

        let mut inside = params(&base);
        inside.camera.position = Vec3::new(-0.45, 0.40, -0.30);
        out.push(("camera inside a sphere", inside, base.geometry().unwrap()));
        out
    }

    /// Every integrator flag combination, on every scene above, with
    /// paths of 1, 5 and 16 bounces, frames of 0, 1 and 7 samples, a tile
    /// that starts mid-row and rows that are not a multiple of eight: each
    /// pixel's samples are exactly `render_pixel`'s.
    #[test]
    fn eight_lanes_return_the_scalar_samples_bit_for_bit() {
        assert!(available(), "this test needs a CPU with AVX2, which the CPU renderer uses where it has it");
        let mut checked = 0;
        for (name, base, geometry) in scenes() {
            for flags in 0..512u32 {
                let known = FLAG_NEE
                    | FLAG_MIS
                    | FLAG_SOBOL
                    | FLAG_RR_LUMINANCE
                    | FLAG_GLOW
                    | FLAG_SOBOL_DEEP
                    | FLAG_NEE_PROJECTED
                    | FLAG_GLOW_SPARSE
                    | FLAG_CONNECT;
                assert_eq!(flags & !known, 0);
                for (max_bounces, spp) in [(5, 7), (1, 1), (16, 7), (5, 0)] {
                    let params =
                        FrameParams { flags, max_bounces, samples_per_frame: spp, frame: 2, sample_offset: 9, ..base };
                    for (x0, y, width) in [(0, 0, 21), (3, 4, 11)] {
                        let mut got = vec![None; width as usize];
                        // SAFETY: AVX2 is asserted above.
                        unsafe { render_row(&params, &geometry, x0, y, width, |i, s| got[i] = Some(s)) };
                        for (i, g) in got.into_iter().enumerate() {
                            let want = render_pixel(x0 + i as u32, y, &params, &geometry);
                            assert_eq!(
                                g,
                                Some(want),
                                "{name}, flags {flags}, {max_bounces} bounces, {spp} spp, pixel ({}, {y})",
                                x0 + i as u32
                            );
                            checked += (spp > 0) as u32;
                        }
                    }
                }
            }
        }
        assert_eq!(checked, 5 * 512 * 3 * 32);
    }
}
