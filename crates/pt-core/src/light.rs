//! The spherical area light and sampling of the cone of directions it
//! subtends (solid-angle density).

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::sampling::{PI, about_axis, exp_f32, ln_f32, orthonormal_basis, sin_cos_of_turn};

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
        let dir = about_axis(self.axis, cos_theta, sin_theta, u2);
        (dir, self.near_distance(one_minus_cos))
    }

    /// The distance to the light's near surface along a direction of the
    /// cone whose angle to the axis has `1 - cos` = `one_minus_cos`: the
    /// near root of |p + s dir - c| = r, s = d cos - d sqrt(sin2_max -
    /// sin2), with sin2 from the product form `x (2 - x)`.
    #[inline]
    fn near_distance(&self, one_minus_cos: f32) -> f32 {
        let sin2 = one_minus_cos * (2.0 - one_minus_cos);
        self.dist * ((1.0 - one_minus_cos) - (self.sin2_max - sin2).max(0.0).sqrt())
    }

    /// Whether the cone is not empty and lies wholly above the horizon of
    /// a surface of unit normal `n`: the angle from `n` to the axis plus
    /// the cone's half angle is at most 90 degrees.
    pub fn above_horizon(&self, n: Vec3) -> bool {
        let c = n.dot(self.axis);
        !self.is_empty() && c > 0.0 && c * c >= self.sin2_max
    }

    /// The weight of NEE's control variate at a surface of unit normal
    /// `n` (`FLAG_NEE_CONTROL`): 1 where the cone lies wholly above the
    /// horizon, 0 where wholly below, and between them the smoothstep
    /// `t^2 (3 - 2t)` of the share `t` of the range of the cone's cosines,
    /// `n . axis +- sin(half angle)`, that lies above 0.
    ///
    /// The control is the signed cosine `g`, the estimated integrand its
    /// positive part `f` (times visibility). The weight that leaves least
    /// variance is `Cov(f, g) / Var(g)`; for cosines spread uniformly over
    /// a range of which a share `t` is positive it is `t^2 (3 - 2t)`. With
    /// weight 1 wherever the cone's axis is above the horizon and 0 below,
    /// relMSE at 64 spp on the CPU was 1.007x this weight's around the
    /// large light and 1.003x around lights of radius 0.19 to 0.3 (6
    /// seeds); with weight 1 on a lit sphere's terminator beside a large
    /// light, the noise of direct light was 1.14x that of no control
    /// variate at all.
    pub fn control_weight(&self, n: Vec3) -> f32 {
        let t = (0.5 + 0.5 * n.dot(self.axis) / self.sin2_max.sqrt()).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }

    /// The cone's projected solid angle on a surface of unit normal `n`
    /// over pi, `sin^2(half angle) cos(angle from n to the axis)`: the
    /// integral of `cos / pi` over the cone where
    /// [`LightCone::above_horizon`], and of the signed cosine (negative
    /// below the horizon) over pi at every tilt. A diffuse surface that sees all of the
    /// light reflects `albedo * radiance` times this.
    pub fn projected_over_pi(&self, n: Vec3) -> f32 {
        self.sin2_max * n.dot(self.axis)
    }

    /// A direction of the cone with density proportional to its cosine to
    /// `n` (projected solid angle), and the distance along it to the
    /// light's near surface; only where [`LightCone::above_horizon`].
    /// `u1`, `u2` in [0, 1).
    ///
    /// The cone meets the unit sphere in a circle whose plane is normal to
    /// the axis; seen along `n` (dropped onto the tangent plane) that
    /// circle is an ellipse, and a point uniform in the ellipse, lifted back
    /// onto the hemisphere, has density `cos / (pi sin^2 cos_axis)` (the
    /// tangent plane's area is projected solid angle, Nusselt's analogue).
    /// With `t1` the tangent toward the axis, the ellipse has centre
    /// `cos(half angle) sin(axis angle) t1` and half axes `sin(half angle)
    /// cos(axis angle)` along `t1` and `sin(half angle)` across it. A
    /// shadow ray's estimate is then `albedo * radiance *
    /// projected_over_pi` when it reaches the light and 0 otherwise: no
    /// noise at all where the whole light is visible or hidden.
    pub fn sample_projected(&self, n: Vec3, u1: f32, u2: f32) -> (Vec3, f32) {
        let c = n.dot(self.axis);
        let toward = self.axis - n * c;
        let s2 = toward.dot(toward);
        // Light at the zenith: every tangent leads toward it.
        let (t1, t2) = if s2 > 1e-12 {
            let t1 = toward / s2.sqrt();
            (t1, n.cross(t1))
        } else {
            orthonormal_basis(n)
        };
        let sin_half = self.sin2_max.sqrt();
        let cos_half = 1.0 - self.one_minus_cos_max;
        // A point uniform in the unit disc, polar: radius sqrt(u1).
        let r = u1.sqrt();
        let (sin_phi, cos_phi) = sin_cos_of_turn(u2);
        let x = cos_half * s2.sqrt() + sin_half * c * (r * cos_phi);
        let y = sin_half * (r * sin_phi);
        let h = (1.0 - x * x - y * y).max(0.0).sqrt();
        let dir = t1 * x + t2 * y + n * h;
        // 1 - cos of the angle to the axis from half the squared chord,
        // which keeps its digits in tiny cones.
        let chord = dir - self.axis;
        (dir, self.near_distance(0.5 * chord.dot(chord)))
    }
}

/// How far the glow lobe reaches past the light's cone, in `1 - cos` of the
/// angle to the light: 0.125, 29 degrees around a point-sized light. Chosen
/// with [`crate::bsdf::GLOW_PROBABILITY`] by the relMSE at 64 spp on
/// the default scene, among reaches 1/16, 1/8 and 1/4 and probabilities
/// 0.2, 0.25 and 0.35: the neighbours of this pair were 4% to 14% worse.
pub const GLOW_REACH: f32 = 0.125;

/// The smallest inner edge of the glow lobe. Its density is evaluated from
/// `1 - cos` of directions, which half the squared chord gives to a few
/// 1e-8 near the axis; round a tinier light the lobe starts a little
/// outside its cone, which NEE covers anyway.
pub const GLOW_MIN_SCALE: f32 = 1e-6;

/// The glow lobe: directions around the light with solid-angle density
/// proportional to `1 / x`, `x = 1 - cos` of the angle to the light's
/// centre, from the rim of the light's cone (`x = e`, that of the light's
/// half angle) out to `x = e + GLOW_REACH`. The light's own cone is left to
/// NEE: BSDF samples there would mostly be weighed away by MIS.
///
/// Surfaces near a light glow: their irradiance falls as the inverse
/// square of the distance to the light. Seen from afar, a point at distance
/// `r` from the light lies at an angle `a ~ r / d` from it, and
/// `x ~ a^2 / 2`: the glow's radiance falls as `1 / x` around the light's
/// direction, the shape of this density. BSDF sampling mixes it with the
/// cosine lobe, so that paths find the bright surroundings of a small light
/// (a ceiling right above it) far more often than the cosine lobe alone
/// does; the walls' indirect light is then far less noisy.
///
/// `repr(C)`, axis first: naga gives a struct with a `Vec3` the vector's
/// 16-byte alignment, and a [`crate::bsdf::Scatter`] held across a branch
/// keeps this one as a member.
#[repr(C)]
#[derive(Copy, Clone, Debug)]
pub struct GlowLobe {
    axis: Vec3,
    /// Inner edge `e`, in `1 - cos`.
    scale: f32,
    /// Largest `x` sampled.
    reach: f32,
    /// `ln(reach / scale)`: the normalisation.
    log_ratio: f32,
}

impl GlowLobe {
    /// A placeholder for vertices that sample no glow lobe: never sampled,
    /// and its density is never evaluated (its mixture probability is 0).
    pub const UNUSED: Self = Self { axis: Vec3::Z, scale: 1.0, reach: 1.0, log_ratio: 1.0 };

    /// The lobe around `cone`, which must not be empty.
    pub fn new(cone: &LightCone) -> Self {
        let scale = cone.one_minus_cos_max.max(GLOW_MIN_SCALE);
        let reach = scale + GLOW_REACH;
        Self { axis: cone.axis, scale, reach, log_ratio: ln_f32(reach / scale) }
    }

    /// The lobe's axis: the direction of the light's centre.
    pub fn axis(&self) -> Vec3 {
        self.axis
    }

    /// The largest `1 - cos` of the angle to the axis the lobe reaches.
    pub fn reach(&self) -> f32 {
        self.reach
    }

    /// `(cos, sin)` of the angle to the axis of a direction of the lobe, `u1`
    /// in [0, 1); the lobe is symmetric about its axis. The density of `x =
    /// 1 - cos` on [e, reach] is `1 / (x ln(reach / e))`, whose inverse CDF
    /// is `x = e exp(u1 ln(reach / e))`.
    pub fn polar(&self, u1: f32) -> (f32, f32) {
        let x = (self.scale * exp_f32(u1 * self.log_ratio)).min(self.reach);
        (1.0 - x, (x * (2.0 - x)).max(0.0).sqrt())
    }

    /// A direction of the lobe, `u1`, `u2` in [0, 1).
    pub fn sample(&self, u1: f32, u2: f32) -> Vec3 {
        let (cos_theta, sin_theta) = self.polar(u1);
        about_axis(self.axis, cos_theta, sin_theta, u2)
    }

    /// Whether every direction of the lobe lies below the surface of unit
    /// normal `n` (the light is far below its horizon): sampling it would
    /// only end paths.
    pub fn below_horizon(&self, n: Vec3) -> bool {
        // The lobe is the cap of half angle t about the axis, 1 - cos t =
        // reach; all below when the axis is more than t below the horizon.
        self.reach < 1.0 && n.dot(self.axis) < -(self.reach * (2.0 - self.reach)).sqrt()
    }

    /// Solid-angle density of [`GlowLobe::sample`] at unit `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        // 1 - cos as half the squared chord: no cancellation near the axis.
        let chord = dir - self.axis;
        let x = 0.5 * chord.dot(chord);
        if x <= self.reach && x >= self.scale { 1.0 / (2.0 * PI * self.log_ratio * x) } else { 0.0 }
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

    /// The glow lobe of a light of sin(alpha) `sin_alpha` seen from 3 units.
    fn glow(sin_alpha: f32) -> (GlowLobe, Vec3) {
        let light = SphereLight::new(Vec3::new(0.4, -2.0, 1.0), 3.0 * sin_alpha, Vec3::ONE);
        let p = light.center + Vec3::new(2.0, 1.0, -2.0).normalize() * 3.0;
        let cone = light_cone(&light, p);
        (GlowLobe::new(&cone), cone.axis)
    }

    #[test]
    fn glow_pdf_integrates_to_one() {
        // The density depends on x = 1 - cos only, and d(solid angle) =
        // 2 pi dx: a midpoint sum over x in [0, 2] (log-spaced cells near
        // the axis, where it peaks), evaluated through `pdf` on directions.
        for sin_alpha in [1e-4f32, 0.05, 0.3, 0.9] {
            let (lobe, axis) = glow(sin_alpha);
            let (t, _) = crate::sampling::orthonormal_basis(axis);
            let cells = 200_000;
            let x_at = |i: f64| 1e-9f64 * (2.0f64 / 1e-9).powf(i / cells as f64);
            let mut total = 2.0 * PI as f64 * lobe.pdf(axis) as f64 * x_at(0.0);
            for i in 0..cells {
                let (x0, x1) = (x_at(i as f64), x_at(i as f64 + 1.0));
                let x = 0.5 * (x0 + x1);
                let sin = (x * (2.0 - x)).sqrt();
                let dir = (t.as_dvec3() * sin + axis.as_dvec3() * (1.0 - x)).as_vec3();
                total += 2.0 * PI as f64 * lobe.pdf(dir) as f64 * (x1 - x0);
            }
            assert!((total - 1.0).abs() < 2e-3, "sin(alpha) {sin_alpha}: integral {total}");
        }
    }

    #[test]
    fn glow_samples_follow_its_pdf() {
        // Kolmogorov-Smirnov on x = 1 - cos against the lobe's CDF
        // ln(x / e) / ln(reach / e) on [e, reach]; 1.95 / sqrt(n) is the 0.001
        // level. Every sample is a unit vector with a positive density.
        for (sin_alpha, seed) in [(1e-3f32, 1), (0.09, 2), (0.5, 3)] {
            let (lobe, axis) = glow(sin_alpha);
            let mut rng = Rng::new(seed, 0, 0, 0, 0);
            let n = 20_000;
            let mut xs: Vec<f64> = (0..n)
                .map(|_| {
                    let d = lobe.sample(rng.next_f32(), rng.next_f32());
                    assert!((d.length() - 1.0).abs() < 1e-5 && lobe.pdf(d) > 0.0);
                    let c = d.as_dvec3() - axis.as_dvec3();
                    0.5 * c.dot(c)
                })
                .collect();
            xs.sort_by(f64::total_cmp);
            let (e, reach) = (lobe.scale as f64, lobe.reach as f64);
            let cdf = |x: f64| (x / e).ln().max(0.0) / (reach / e).ln();
            let d = xs
                .iter()
                .enumerate()
                .map(|(i, &x)| (cdf(x) - i as f64 / n as f64).abs().max((cdf(x) - (i + 1) as f64 / n as f64).abs()))
                .fold(0.0, f64::max);
            assert!(d < 1.95 / (n as f64).sqrt(), "sin(alpha) {sin_alpha}: KS distance {d}");
        }
    }

    #[test]
    fn glow_is_below_the_horizon_only_when_all_of_it_is() {
        let (lobe, axis) = glow(0.09);
        let (t, _) = crate::sampling::orthonormal_basis(axis);
        // The lobe's edge is t_r = acos(1 - reach) from the axis: a normal
        // tilted 90 + t_r degrees away just puts the whole lobe below.
        let edge = (1.0 - lobe.reach).acos();
        let normal = |tilt: f32| t * tilt.sin() + axis * tilt.cos();
        assert!(!lobe.below_horizon(axis) && !lobe.below_horizon(t));
        assert!(!lobe.below_horizon(normal(PI / 2.0 + edge - 1e-3)));
        assert!(lobe.below_horizon(normal(PI / 2.0 + edge + 1e-3)) && lobe.below_horizon(-axis));
        // A point next to a large light: the lobe reaches past 90 degrees.
        let (near, axis) = glow(0.999);
        assert!(near.reach > 1.0 && !near.below_horizon(-axis));
    }

    /// A light of sin(half angle) `sin_alpha` at distance 3 whose axis is
    /// `tilt` radians from the normal `n` returned with its cone.
    fn tilted_cone(sin_alpha: f32, tilt: f32) -> (LightCone, Vec3) {
        let p = Vec3::new(0.3, -0.2, 0.5);
        let n = Vec3::new(0.2, 0.9, -0.3).normalize();
        let (t, _) = crate::sampling::orthonormal_basis(n);
        let axis = n * tilt.cos() + t * tilt.sin();
        let light = SphereLight::new(p + axis * 3.0, 3.0 * sin_alpha, Vec3::ONE);
        (light_cone(&light, p), n)
    }

    #[test]
    fn the_horizon_test_is_the_cones_edge_against_the_tangent_plane() {
        // Half angle asin(0.5) = 30 degrees: above the horizon up to a tilt
        // of 60 degrees, however the normal is turned.
        let deg = PI / 180.0;
        assert!(tilted_cone(0.5, 0.0).0.above_horizon(tilted_cone(0.5, 0.0).1));
        let (inside, n) = tilted_cone(0.5, 59.9 * deg);
        assert!(inside.above_horizon(n));
        let (across, n) = tilted_cone(0.5, 60.1 * deg);
        assert!(!across.above_horizon(n));
        let (below, n) = tilted_cone(0.5, 120.0 * deg);
        assert!(!below.above_horizon(n) && below.above_horizon(-n));
        let light = SphereLight::new(Vec3::ZERO, 1.0, Vec3::ONE);
        assert!(!light_cone(&light, Vec3::new(0.5, 0.0, 0.0)).above_horizon(Vec3::X));
    }

    /// NEE's control variate rests on two facts of the cone. The cone's
    /// signed cosine to the normal integrates to `projected_over_pi` (times
    /// pi) at every tilt, across the horizon too: a 256 x 256 midpoint grid
    /// over the uniform sampler's square, exact for this integrand (linear
    /// in the cosine of the polar angle, which the sampler takes linearly
    /// from `u1`; the turn's midpoint sums of sine and cosine vanish), to
    /// 1e-5 of `sin^2(half angle)`. And its weight is 1 wholly above the
    /// horizon, 0 wholly below, 1/2 with the axis on it, and rises between.
    #[test]
    fn the_signed_cosine_integrates_to_projected_over_pi_and_the_weight_follows_the_horizon() {
        let deg = PI / 180.0;
        for sin_alpha in [0.05f32, 0.5, 0.95] {
            let edge = 90.0 - sin_alpha.asin() / deg;
            let mut last_weight = 2.0;
            let mut tilts = [0.0, 0.5 * edge, edge - 0.1, 80.0, 89.0, 90.0, 91.0, 100.0, 150.0, 180.0 - edge + 0.1];
            tilts.sort_by(f32::total_cmp);
            for tilt in tilts {
                let (cone, n) = tilted_cone(sin_alpha, tilt * deg);
                let m = 256;
                let mut sum = 0.0f64;
                for i in 0..m {
                    for j in 0..m {
                        let (u1, u2) = ((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                        sum += n.dot(cone.sample(u1, u2).0) as f64;
                    }
                }
                let integral_over_pi = sum / (m * m) as f64 / cone.pdf() as f64 / std::f64::consts::PI;
                let expected = cone.projected_over_pi(n) as f64;
                assert!(
                    (integral_over_pi - expected).abs() < 1e-5 * cone.sin2_max as f64,
                    "sin {sin_alpha}, tilt {tilt}: {integral_over_pi} against {expected}"
                );
                let w = cone.control_weight(n);
                if cone.above_horizon(n) {
                    assert_eq!(w, 1.0, "sin {sin_alpha}, tilt {tilt}");
                } else if cone.above_horizon(-n) {
                    assert_eq!(w, 0.0, "sin {sin_alpha}, tilt {tilt}");
                } else {
                    assert!(w > 0.0 && w < 1.0, "sin {sin_alpha}, tilt {tilt}: {w}");
                }
                if tilt == 90.0 {
                    assert!((w - 0.5).abs() < 1e-3, "sin {sin_alpha}: {w} with the axis on the horizon");
                }
                assert!(w <= last_weight, "sin {sin_alpha}: the weight rises with the tilt at {tilt}");
                last_weight = w;
            }
        }
    }

    /// Case: the projected-solid-angle samples of cones of sin(a) = 0.05,
    /// 0.5 and 0.95 at tilts from the zenith to the horizon, binned as in
    /// the cone's chi-square test (20 bands x 40 sectors, 400,000 samples);
    /// each cell expects its share of the integral of cos to the normal,
    /// summed on a 6 x 6 midpoint grid in (1 - cos, turn), which is exact
    /// to far below the test's resolution (the integrand is smooth there).
    /// `projected_over_pi` is that integral over pi, checked to 1e-5.
    #[test]
    fn projected_samples_follow_the_cosine_in_the_cap() {
        use crate::test_support::chi2::chi2_test;
        use crate::test_support::{cap_histogram, chi2_alpha};
        let n_samples = 400_000;
        let (nt, np, sub) = (20usize, 40usize, 6usize);
        for (sin_alpha, tilt_fraction) in [(0.05f32, 0.0f32), (0.05, 0.999), (0.5, 0.5), (0.5, 1.0), (0.95, 0.9)] {
            // Tilt as a fraction of the largest that keeps the cone above the horizon.
            let tilt = tilt_fraction * (PI / 2.0 - sin_alpha.asin());
            let (cone, normal) = tilted_cone(sin_alpha, tilt);
            assert!(cone.above_horizon(normal) || tilt_fraction == 1.0);
            let observed = cap_histogram(n_samples, cone.axis, cone.one_minus_cos_max as f64, (nt, np), |rng| {
                let (dir, _) = cone.sample_projected(normal, rng.next_f32(), rng.next_f32());
                assert!(normal.dot(dir) >= -1e-6, "a direction below the horizon");
                dir
            });
            assert_eq!(observed[nt * np], 0.0, "sin(a) = {sin_alpha}: samples outside the cap");
            let (tb, bb) = crate::sampling::orthonormal_basis(cone.axis);
            let (axis, tb, bb, nd) = (cone.axis.as_dvec3(), tb.as_dvec3(), bb.as_dvec3(), normal.as_dvec3());
            let max_x = cone.one_minus_cos_max as f64;
            let (dx, dphi) = (max_x / (nt * sub) as f64, 2.0 * std::f64::consts::PI / (np * sub) as f64);
            let mut expected = vec![0.0; nt * np];
            for i in 0..nt * sub {
                let x = (i as f64 + 0.5) * dx;
                let sin = (x * (2.0 - x)).sqrt();
                for j in 0..np * sub {
                    let phi = (j as f64 + 0.5) * dphi;
                    let d = tb * (sin * phi.cos()) + bb * (sin * phi.sin()) + axis * (1.0 - x);
                    expected[(i / sub) * np + j / sub] += nd.dot(d).max(0.0) * dx * dphi;
                }
            }
            let integral: f64 = expected.iter().sum();
            let over_pi = cone.projected_over_pi(normal) as f64;
            assert!((integral / std::f64::consts::PI / over_pi - 1.0).abs() < 1e-5, "{integral} vs {over_pi}");
            let expected: Vec<f64> = expected.iter().map(|e| e / integral * n_samples as f64).collect();
            let r = chi2_test(&observed[..nt * np], &expected);
            assert!(r.p_value >= chi2_alpha(), "sin(a) = {sin_alpha}: chi2 {:.1}, p = {:.2e}", r.chi2, r.p_value);
        }
    }

    #[test]
    fn projected_samples_hit_the_light_at_the_returned_distance() {
        // As for uniform samples, down to a light of sin(a) = 1e-4, whose
        // distance needs 1 - cos from the chord.
        for (sin_alpha, seed) in [(1e-4f32, 1), (0.01, 2), (0.5, 3), (0.99, 4)] {
            let (cone, n) = tilted_cone(sin_alpha, 0.5 * (PI / 2.0 - sin_alpha.asin()));
            let p = Vec3::new(0.3, -0.2, 0.5);
            let center = p + cone.axis * cone.dist;
            let mut rng = Rng::new(seed, 0, 0, 0, 0);
            for _ in 0..2000 {
                let (dir, dist) = cone.sample_projected(n, rng.next_f32(), rng.next_f32());
                assert!((dir.length() - 1.0).abs() < 1e-5);
                let t = intersect_sphere(center, cone.dist * sin_alpha, &Ray { origin: p, dir }, 0.0, f32::MAX);
                if t == f32::MAX {
                    assert!(sin_alpha > 0.9, "sample missed a light of sin(alpha) {sin_alpha}");
                    continue;
                }
                assert!((t - dist).abs() <= 2e-3 * cone.dist, "sin {sin_alpha}: t {t} vs dist {dist}");
            }
        }
    }

    #[test]
    fn points_inside_the_light_see_an_empty_cone() {
        let light = SphereLight::new(Vec3::ZERO, 1.0, Vec3::ONE);
        assert!(light_cone(&light, Vec3::new(0.5, 0.0, 0.0)).is_empty());
        assert_eq!(light_cone(&light, Vec3::new(0.5, 0.0, 0.0)).pdf(), 0.0);
        assert!(!light_cone(&light, Vec3::new(1.5, 0.0, 0.0)).is_empty());
    }

    /// Case: 400,000 light-cone directions for lights of sin(a) = 0.05, 0.5
    /// and 0.95, binned in their own frame in 20 bands of equal `1 - cos` by
    /// 40 sectors (equal solid angles of the cap, so each cell expects the
    /// same count), pass a chi-square test, and none falls outside the cap.
    #[test]
    fn cone_samples_pass_chi_square_and_stay_in_the_cap() {
        use crate::test_support::chi2::chi2_test;
        use crate::test_support::{cap_histogram, chi2_alpha};
        let n = 400_000;
        for sin_sigma in [0.05f32, 0.5, 0.95] {
            let l = SphereLight::new(Vec3::new(0.2, 0.1, 0.9).normalize() * 2.0, 2.0 * sin_sigma, Vec3::ONE);
            let cone = light_cone(&l, Vec3::ZERO);
            let (nt, np) = (20usize, 40usize);
            let observed = cap_histogram(n, cone.axis, cone.one_minus_cos_max as f64, (nt, np), |rng| {
                cone.sample(rng.next_f32(), rng.next_f32()).0
            });
            assert_eq!(observed[nt * np], 0.0, "sin(a) = {sin_sigma}: samples outside the cap");
            let r = chi2_test(&observed[..nt * np], &vec![n as f64 / (nt * np) as f64; nt * np]);
            assert!(r.p_value >= chi2_alpha(), "sin(a) = {sin_sigma}: chi2 {:.1}, p = {:.2e}", r.chi2, r.p_value);
        }
    }

    /// Case: 400,000 glow-lobe directions for lights of sin(a) = 0.5 and 0.2
    /// (lobes that peak 3 and 8 times above their rims), binned in the
    /// lobe's frame over `1 - cos` in [0, reach] in 20 x 20 cells, pass a
    /// chi-square test against each band's integral of the lobe's own pdf
    /// (a midpoint sum of 1000 steps), and none falls outside the lobe.
    #[test]
    fn glow_samples_pass_chi_square_against_their_pdf() {
        use crate::test_support::chi2::chi2_test;
        use crate::test_support::{cap_histogram, chi2_alpha};
        use std::f64::consts::PI;
        let n = 400_000;
        for sin_sigma in [0.5f32, 0.2] {
            let l = SphereLight::new(Vec3::new(0.2, 0.1, 0.9).normalize() * 2.0, 2.0 * sin_sigma, Vec3::ONE);
            let lobe = GlowLobe::new(&light_cone(&l, Vec3::ZERO));
            let (nt, np, sub) = (20usize, 20usize, 1000usize);
            let (reach, axis) = (lobe.reach() as f64, lobe.axis().as_dvec3());
            let side = crate::sampling::orthonormal_basis(lobe.axis()).0.as_dvec3();
            let band_mass = |band: usize| {
                (0..sub)
                    .map(|i| {
                        let x = reach * (band as f64 + (i as f64 + 0.5) / sub as f64) / nt as f64;
                        let dir = side * (x * (2.0 - x)).sqrt() + axis * (1.0 - x);
                        2.0 * PI * lobe.pdf(dir.as_vec3()) as f64 * reach / (nt * sub) as f64
                    })
                    .sum::<f64>()
            };
            let expected: Vec<f64> =
                (0..nt).flat_map(|t| std::iter::repeat_n(n as f64 * band_mass(t) / np as f64, np)).collect();
            let observed =
                cap_histogram(n, lobe.axis(), reach, (nt, np), |rng| lobe.sample(rng.next_f32(), rng.next_f32()));
            assert_eq!(observed[nt * np], 0.0, "sin(a) = {sin_sigma}: samples outside the lobe");
            let r = chi2_test(&observed[..nt * np], &expected);
            assert!(r.p_value >= chi2_alpha(), "sin(a) = {sin_sigma}: chi2 {:.1}, p = {:.2e}", r.chi2, r.p_value);
        }
    }
}
