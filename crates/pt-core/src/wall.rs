//! Walls: two-sided Lambertian parallelograms, and ray/wall intersection.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::light::SphereLight;
use crate::ray::Ray;

/// Slack of the inside test in parametric units (fractions of an edge).
///
/// Walls that meet at an edge each extend 1e-5 of their size past it, so a
/// ray aimed exactly at a seam hits at least one of them whatever the
/// rounding: the room is watertight. 1e-5 of a wall is far below a pixel.
pub const EDGE_SLACK: f32 = 1e-5;

/// A planar parallelogram `corner + a * edge_u + b * edge_v`, a, b in [0, 1],
/// as the kernel reads it. Build it with [`Wall::new`], which derives the
/// normal and the coordinate vectors from the edges.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Wall {
    /// One corner, world space.
    pub corner: Vec3,
    /// Padding: a `Vec3` must start at a multiple of 16 bytes.
    pub _pad0: f32,
    /// First edge, from `corner`.
    pub edge_u: Vec3,
    /// Padding.
    pub _pad1: f32,
    /// Second edge, from `corner`.
    pub edge_v: Vec3,
    /// Padding.
    pub _pad2: f32,
    /// Unit normal, `edge_u x edge_v` normalised. Walls are two-sided: the
    /// integrator flips it toward the incoming ray.
    pub normal: Vec3,
    /// +1 or -1 when every other wall and sphere of the scene lies on that
    /// side of the wall's plane (along `normal`), else 0: the wall is then a
    /// face of the scene's convex hull, and no shadow ray between two points
    /// on that side can cross it. [`Wall::new`] sets 0 (nothing known);
    /// `Geometry::new` sets it from the whole scene.
    pub enclosure_side: f32,
    /// `edge_v x w` with `w = (edge_u x edge_v) / |edge_u x edge_v|^2`:
    /// `q . coord_u` is the coordinate `a` of a point `q` relative to
    /// `corner`. It equals `w . (q x edge_v)` (Shirley, "Ray Tracing: The
    /// Next Week", 6.4) by the scalar triple product, one dot product
    /// instead of a cross and a dot per test.
    pub coord_u: Vec3,
    /// Padding.
    pub _pad4: f32,
    /// `w x edge_u`: `q . coord_v` is the coordinate `b`.
    pub coord_v: Vec3,
    /// Padding.
    pub _pad5: f32,
    /// Diffuse reflectance per RGB channel, each in [0, 1].
    pub albedo: Vec3,
    /// Padding to a 16-byte multiple.
    pub _pad6: f32,
}

impl Wall {
    /// A wall from a corner, two edges and an albedo. The edges must not be
    /// parallel (the scene loader rejects zero-area walls before this).
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3, albedo: Vec3) -> Self {
        let n = edge_u.cross(edge_v);
        let n2 = n.dot(n);
        let (normal, w) = if n2 > 0.0 { (n / n2.sqrt(), n / n2) } else { (Vec3::ZERO, Vec3::ZERO) };
        let (coord_u, coord_v) = (edge_v.cross(w), w.cross(edge_u));
        Self { corner, edge_u, edge_v, normal, coord_u, coord_v, albedo, ..Self::default() }
    }

    /// Whether the wall can block no shadow ray toward `light`: all other
    /// geometry and the whole light lie on its [`Wall::enclosure_side`].
    /// Shadow rays start on surfaces and end on the light, and a segment
    /// between two points of a half-space stays in it.
    pub fn cannot_shadow(&self, light: &SphereLight) -> bool {
        // A side of 0 gives 0 >= radius: false, as the light's radius is > 0.
        self.enclosure_side * self.normal.dot(light.center - self.corner) >= light.radius
    }

    /// The axis (0 x, 1 y, 2 z) along which the wall's normal lies exactly
    /// (`normal` is `+-e_k`, and `coord_u` and `coord_v` have a zero
    /// component `k`, as [`Wall::new`] makes them for edges with a zero
    /// component `k`), or `None`: where it is `Some(k)`,
    /// [`intersect_wall_on_axis`] with `k` returns what [`intersect_wall`]
    /// returns.
    pub fn normal_axis(&self) -> Option<u32> {
        let (n, u, v) = (self.normal.to_array(), self.coord_u.to_array(), self.coord_v.to_array());
        (0..3u32).find(|&k| {
            let k = k as usize;
            (0..3).all(|c| if c == k { n[c].abs() == 1.0 } else { n[c] == 0.0 }) && u[k] == 0.0 && v[k] == 0.0
        })
    }

    /// Area of the parallelogram.
    pub fn area(&self) -> f32 {
        self.edge_u.cross(self.edge_v).length()
    }
}

/// The `t` in (`t_min`, `t_max`) where the ray meets the wall, or `t_max`
/// when it misses.
///
/// `t = n . (corner - o) / n . d`: subtracting the points before the dot
/// product keeps `t` accurate when the scene sits far from the origin.
#[inline]
pub fn intersect_wall(wall: &Wall, ray: &Ray, t_min: f32, t_max: f32) -> f32 {
    let denom = wall.normal.dot(ray.dir);
    // Parallel (or a degenerate wall, normal zero): no hit. A ray exactly in
    // the plane sees the wall edge-on, which has no area.
    if denom == 0.0 {
        return t_max;
    }
    let t = wall.normal.dot(wall.corner - ray.origin) / denom;
    if !(t > t_min && t < t_max) {
        return t_max;
    }
    let q = ray.at(t) - wall.corner;
    let a = q.dot(wall.coord_u);
    let b = q.dot(wall.coord_v);
    let lo = -EDGE_SLACK;
    let hi = 1.0 + EDGE_SLACK;
    if a >= lo && a <= hi && b >= lo && b <= hi { t } else { t_max }
}

/// Component `k` of `v`: x for 0, y for 1, z for 2.
#[inline(always)]
pub fn component(v: Vec3, k: u32) -> f32 {
    if k == 0 {
        v.x
    } else if k == 1 {
        v.y
    } else {
        v.z
    }
}

/// [`intersect_wall`] for a wall whose [`Wall::normal_axis`] is `k`, known
/// where the test is compiled: the same `t` from the same arithmetic with
/// the terms that multiply a zero left out. Of its 15 multiplies, 17
/// subtractions and additions and 1 division it keeps 6, 7 and 1.
///
/// With `n = +-e_k` the dot products `n . d` and `n . (corner - o)` are
/// `+-d_k` and `+-(corner_k - o_k)` exactly (adding a zero product changes
/// at most the sign of a zero), and their quotient is the same number
/// whatever the sign; `coord_u` and `coord_v` have a zero component `k`,
/// so `q . coord_u` is the sum of the other two products.
#[inline(always)]
pub fn intersect_wall_on_axis(wall: &Wall, k: u32, ray: &Ray, t_min: f32, t_max: f32) -> f32 {
    // The other two axes, in increasing order: the order in which the full
    // dot product adds their terms.
    let (i, j) = if k == 0 {
        (1, 2)
    } else if k == 1 {
        (0, 2)
    } else {
        (0, 1)
    };
    let denom = component(ray.dir, k);
    if denom == 0.0 {
        return t_max;
    }
    let t = (component(wall.corner, k) - component(ray.origin, k)) / denom;
    if !(t > t_min && t < t_max) {
        return t_max;
    }
    // `ray.at(t) - corner` on the two axes in the wall's plane.
    let qi = (component(ray.origin, i) + component(ray.dir, i) * t) - component(wall.corner, i);
    let qj = (component(ray.origin, j) + component(ray.dir, j) * t) - component(wall.corner, j);
    let a = qi * component(wall.coord_u, i) + qj * component(wall.coord_u, j);
    let b = qi * component(wall.coord_v, i) + qj * component(wall.coord_v, j);
    let lo = -EDGE_SLACK;
    let hi = 1.0 + EDGE_SLACK;
    if a >= lo && a <= hi && b >= lo && b <= hi { t } else { t_max }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floor() -> Wall {
        Wall::new(Vec3::new(-1.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -2.0), Vec3::splat(0.5))
    }

    #[test]
    fn derived_fields_are_exact_for_an_axis_aligned_wall() {
        let w = floor();
        assert_eq!(w.normal, Vec3::Y);
        assert_eq!((w.coord_u, w.coord_v), (Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.5)));
        assert_eq!(w.area(), 4.0);
        // The edges' far ends have coordinates 1.
        assert_eq!((w.edge_u.dot(w.coord_u), w.edge_u.dot(w.coord_v)), (1.0, 0.0));
        assert_eq!((w.edge_v.dot(w.coord_u), w.edge_v.dot(w.coord_v)), (0.0, 1.0));
    }

    #[test]
    fn normal_axis_is_the_axis_of_an_exactly_aligned_normal() {
        let axes: Vec<_> = crate::test_support::closed_room().iter().map(Wall::normal_axis).collect();
        // Floor, ceiling, back, left, right, front.
        assert_eq!(axes, [Some(1), Some(1), Some(2), Some(0), Some(0), Some(2)]);
        // Edges that are not on the axes: a wall in the plane y = 0 whose
        // normal is e_y, but a tilted panel has none.
        let skew_in_plane = Wall::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0), Vec3::ONE);
        assert_eq!(skew_in_plane.normal_axis(), Some(1));
        let tilted = Wall::new(Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.2, 0.6), Vec3::ONE);
        assert_eq!(tilted.normal_axis(), None);
        assert_eq!(Wall::new(Vec3::ZERO, Vec3::X, Vec3::X, Vec3::ONE).normal_axis(), None, "degenerate");
    }

    #[test]
    fn the_test_on_the_normals_axis_returns_the_general_tests_t_bit_for_bit() {
        // Random rays from inside and around a room of aligned walls (and
        // one in the plane y = 0.5 with skew edges), grazing ones included.
        let mut walls = crate::test_support::closed_room().to_vec();
        walls.push(Wall::new(
            Vec3::new(0.0, 0.5, -0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(-0.5, 0.0, 0.5),
            Vec3::ONE,
        ));
        let mut rng = crate::rng::Rng::new(1, 2, 3, 4, 5);
        let (mut hits, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let mut u = || rng.next_f32() * 2.0 - 1.0;
            let origin = Vec3::new(1.5 * u(), 1.0 + 1.5 * u(), 1.5 * u());
            let mut dir = Vec3::new(u(), u(), u());
            // A quarter of the rays nearly parallel to an axis plane.
            if u() < -0.5 {
                dir.y *= 1e-4;
            }
            let Some(dir) = dir.try_normalize() else { continue };
            let ray = Ray { origin, dir };
            for w in &walls {
                let k = w.normal_axis().unwrap();
                let (general, on_axis) =
                    (intersect_wall(w, &ray, 0.0, 10.0), intersect_wall_on_axis(w, k, &ray, 0.0, 10.0));
                assert_eq!(general.to_bits(), on_axis.to_bits(), "{ray:?} against {w:?}");
                hits += (general < 10.0) as u32;
                checked += 1;
            }
        }
        // About one wall in ten is hit (each ray meets one or two of seven).
        assert!(hits > checked / 20, "only {hits} hits in {checked} tests");
    }

    #[test]
    fn straight_hit_inside_and_miss_outside() {
        let w = floor();
        let down = |x, z| Ray { origin: Vec3::new(x, 1.0, z), dir: -Vec3::Y };
        assert_eq!(intersect_wall(&w, &down(0.3, -0.2), 0.0, f32::MAX), 1.0);
        assert_eq!(intersect_wall(&w, &down(1.01, 0.0), 0.0, f32::MAX), f32::MAX);
        assert_eq!(intersect_wall(&w, &down(0.0, -1.01), 0.0, f32::MAX), f32::MAX);
    }

    #[test]
    fn grazing_hit_lands_on_the_plane() {
        // Case: a ray 1e-4 rad above the plane direction; t is 1e4 times the
        // height, so a small error in n.d would move the hit far.
        let w = floor();
        let angle = 1e-4f32;
        let r = Ray { origin: Vec3::new(-0.9, 1e-4, 0.0), dir: Vec3::new(angle.cos(), -angle.sin(), 0.0) };
        let t = intersect_wall(&w, &r, 0.0, f32::MAX);
        let exact = 1e-4f64 / (1e-4f64).sin();
        assert!(((t as f64 - exact) / exact).abs() < 1e-5, "t = {t}, exact {exact}");
        assert!(r.at(t).y.abs() < 1e-7);
    }

    #[test]
    fn parallel_ray_misses() {
        let w = floor();
        let r = Ray { origin: Vec3::new(0.0, 0.0, 0.0), dir: Vec3::X };
        assert_eq!(intersect_wall(&w, &r, 0.0, 5.0), 5.0);
    }

    #[test]
    fn a_seam_between_two_walls_is_hit_by_one_of_them() {
        // Case: a ray aimed exactly at the floor/back-wall edge from inside
        // the room must not pass between the two walls.
        let back = Wall::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0), Vec3::ONE);
        let f = floor();
        let o = Vec3::new(0.123, 1.0, 0.456);
        for i in 0..1000 {
            let x = -0.999 + 1.998 * (i as f32 / 999.0);
            let dir = (Vec3::new(x, 0.0, -1.0) - o).normalize();
            let r = Ray { origin: o, dir };
            let hit = intersect_wall(&f, &r, 0.0, f32::MAX).min(intersect_wall(&back, &r, 0.0, f32::MAX));
            assert!(hit < f32::MAX, "ray {i} escaped through the seam");
        }
    }

    /// Case: self-intersection at scales 1e-3 to 1e4. A ray spawned from a
    /// wall hit at the error-bounded offset never re-hits the wall, even
    /// without the path loop's rule that skips the wall a ray leaves.
    #[test]
    fn spawned_rays_never_rehit_their_wall_at_any_scale() {
        use crate::ray::offset_origin;
        use crate::rng::Rng;
        use crate::sampling::cosine_hemisphere;
        use crate::test_support::SCALES;
        for s in SCALES {
            let mut rng = Rng::new(s.to_bits(), 7, 0, 0, 0);
            let wall = Wall::new(
                Vec3::new(-1.0, 0.2, 1.0) * s,
                Vec3::new(2.0, 0.1, 0.0) * s,
                Vec3::new(0.0, 0.3, -2.0) * s,
                Vec3::ONE,
            );
            let o = Vec3::new(0.1, 2.0, -0.2) * s;
            for i in 0..20_000 {
                let aim = wall.corner + wall.edge_u * rng.next_f32() + wall.edge_v * rng.next_f32();
                let ray = Ray { origin: o, dir: (aim - o).normalize() };
                let t = intersect_wall(&wall, &ray, 0.0, f32::MAX);
                assert!(t < f32::MAX, "scale {s}, ray {i}: a ray aimed at the wall missed it");
                let n = if wall.normal.dot(ray.dir) < 0.0 { wall.normal } else { -wall.normal };
                let origin = offset_origin(ray.at(t), n, ray.origin.abs() + (ray.dir * t).abs());
                let refl = Ray { origin, dir: cosine_hemisphere(n, rng.next_f32(), rng.next_f32()) };
                assert_eq!(intersect_wall(&wall, &refl, 0.0, f32::MAX), f32::MAX, "scale {s}, ray {i}");
            }
        }
    }
}
