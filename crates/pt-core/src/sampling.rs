//! Direction sampling: orthonormal bases and cosine-weighted hemispheres.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use spirv_std::glam::Vec3;

/// pi as f32.
pub const PI: f32 = core::f32::consts::PI;

/// Two unit vectors `(t, b)` with `(t, b, n)` a right-handed orthonormal
/// basis, for unit `n`. Branchless and continuous except at n.z = -1 (Duff et
/// al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017).
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// The unit vector at the angle with cosine `cos_theta` and sine
/// `sin_theta` from unit `axis`, turned by `2 pi u` about it.
pub fn about_axis(axis: Vec3, cos_theta: f32, sin_theta: f32, u: f32) -> Vec3 {
    let (sin_phi, cos_phi) = sin_cos_of_turn(u);
    let (t, b) = orthonormal_basis(axis);
    t * (sin_theta * cos_phi) + b * (sin_theta * sin_phi) + axis * cos_theta
}

/// `(sin, cos)` of the angle `2 pi u`: the shader's own functions in the
/// kernel, [`sin_cos_turn`] on the CPU.
#[inline(always)]
pub fn sin_cos_of_turn(u: f32) -> (f32, f32) {
    #[cfg(target_arch = "spirv")]
    {
        let phi = 2.0 * PI * u;
        (phi.sin(), phi.cos())
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        sin_cos_turn(u)
    }
}

/// `ln x` and `exp x` for the glow lobe (`light::GlowLobe`): the shader's
/// own functions in the kernel, [`ln_poly`] and [`exp_poly`] on the CPU,
/// where libm's were a call per lane in the eight-lane path loop and nearly
/// all of the lobe's extra time per sample there.
#[inline(always)]
pub fn ln_f32(x: f32) -> f32 {
    #[cfg(target_arch = "spirv")]
    {
        x.ln()
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        ln_poly(x)
    }
}

/// See [`ln_f32`].
#[inline(always)]
pub fn exp_f32(x: f32) -> f32 {
    #[cfg(target_arch = "spirv")]
    {
        x.exp()
    }
    #[cfg(not(target_arch = "spirv"))]
    {
        exp_poly(x)
    }
}

/// `ln 2` in two parts: `LN_2_HI` has 16 significant bits, so `k LN_2_HI`
/// is exact for the exponents `k` of f32, and `LN_2_LO` is the rest.
#[cfg(not(target_arch = "spirv"))]
const LN_2_HI: f32 = 0.693_145_75;
#[cfg(not(target_arch = "spirv"))]
const LN_2_LO: f32 = 1.428_606_8e-6;

/// `ln x` for a normal `x > 0` on the CPU: `x = m 2^k` with `m` in
/// [sqrt(1/2), sqrt(2)] ([`ln_split`]), then [`ln_reduced`]. Within 2 ulp
/// of the true value on the glow lobe's domain (the tests check).
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn ln_poly(x: f32) -> f32 {
    let (m, k) = ln_split(x);
    ln_reduced(m, k)
}

/// `(m, k)` with `x = m 2^k` and `m` in [sqrt(1/2), sqrt(2)], for a
/// normal `x > 0`: the exponent and mantissa bits, exactly.
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn ln_split(x: f32) -> (f32, f32) {
    let bits = x.to_bits();
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let k = ((bits >> 23) & 0xff) as i32 - 127;
    if m > core::f32::consts::SQRT_2 { (m * 0.5, (k + 1) as f32) } else { (m, k as f32) }
}

/// `ln(m 2^k)` for `m` in [sqrt(1/2), sqrt(2)]: `k ln 2 + 2 atanh(s)`, `s =
/// (m - 1) / (m + 1)` (`m - 1` is exact there, and `|s| <= 0.172`), by the
/// series of `atanh` to `s^9` (the first term left out is below 1e-9).
/// Generic so that the eight-lane path loop (`pt_render::lanes`) runs
/// these very operations on its vectors and gets [`ln_poly`]'s bits.
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn ln_reduced<T>(m: T, k: T) -> T
where
    T: Copy + core::ops::Add<Output = T> + core::ops::Mul<Output = T> + core::ops::Div<Output = T>,
    T: core::ops::Add<f32, Output = T> + core::ops::Sub<f32, Output = T> + core::ops::Mul<f32, Output = T>,
{
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let tail = s2 * (s2 * (s2 * (s2 * (1.0 / 9.0) + 1.0 / 7.0) + 1.0 / 5.0) + 1.0 / 3.0);
    let twice = s * 2.0;
    k * LN_2_HI + (twice + twice * tail + k * LN_2_LO)
}

/// `exp x` for `|x| < 87` on the CPU: `x = k ln 2 + r` with `|r| <= ln 2 /
/// 2` ([`exp_split`] gives `k` and `2^k`), then [`exp_reduced`]. Within 2
/// ulp of the true value on the glow lobe's domain (the tests check).
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn exp_poly(x: f32) -> f32 {
    let (k, two_k) = exp_split(x);
    exp_reduced(x, k, two_k)
}

/// `(k, 2^k)`, `k` the integer nearest `x / ln 2`, held to the exponents
/// of normal f32 (a NaN gives `k` NaN and `2^k` 1).
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn exp_split(x: f32) -> (f32, f32) {
    let k = (x * core::f32::consts::LOG2_E).round_ties_even().clamp(-126.0, 127.0);
    (k, f32::from_bits(((k as i32 + 127) as u32) << 23))
}

/// `exp x` from [`exp_split`]'s `k` and `2^k`: `2^k exp(r)`, `r = x - k ln
/// 2` (in two parts, exact to f32), `exp(r)` by its Taylor polynomial to
/// `r^7` (the first term left out is below 6e-9). Generic as
/// [`ln_reduced`] is.
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn exp_reduced<T>(x: T, k: T, two_k: T) -> T
where
    T: Copy + core::ops::Add<Output = T> + core::ops::Sub<Output = T> + core::ops::Mul<Output = T>,
    T: core::ops::Add<f32, Output = T> + core::ops::Mul<f32, Output = T>,
{
    let r = (x - k * LN_2_HI) - k * LN_2_LO;
    let p = r
        * (r * (r * (r * (r * (r * (r * (1.0 / 5040.0) + 1.0 / 720.0) + 1.0 / 120.0) + 1.0 / 24.0) + 1.0 / 6.0) + 0.5)
            + 1.0)
        + 1.0;
    p * two_k
}

/// `(sin a, cos a)` for |a| <= pi/4 by their Taylor polynomials, to `a^9`
/// and `a^10` (the first terms left out are below 2e-9 and 3e-9), in
/// Horner's form. Generic so that the CPU's eight-lane path loop
/// (`pt_render::lanes`) runs these very operations on its vectors and gets
/// the same bits as [`sin_cos_turn`].
#[cfg(not(target_arch = "spirv"))]
#[inline(always)]
pub fn sin_cos_taylor<T>(a: T) -> (T, T)
where
    T: Copy + core::ops::Add<Output = T> + core::ops::Mul<Output = T> + core::ops::Add<f32, Output = T>,
    T: core::ops::Mul<f32, Output = T>,
{
    let a2 = a * a;
    let sin = a + a * a2 * (a2 * (a2 * (a2 * (1.0 / 362_880.0) + -1.0 / 5040.0) + 1.0 / 120.0) + -1.0 / 6.0);
    let cos =
        a2 * (a2 * (a2 * (a2 * (a2 * (-1.0 / 3_628_800.0) + 1.0 / 40_320.0) + -1.0 / 720.0) + 1.0 / 24.0) + -0.5) + 1.0;
    (sin, cos)
}

/// `(sin, cos)` of `2 pi u` on the CPU, by polynomials: the CPU's libm
/// call per direction is a call per lane in the eight-lane path loop
/// (`pt_render::lanes`), which evaluates these same operations on eight
/// lanes at once and so gets the same bits. The kernel keeps the shader's
/// own sine and cosine.
///
/// `4u` splits into a quarter turn `q` (rounded to nearest, ties to even)
/// and a rest in [-1/2, 1/2], exactly; the rest, as an angle `a` of at most
/// pi/4, goes through the Taylor polynomials, and `q` rotates the pair.
/// Within 2.5e-7 of the true values (the tests check).
#[cfg(not(target_arch = "spirv"))]
#[inline]
pub fn sin_cos_turn(u: f32) -> (f32, f32) {
    let t = 4.0 * u;
    let q = t.round_ties_even();
    let (s, c) = sin_cos_taylor((t - q) * (PI / 2.0));
    match (q as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `(cos, sin)` of the polar angle of [`cosine_hemisphere`]'s direction
/// for `u1`: Malley's method lifts a uniform disk point of radius
/// `sqrt(u1)` onto the hemisphere; `1 - u1` is exact and never negative.
pub fn cosine_polar(u1: f32) -> (f32, f32) {
    ((1.0 - u1).sqrt(), u1.sqrt())
}

/// A direction about unit `n` with density cos(theta)/pi (Malley's method).
/// `u1`, `u2` in [0, 1).
pub fn cosine_hemisphere(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (cos_theta, sin_theta) = cosine_polar(u1);
    about_axis(n, cos_theta, sin_theta, u2)
}

/// Density of [`cosine_hemisphere`] for a direction with cosine `cos_theta`
/// to the normal (solid angle measure).
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * (1.0 / PI)
}

/// Power heuristic with exponent 2 (Veach 1997), weight of strategy `f`
/// against strategy `g`, one sample each.
pub fn power_heuristic(pdf_f: f32, pdf_g: f32) -> f32 {
    let f2 = pdf_f * pdf_f;
    let g2 = pdf_g * pdf_g;
    if f2 + g2 > 0.0 { f2 / (f2 + g2) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn basis_is_orthonormal_including_near_minus_z() {
        for n in
            [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(1e-7, 0.0, -1.0).normalize(), Vec3::new(0.3, -0.5, 0.8).normalize()]
        {
            let (t, b) = orthonormal_basis(n);
            for (u, v) in [(t, b), (t, n), (b, n)] {
                assert!(u.dot(v).abs() < 1e-6, "{n}: not orthogonal");
            }
            assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
            assert!((t.cross(b) - n).length() < 1e-6, "{n}: not right-handed");
        }
    }

    #[test]
    fn cosine_samples_have_the_moments_of_cos_over_pi() {
        // Under p = cos/pi: E[cos] = 2/3, E[cos^2] = 1/2. With 1e5 samples
        // the standard error of the mean of cos is sqrt(1/2 - 4/9)/sqrt(1e5)
        // = 7.5e-4; tolerance 5 sigma.
        let n = Vec3::new(0.2, 0.9, -0.3).normalize();
        let mut rng = Rng::new(7, 11, 0, 0, 0);
        let count = 100_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            let d = cosine_hemisphere(n, rng.next_f32(), rng.next_f32());
            let c = n.dot(d) as f64;
            assert!(c > 0.0, "sample below the hemisphere");
            assert!((d.length() - 1.0).abs() < 1e-5);
            s1 += c;
            s2 += c * c;
        }
        let se = ((0.5 - 4.0 / 9.0) / count as f64).sqrt();
        assert!((s1 / count as f64 - 2.0 / 3.0).abs() < 5.0 * se);
        assert!((s2 / count as f64 - 0.5).abs() < 5.0 * 2e-3);
    }

    /// `ln_poly` and `exp_poly` against f64 on the glow lobe's domain: the
    /// lobe's `reach / scale` from 1 to `1 + GLOW_REACH / GLOW_MIN_SCALE`
    /// (about 1.25e5) and `exp` of `u ln` of it, at a million points each,
    /// within 2 ulp (and exact at 1 and 0).
    #[test]
    fn ln_and_exp_polynomials_are_within_two_ulps() {
        // The bits of |want| as an f32, and the spacing of f32 there.
        let bits = |v: f64| (v.abs() as f32).max(f32::MIN_POSITIVE).to_bits();
        let close = |got: f32, want: f64| {
            let one = f32::from_bits(bits(want) + 1) as f64 - f32::from_bits(bits(want)) as f64;
            (got as f64 - want).abs() <= 2.0 * one
        };
        let top = 1.0 + crate::light::GLOW_REACH / crate::light::GLOW_MIN_SCALE;
        for i in 0..1_000_000u32 {
            let x = (top.ln() * i as f32 / 1e6).exp().max(1.0);
            let l = ln_poly(x);
            assert!(close(l, (x as f64).ln()) || (x == 1.0 && l == 0.0), "ln {x}: {l}");
            let y = top.ln() * i as f32 / 1e6;
            assert!(close(exp_poly(y), (y as f64).exp()), "exp {y}: {}", exp_poly(y));
            // Arguments below 1 and negative ones, for the rest of the range.
            let z = 1e-3 + i as f32 * 1e-6;
            assert!(close(ln_poly(z), (z as f64).ln()), "ln {z}");
            assert!(close(exp_poly(-y), (-y as f64).exp()), "exp {}", -y);
        }
        assert_eq!((ln_poly(1.0), exp_poly(0.0)), (0.0, 1.0));
    }

    /// `sin_cos_turn` against f64 sine and cosine at a million points of
    /// [0, 1) and at the quarter turns, where the rounding of `4u` changes.
    #[test]
    fn sin_cos_turn_is_within_a_few_ulps() {
        let check = |u: f32| {
            let (s, c) = sin_cos_turn(u);
            let phi = 2.0 * std::f64::consts::PI * u as f64;
            let (es, ec) = ((s as f64 - phi.sin()).abs(), (c as f64 - phi.cos()).abs());
            assert!(es < 2.5e-7 && ec < 2.5e-7, "u {u}: sin {s} cos {c}, errors {es:.2e} {ec:.2e}");
        };
        for i in 0..1_000_000u32 {
            check(i as f32 / 1e6);
        }
        for q in [0.125f32, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0 - f32::EPSILON / 2.0] {
            for u in [q, f32::from_bits(q.to_bits() - 1), f32::from_bits(q.to_bits() + 1)] {
                check(u);
            }
        }
        assert_eq!(sin_cos_turn(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turn(0.5).1, -1.0);
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 1.0), (3.0, 0.5), (1e7, 0.3), (0.0, 2.0)] {
            assert!((power_heuristic(a, b) + power_heuristic(b, a) - 1.0).abs() < 1e-6);
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }

    /// Case: 400,000 cosine-hemisphere directions about a tilted normal,
    /// binned in 20 x 40 equal-area cells of the sphere, pass a chi-square
    /// test against counts integrated from the pdf (cells under 5 expected
    /// samples pooled, as Mitsuba 3's chi2.py); the pdf integrates to one
    /// over the sphere (midpoint rule in f64 on 2000 x 2000 cells, 1e-4).
    #[test]
    fn cosine_samples_pass_chi_square_and_the_pdf_integrates_to_one() {
        use crate::rng::Rng;
        use crate::test_support::chi2::{SphereBins, chi2_test};
        use crate::test_support::chi2_alpha;
        use spirv_std::glam::DVec3;
        let normal = Vec3::new(0.3, -0.4, 0.866).normalize();
        let nd = normal.as_dvec3();
        let pdf = |d: [f64; 3]| DVec3::from_array(d).dot(nd).max(0.0) / std::f64::consts::PI;
        let (bins, n) = (SphereBins { nt: 20, np: 40 }, 400_000);
        let mut rng = Rng::new(5, 6, 7, 8, 9);
        let mut observed = vec![0.0; bins.nt * bins.np];
        for _ in 0..n {
            let d = cosine_hemisphere(normal, rng.next_f32(), rng.next_f32());
            observed[bins.cell([d.x as f64, d.y as f64, d.z as f64])] += 1.0;
        }
        let r = chi2_test(&observed, &bins.expected(n, 8, pdf));
        assert!(r.p_value >= chi2_alpha(), "chi2 {:.1} on {} dof: p = {:.2e}", r.chi2, r.dof, r.p_value);
        let total: f64 = SphereBins { nt: 200, np: 200 }.expected(1, 10, pdf).iter().sum();
        assert!((total - 1.0).abs() <= 1e-4, "{total}");
    }
}
