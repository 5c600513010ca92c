//! The spherical area light and sampling of the cone of directions it
//! subtends (solid-angle density).

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::sampling::{PI, orthonormal_basis};

/// A spherical light: emits `radiance` from every point of its surface,
/// outward, and reflects nothing.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SphereLight {
    /// Centre, world space.
    pub center: Vec3,
    /// Radius, > 0.
    pub radius: f32,
    /// Emitted radiance, linear RGB.
    pub radiance: Vec3,
    /// Padding to a 16-byte multiple.
    pub _pad: f32,
}

impl SphereLight {
    /// A light from its centre, radius and emitted radiance.
    pub fn new(center: Vec3, radius: f32, radiance: Vec3) -> Self {
        Self {
            center,
            radius,
            radiance,
            _pad: 0.0,
        }
    }
}

/// The cone of directions in which a point sees the light.
#[derive(Copy, Clone, Debug)]
pub struct LightCone {
    /// Unit vector from the point toward the light's centre.
    pub axis: Vec3,
    /// Distance from the point to the centre.
    pub dist: f32,
    /// sin^2 of the cone's half angle, (r / d)^2.
    pub sin2_max: f32,
    /// 1 - cos of the half angle, computed as sin^2 / (1 + cos): no
    /// cancellation however small the light looks.
    pub one_minus_cos_max: f32,
}

/// The cone in which `p` sees `light`. When `p` is on or inside the light
/// (where the light shows its inside, which emits nothing) the cone is
/// empty: [`LightCone::is_empty`] is true and its pdf is 0.
pub fn light_cone(light: &SphereLight, p: Vec3) -> LightCone {
    let to_center = light.center - p;
    let d2 = to_center.dot(to_center);
    let r2 = light.radius * light.radius;
    if !(d2 > r2) {
        return LightCone {
            axis: Vec3::Z,
            dist: 0.0,
            sin2_max: 0.0,
            one_minus_cos_max: 0.0,
        };
    }
    let dist = d2.sqrt();
    let sin2_max = r2 / d2;
    let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
    LightCone {
        axis: to_center / dist,
        dist,
        sin2_max,
        one_minus_cos_max: sin2_max / (1.0 + cos_max),
    }
}

impl LightCone {
    /// Whether the point sees no light (it is on or inside the light).
    pub fn is_empty(&self) -> bool {
        !(self.one_minus_cos_max > 0.0)
    }

    /// Solid-angle density of [`LightCone::sample`]: uniform over the cone;
    /// 0 for an empty cone.
    pub fn pdf(&self) -> f32 {
        if self.is_empty() {
            0.0
        } else {
            1.0 / (2.0 * PI * self.one_minus_cos_max)
        }
    }

    /// A direction uniform in the cone and the distance along it to the
    /// light's near surface. `u1`, `u2` in [0, 1).
    ///
    /// cos(theta) = 1 - u1 (1 - cos_max); sin^2 comes from the product form
    /// `x (2 - x)`, x = 1 - cos(theta), so tiny cones keep full precision.
    pub fn sample(&self, u1: f32, u2: f32) -> (Vec3, f32) {
        let one_minus_cos = u1 * self.one_minus_cos_max;
        let cos_theta = 1.0 - one_minus_cos;
        let sin2 = one_minus_cos * (2.0 - one_minus_cos);
        let sin_theta = sin2.max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let (t, b) = orthonormal_basis(self.axis);
        let dir = t * (sin_theta * phi.cos()) + b * (sin_theta * phi.sin()) + self.axis * cos_theta;
        // Near root of |p + s dir - c| = r: s = d cos - d sqrt(sin2_max - sin2).
        let dist = self.dist * (cos_theta - (self.sin2_max - sin2).max(0.0).sqrt());
        (dir, dist)
    }
}
