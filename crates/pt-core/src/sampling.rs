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
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A direction about unit `n` with density cos(theta)/pi (Malley's method:
/// a uniform disk point lifted onto the hemisphere). `u1`, `u2` in [0, 1).
pub fn cosine_hemisphere(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let x = r * phi.cos();
    let y = r * phi.sin();
    // 1 - u1 instead of 1 - x^2 - y^2: exact, never negative.
    let z = (1.0 - u1).sqrt();
    let (t, b) = orthonormal_basis(n);
    t * x + b * y + n * z
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
