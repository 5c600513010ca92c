//! Rays and robust spawning of new rays from surface points.

use spirv_std::glam::Vec3;

/// A ray `origin + t * dir`, `dir` of unit length.
#[derive(Copy, Clone, Debug)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

impl Ray {
    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Relative rounding error budget of a computed hit point, in units of
/// `f32::EPSILON` times the magnitude of the values it came from.
///
/// A hit point computed as `o + t d` (or re-projected onto a sphere) is off
/// the true surface by a few ulps of the largest magnitude involved (pbrt-v4,
/// section 6.8, bounds it by gamma(7) ~ 7 eps for ray/plane). 32 eps keeps a
/// wide safety factor and is still invisible: 4e-6 of the scene's size.
pub const HIT_ERROR_EPS: f32 = 32.0 * f32::EPSILON;

/// Moves a surface point off its surface along the normal by more than its
/// rounding error, so that a ray spawned from it toward the side of `normal`
/// cannot re-hit the same surface (pbrt-v4, `OffsetRayOrigin`).
///
/// `magnitude` is a component-wise bound on the values the point was
/// computed from (for `o + t d`: `|o| + |t d|`), which makes the offset scale
/// with the scene instead of being a fixed epsilon.
pub fn offset_origin(p: Vec3, normal: Vec3, magnitude: Vec3) -> Vec3 {
    let err = magnitude * HIT_ERROR_EPS;
    let d = normal.abs().dot(err);
    p + normal * d
}
