//! Diffuse spheres and the numerically careful ray/sphere intersection.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::ray::Ray;

/// A Lambertian sphere, as the kernel reads it from its geometry block.
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
        Self { center, radius, albedo, _pad: 0.0 }
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
#[inline]
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

/// Whether the segment from `ray.origin` to `ray.at(t_max)` crosses the
/// sphere's surface, for a shadow ray (`t_max` > 0, `ray.dir` of unit
/// length): the answer of `intersect_sphere(.., 0.0, t_max) < t_max` for
/// about two thirds of its arithmetic, since a shadow ray needs no root.
/// The segment crosses the surface where its point nearest the centre lies
/// inside and its two ends do not both lie inside (the sphere is convex).
/// The nearest point is the foot of the perpendicular (`t = -f.d`, where
/// `intersect_sphere`'s discriminant is measured, with its precision for far
/// and tiny spheres) clamped to the segment. A foot before the origin leaves
/// the origin itself, which a ray spawned off the outside of the surface
/// holds outside by its offset; a foot past the end leaves the end point.
/// The ends are tested only for a segment that starts inside (a room that
/// is a sphere), from `|f + t d|^2 = |f|^2 + t (t - 2 foot)`.
#[inline]
pub fn sphere_meets_segment(center: Vec3, radius: f32, ray: &Ray, t_max: f32) -> bool {
    let f = ray.origin - center;
    let r2 = radius * radius;
    // Selects, not `clamp`: a NaN direction gives a NaN foot, whose
    // comparisons fail, and `clamp` would panic on it in debug builds.
    let foot = -f.dot(ray.dir);
    let t = if foot > 0.0 { foot } else { 0.0 };
    let t = if t < t_max { t } else { t_max };
    let nearest = f + ray.dir * t;
    let c = f.dot(f) - r2;
    let both_inside = c < 0.0 && c + t_max * (t_max - 2.0 * foot) < 0.0;
    nearest.dot(nearest) < r2 && !both_inside
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The nearest root > 0 computed in f64, as the exact answer. The
    /// direction is renormalised in f64: an f32 unit vector is only unit to
    /// within an ulp, which moves a root 1e4 away by ~1e-5 relative.
    fn t_f64(center: Vec3, radius: f32, o: Vec3, d: Vec3) -> Option<f64> {
        let (c, o, d) = (center.as_dvec3(), o.as_dvec3(), d.as_dvec3().normalize());
        let f = o - c;
        let b = f.dot(d);
        let disc = b * b - (f.dot(f) - (radius as f64).powi(2));
        if disc < 0.0 {
            return None;
        }
        let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
        [t0, t1].into_iter().find(|&t| t > 0.0)
    }

    fn ray(o: Vec3, d: Vec3) -> Ray {
        Ray { origin: o, dir: d.normalize() }
    }

    #[test]
    fn far_sphere_hit_matches_f64() {
        // Case: a unit sphere 1e4 away; b^2 - c cancels there in the naive form.
        let c = Vec3::new(0.0, 0.0, -1.0e4);
        let r = ray(Vec3::ZERO, Vec3::new(0.0, 0.5e-4, -1.0));
        let t = intersect_sphere(c, 1.0, &r, 0.0, f32::MAX);
        let exact = t_f64(c, 1.0, r.origin, r.dir).unwrap();
        assert!(((t as f64 - exact) / exact).abs() < 1e-6, "t = {t}, exact {exact}");
    }

    #[test]
    fn tiny_sphere_hit_matches_f64() {
        // Case: radius 1e-3 at distance 1, hit off-centre.
        let c = Vec3::new(0.3, -0.2, -1.0);
        let d = (c + Vec3::new(0.0, 0.7e-3, 0.0)).normalize();
        let r = ray(Vec3::ZERO, d);
        let t = intersect_sphere(c, 1e-3, &r, 0.0, f32::MAX);
        let exact = t_f64(c, 1e-3, r.origin, r.dir).unwrap();
        assert!(((t as f64 - exact) / exact).abs() < 1e-6, "t = {t}, exact {exact}");
    }

    #[test]
    fn tangent_rays_hit_inside_and_miss_outside() {
        // Case: rays passing the centre at radius (1 -+ 1e-4): the first
        // hits, the second misses, at distance 100 from a sphere of radius 1.
        let c = Vec3::new(0.0, 0.0, -100.0);
        let inside = ray(Vec3::new(0.0, 1.0 - 1e-4, 0.0), -Vec3::Z);
        let outside = ray(Vec3::new(0.0, 1.0 + 1e-4, 0.0), -Vec3::Z);
        assert!(intersect_sphere(c, 1.0, &inside, 0.0, f32::MAX) < f32::MAX);
        assert_eq!(intersect_sphere(c, 1.0, &outside, 0.0, f32::MAX), f32::MAX);
    }

    #[test]
    fn origin_inside_hits_the_far_side() {
        // Case: origin at the centre: the only positive root is the radius.
        let c = Vec3::new(1.0, 2.0, 3.0);
        let r = ray(c, Vec3::new(1.0, 1.0, 0.0));
        let t = intersect_sphere(c, 0.5, &r, 0.0, f32::MAX);
        assert!((t - 0.5).abs() < 1e-6, "t = {t}");
    }

    #[test]
    fn origin_on_surface_inward_finds_the_chord() {
        // Case: from a surface point straight through the centre: chord 2r.
        let c = Vec3::new(0.0, 5.0, 0.0);
        let r = ray(Vec3::new(0.0, 5.0 + 2.0, 0.0), -Vec3::Y);
        let t = intersect_sphere(c, 2.0, &r, 1e-4, f32::MAX);
        assert!((t - 4.0).abs() < 1e-5, "t = {t}");
    }

    #[test]
    fn miss_returns_t_max() {
        let r = ray(Vec3::ZERO, Vec3::X);
        assert_eq!(intersect_sphere(Vec3::new(0.0, 5.0, 0.0), 1.0, &r, 0.0, 7.0), 7.0);
    }

    #[test]
    fn hit_point_is_reprojected_onto_the_surface() {
        let c = Vec3::new(3.0, -2.0, 1.0);
        let r = ray(Vec3::new(3.0, -2.0, 10.0), -Vec3::Z);
        let t = intersect_sphere(c, 0.75, &r, 0.0, f32::MAX);
        let (p, n) = sphere_hit_point(c, 0.75, &r, t);
        assert!(((p - c).length() - 0.75).abs() < 1e-6);
        assert!((n - Vec3::Z).length() < 1e-6);
    }

    /// Case, swept: 100,000 random rays per hard configuration (a sphere
    /// 1e4 away, one of radius 1e-3, rays aimed at 0.99999 r, origins on the
    /// surface and inside). The hit point `o + t d` (t from f32, the rest in
    /// f64) lies on the true sphere within 8 units of the f32 resolution of
    /// the coordinates involved, eps x max(|o|, |c| + r): an f32 `t` cannot
    /// do better than about one. Every ray aims inside, so a miss fails too.
    #[test]
    fn hit_points_stay_on_the_sphere_in_hard_configurations() {
        use crate::rng::Rng;
        use crate::test_support::random_dir;
        type Origin = fn(&mut Rng, Vec3, f32) -> Vec3;
        let outside: Origin = |rng, c, r| c + random_dir(rng) * (r * 5.0);
        let far: Origin = |rng, c, _| c + random_dir(rng) * 1e4;
        let on_surface: Origin = |rng, c, r| c + random_dir(rng) * r;
        let inside: Origin = |rng, c, r| c + random_dir(rng) * (r * 0.5 * rng.next_f32());
        // (name, centre, radius, origin, aim point's offset as a fraction of r)
        let cases: [(&str, Vec3, f32, Origin, f32); 5] = [
            ("far sphere", Vec3::new(3.0, -2.0, 1.0), 1.0, far, 0.9),
            ("tiny sphere", Vec3::new(0.2, 0.1, -0.4), 1e-3, outside, 0.9),
            ("tangent rays", Vec3::new(1.0, 1.0, 1.0), 2.0, outside, 0.99999),
            ("origin on the surface", Vec3::new(-1.0, 0.5, 2.0), 0.7, on_surface, 0.3),
            ("origin inside", Vec3::new(0.0, 3.0, 0.0), 1.5, inside, 0.3),
        ];
        for (name, center, radius, origin, aim) in cases {
            let mut rng = Rng::new(11, 22, 33, 44, 55);
            let mut worst = 0.0f64;
            for _ in 0..100_000 {
                let o = origin(&mut rng, center, radius);
                let to_c = (center - o).normalize_or(Vec3::X);
                let (tb, _) = crate::sampling::orthonormal_basis(to_c);
                let target = center + tb * (aim * radius * rng.next_f32());
                let Some(dir) = (target - o).try_normalize() else { continue };
                let ray = Ray { origin: o, dir };
                let t = intersect_sphere(center, radius, &ray, 1e-4 * radius, f32::MAX);
                assert!(t < f32::MAX, "{name}: a ray aimed inside the sphere missed it");
                let p = ray.origin.as_dvec3() + ray.dir.as_dvec3() * t as f64;
                let resolution = f32::EPSILON as f64 * (o.length().max(center.length() + radius)) as f64;
                worst = worst.max(((p - center.as_dvec3()).length() - radius as f64).abs() / resolution);
            }
            assert!(worst <= 8.0, "{name}: hit point {worst:.2} f32 ulps off the sphere");
        }
    }

    /// Case: self-intersection at scales 1e-3 to 1e4. From hit points on a
    /// sphere seen from outside, rays spawned at the error-bounded offset
    /// never re-hit it, and shadow rays to points above the surface are
    /// never blocked by it; from inside (a spherical room), a spawned ray
    /// finds the far side (within 1e-4 r of the f64 root), not its start,
    /// and a shadow ray to a point inside is not blocked.
    #[test]
    fn spawned_rays_never_rehit_their_sphere_at_any_scale() {
        use crate::ray::offset_origin;
        use crate::rng::Rng;
        use crate::sampling::cosine_hemisphere;
        use crate::test_support::{SCALES, random_dir};
        for s in SCALES {
            let mut rng = Rng::new(s.to_bits(), 7, 0, 0, 0);
            let center = Vec3::new(0.3, -0.7, 0.2) * s;
            let magnitude = center.abs() + Vec3::splat(s);
            for i in 0..20_000 {
                let o = center + random_dir(&mut rng) * (3.0 * s);
                let ray = Ray { origin: o, dir: (center + random_dir(&mut rng) * (0.5 * s) - o).normalize() };
                let t = intersect_sphere(center, s, &ray, 0.0, f32::MAX);
                if t < f32::MAX {
                    let (p, n) = sphere_hit_point(center, s, &ray, t);
                    let origin = offset_origin(p, n, magnitude);
                    let refl = Ray { origin, dir: cosine_hemisphere(n, rng.next_f32(), rng.next_f32()) };
                    assert_eq!(intersect_sphere(center, s, &refl, 0.0, f32::MAX), f32::MAX, "scale {s}, ray {i}");
                    let target =
                        p + cosine_hemisphere(n, rng.next_f32(), rng.next_f32()) * (s * 2.0 * rng.next_f32().max(1e-3));
                    let to = target - origin;
                    let shadow = Ray { origin, dir: to.normalize() };
                    assert!(intersect_sphere(center, s, &shadow, 0.0, to.length()) >= to.length(), "scale {s}");
                    assert!(!sphere_meets_segment(center, s, &shadow, to.length()), "scale {s}: shadow segment");
                }
                let ray = Ray { origin: center + random_dir(&mut rng) * (0.5 * s), dir: random_dir(&mut rng) };
                let t = intersect_sphere(center, s, &ray, 0.0, f32::MAX);
                let (p, n_out) = sphere_hit_point(center, s, &ray, t);
                let origin = offset_origin(p, -n_out, magnitude);
                let d = cosine_hemisphere(-n_out, rng.next_f32(), rng.next_f32());
                let far = t_f64(center, s, origin, d).expect("a ray from inside hits the sphere");
                let t2 = intersect_sphere(center, s, &Ray { origin, dir: d }, 0.0, f32::MAX);
                assert!((t2 as f64 - far).abs() <= 1e-4 * s as f64, "scale {s}, inside ray {i}: {t2} against {far}");
                // A shadow ray from there to a point inside crosses nothing.
                let inside = Ray { origin, dir: d };
                assert!(!sphere_meets_segment(center, s, &inside, far as f32 * 0.5), "scale {s}, inside shadow {i}");
            }
        }
    }

    /// The shadow test against the closest-hit one: 200,000 random segments
    /// per scale, from origins inside and outside the sphere, aimed at,
    /// past and beside it, ending before, inside and beyond it, get the
    /// answer of `intersect_sphere(..) < t_max` and of f64, except where
    /// the segment's nearest point or an end lies within 1e-5 of the radius
    /// of the surface (f64), where either answer is a rounding.
    #[test]
    fn segment_test_agrees_with_the_closest_hit_test() {
        use crate::rng::Rng;
        use crate::test_support::{SCALES, random_dir};
        for s in SCALES {
            let mut rng = Rng::new(s.to_bits(), 3, 1, 4, 1);
            let center = Vec3::new(-0.4, 0.9, 0.6) * s;
            let (mut blocked, mut both_inside, mut near) = (0, 0, 0);
            for i in 0..200_000 {
                let o = center + random_dir(&mut rng) * (s * 4.0 * rng.next_f32());
                let aim = center + random_dir(&mut rng) * (s * 1.5 * rng.next_f32());
                let Some(dir) = (aim - o).try_normalize() else { continue };
                let t_max = (aim - o).length() * 3.0 * rng.next_f32();
                if t_max <= 0.0 {
                    continue;
                }
                let ray = Ray { origin: o, dir };
                let fast = sphere_meets_segment(center, s, &ray, t_max);
                // f64: the segment's nearest point to the centre.
                let (c, o64, d) = (center.as_dvec3(), o.as_dvec3(), dir.as_dvec3());
                let foot = (c - o64).dot(d).clamp(0.0, t_max as f64);
                let gap = |t: f64| ((o64 + d * t - c).length() - s as f64) / s as f64;
                let (nearest, start, end) = (gap(foot), gap(0.0), gap(t_max as f64));
                if nearest.abs() < 1e-5 || start.abs() < 1e-5 || end.abs() < 1e-5 {
                    near += 1;
                    continue;
                }
                let crosses = nearest < 0.0 && (start > 0.0 || end > 0.0);
                assert_eq!(fast, crosses, "scale {s}, segment {i}: against f64");
                assert_eq!(fast, intersect_sphere(center, s, &ray, 0.0, t_max) < t_max, "scale {s}, segment {i}");
                blocked += fast as u32;
                both_inside += (start < 0.0 && end < 0.0) as u32;
            }
            // Both answers were exercised, and the rounding band was thin.
            assert!((40_000..160_000).contains(&blocked), "scale {s}: {blocked} blocked");
            assert!(both_inside > 10_000, "scale {s}: {both_inside} segments wholly inside");
            assert!(near < 100, "scale {s}: {near} segments within 1e-5 of the surface");
        }
    }
}
