//! Diffuse spheres and the numerically careful ray/sphere intersection.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::ray::Ray;

/// A Lambertian sphere, as the kernel reads it from its storage buffer.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Sphere {
    /// Centre, world space.
    pub center: Vec3,
    /// Radius, > 0 (checked when the scene is loaded).
    pub radius: f32,
    /// Diffuse reflectance per RGB channel, each in [0, 1].
    pub albedo: Vec3,
    /// Padding to a 16-byte multiple.
    pub _pad: f32,
}

impl Sphere {
    /// A sphere from its centre, radius and albedo.
    pub fn new(center: Vec3, radius: f32, albedo: Vec3) -> Self {
        Self {
            center,
            radius,
            albedo,
            _pad: 0.0,
        }
    }
}

/// The smallest `t` in (`t_min`, `t_max`) where the ray meets the sphere, or
/// `t_max` when it misses. `ray.dir` must be of unit length.
///
/// Follows Haines et al., "Precision Improvements for Ray/Sphere
/// Intersection" (Ray Tracing Gems, ch. 7): the discriminant is computed
/// from the perpendicular distance of the centre to the line, `r^2 - |f -
/// (f.d) d|^2`, which stays accurate for far and tiny spheres where `b^2 -
/// c` cancels; the two roots come from the stable `q` form, so the small
/// root is accurate for an origin on or near the surface.
pub fn intersect_sphere(center: Vec3, radius: f32, ray: &Ray, t_min: f32, t_max: f32) -> f32 {
    let f = ray.origin - center;
    let b = -f.dot(ray.dir);
    let perp = f + ray.dir * b;
    let r2 = radius * radius;
    let disc = r2 - perp.dot(perp);
    if disc < 0.0 {
        return t_max;
    }
    let c = f.dot(f) - r2;
    let sign_b = if b >= 0.0 { 1.0 } else { -1.0 };
    let q = b + sign_b * disc.sqrt();
    // Roots q and c / q; q == 0 only when b == 0 and disc == 0 (a tangent
    // ray through the centre's foot point at the origin): one root, 0.
    let (t0, t1) = if q == 0.0 {
        (0.0, 0.0)
    } else {
        let other = c / q;
        if other < q { (other, q) } else { (q, other) }
    };
    if t0 > t_min && t0 < t_max {
        t0
    } else if t1 > t_min && t1 < t_max {
        t1
    } else {
        t_max
    }
}

/// The hit point at `t` re-projected onto the sphere's surface, which
/// removes most of the rounding error of `o + t d` (pbrt-v4, section 6.8.5).
pub fn sphere_hit_point(center: Vec3, radius: f32, ray: &Ray, t: f32) -> (Vec3, Vec3) {
    let p = ray.at(t);
    let to_p = p - center;
    let len = to_p.length();
    // len is ~radius > 0 for a real hit; guard anyway so that no NaN leaks.
    let normal = if len > 0.0 { to_p / len } else { Vec3::Y };
    (center + normal * radius, normal)
}
