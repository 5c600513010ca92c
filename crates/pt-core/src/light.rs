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
        Self { center, radius, radiance, _pad: 0.0 }
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
    // Written so that a NaN point also gives the empty cone.
    if d2 > r2 {
        let dist = d2.sqrt();
        let sin2_max = r2 / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        LightCone { axis: to_center / dist, dist, sin2_max, one_minus_cos_max: sin2_max / (1.0 + cos_max) }
    } else {
        LightCone { axis: Vec3::Z, dist: 0.0, sin2_max: 0.0, one_minus_cos_max: 0.0 }
    }
}

impl LightCone {
    /// Whether the point sees no light (it is on or inside the light).
    pub fn is_empty(&self) -> bool {
        // light_cone gives 0 for an empty cone and r^2/d^2/(1+cos) > 0 else.
        self.one_minus_cos_max <= 0.0
    }

    /// Solid-angle density of [`LightCone::sample`]: uniform over the cone;
    /// 0 for an empty cone.
    pub fn pdf(&self) -> f32 {
        if self.is_empty() { 0.0 } else { 1.0 / (2.0 * PI * self.one_minus_cos_max) }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::Ray;
    use crate::rng::Rng;
    use crate::sphere::intersect_sphere;

    #[test]
    fn one_minus_cos_has_full_precision_for_tiny_lights() {
        // Case: sin(alpha) = 1e-4: 1 - cos by subtraction loses all digits in f32.
        let light = SphereLight::new(Vec3::new(0.0, 0.0, -1.0), 1e-4, Vec3::ONE);
        let cone = light_cone(&light, Vec3::ZERO);
        let exact = 1.0 - (1.0f64 - 1e-8).sqrt();
        assert!(((cone.one_minus_cos_max as f64 - exact) / exact).abs() < 1e-5);
    }

    #[test]
    fn samples_lie_in_the_cone_and_hit_the_light_at_the_returned_distance() {
        for (sin_alpha, seed) in [(1e-4f32, 1), (0.01, 2), (0.5, 3), (0.999, 4)] {
            let d = 3.0;
            let light = SphereLight::new(Vec3::new(0.4, -2.0, 1.0), d * sin_alpha, Vec3::ONE);
            let p = light.center + Vec3::new(2.0, 1.0, -2.0).normalize() * d;
            let cone = light_cone(&light, p);
            let mut rng = Rng::new(seed, 0, 0, 0, 0);
            for _ in 0..2000 {
                let (dir, dist) = cone.sample(rng.next_f32(), rng.next_f32());
                assert!((dir.length() - 1.0).abs() < 1e-5);
                let t = intersect_sphere(light.center, light.radius, &Ray { origin: p, dir }, 0.0, f32::MAX);
                // Directions at the cone's rim graze the sphere: allow them
                // to miss by rounding only when sin_alpha is large.
                if t == f32::MAX {
                    assert!(sin_alpha > 0.9, "sample missed a light of sin(alpha) {sin_alpha}");
                    continue;
                }
                assert!((t - dist).abs() <= 2e-3 * d, "sin {sin_alpha}: t {t} vs dist {dist}");
            }
        }
    }

    #[test]
    fn cone_pdf_integrates_to_one_over_its_solid_angle() {
        // The cone's solid angle is 2 pi (1 - cos); uniform density times it is 1.
        let light = SphereLight::new(Vec3::ZERO, 0.3, Vec3::ONE);
        let cone = light_cone(&light, Vec3::new(0.0, 0.0, 2.0));
        let solid_angle = 2.0 * PI * (1.0 - (1.0f32 - 0.0225).sqrt());
        assert!((cone.pdf() * solid_angle - 1.0).abs() < 1e-5);
    }

    #[test]
    fn points_inside_the_light_see_an_empty_cone() {
        let light = SphereLight::new(Vec3::ZERO, 1.0, Vec3::ONE);
        assert!(light_cone(&light, Vec3::new(0.5, 0.0, 0.0)).is_empty());
        assert_eq!(light_cone(&light, Vec3::new(0.5, 0.0, 0.0)).pdf(), 0.0);
        assert!(!light_cone(&light, Vec3::new(1.5, 0.0, 0.0)).is_empty());
    }
}
