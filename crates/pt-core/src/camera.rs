//! The pinhole camera and primary rays.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::{Vec2, Vec3};

use crate::light::SphereLight;
use crate::ray::Ray;
use crate::sampling::orthonormal_basis;

/// A pinhole camera as the kernel reads it. `right` and `up` are scaled so
/// that film coordinates in [-1, 1] span the field of view.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Camera {
    /// Pinhole position, world space.
    pub position: Vec3,
    /// Padding.
    pub _pad0: f32,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Padding.
    pub _pad1: f32,
    /// Right vector times tan(vfov / 2) times the aspect ratio (width/height).
    pub right: Vec3,
    /// Padding.
    pub _pad2: f32,
    /// Up vector times tan(vfov / 2).
    pub up: Vec3,
    /// Padding.
    pub _pad3: f32,
}

impl Camera {
    /// A camera at `position` looking at `target` with `up` as the rough up
    /// direction, vertical field of view `vfov_degrees`, film `aspect` =
    /// width / height. The caller ensures `target != position` and `up` is
    /// not parallel to the view direction (the scene loader checks both).
    pub fn look_at(position: Vec3, target: Vec3, up: Vec3, vfov_degrees: f32, aspect: f32) -> Self {
        let forward = (target - position).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        let tan_half = (vfov_degrees.to_radians() * 0.5).tan();
        Self { position, forward, right: right * (tan_half * aspect), up: true_up * tan_half, ..Self::default() }
    }

    /// The primary ray through film point (`fx`, `fy`) in pixels, row 0 at
    /// the top, for a `width` x `height` image.
    pub fn ray(&self, fx: f32, fy: f32, width: u32, height: u32) -> Ray {
        Ray { origin: self.position, dir: self.direction(fx, fy, width, height).normalize() }
    }

    /// The unnormalised direction of [`Camera::ray`]: affine in (`fx`, `fy`).
    #[inline]
    pub fn direction(&self, fx: f32, fy: f32, width: u32, height: u32) -> Vec3 {
        let sx = 2.0 * fx / width as f32 - 1.0;
        let sy = 1.0 - 2.0 * fy / height as f32;
        self.forward + self.right * sx + self.up * sy
    }
}

/// The control variate of a pixel's camera samples that meet the light
/// (`FLAG_LIGHT_EDGE`). Where the light's silhouette crosses a pixel, a
/// camera sample's radiance is the light's (tens of times the room's) on
/// one side and the room's on the other, and the box filter's integral of
/// that step is the noisiest part of the pixel. The rays that meet the
/// sphere fill a cone, whose section by the film is an ellipse; the share
/// of the pixel inside it has a closed form ([`LightEdge::of_pixel`]). Each
/// sample adds the light's radiance times that share less its own
/// indicator of the ellipse: an addition with expectation 0 over the
/// jitter, so the pixel stays unbiased, and where nothing hides the light
/// the sample's own light cancels, leaving the pixel the exact light it
/// covers. Noise stays only where something in front of the light hides
/// part of it. Pixels the ellipse misses, or lies wholly over, add exactly
/// 0.
///
/// A straight line along the silhouette would not do: Sobol's jitter
/// already integrates a step with an error falling as N^-1.5, and the
/// sliver a line leaves is itself such a step (CHANGELOG.md).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LightEdge {
    /// The affine map from the jitter less 1/2 to coordinates in which the
    /// ellipse is the unit disk: `y = (a00 zx + a01 zy, a11 zy) + y0`.
    pub a00: f32,
    /// See `a00`.
    pub a01: f32,
    /// See `a00`.
    pub a11: f32,
    /// See `a00`.
    pub y0: Vec2,
    /// The share of the pixel inside the ellipse.
    pub share: f32,
    /// The light's radiance where the control variate acts, else 0.
    pub radiance: Vec3,
}

impl LightEdge {
    /// No control variate: every sample adds 0.
    pub const NONE: Self = Self { a00: 0.0, a01: 0.0, a11: 0.0, y0: Vec2::ZERO, share: 0.0, radiance: Vec3::ZERO };

    /// The ellipse of the rays from `camera` that meet `light`, across pixel (`x`, `y`) of a `width` x `height`
    /// image. With `z` the jitter less 1/2, the ray's direction `d(z)` is
    /// affine in `z`; it meets the sphere where its part across the unit
    /// vector `w` to the centre is at most `tan(a)` times its part along
    /// `w` (`a` the sphere's angular radius), a quadratic inequality in `z`.
    /// Its matrix's Cholesky factor maps the ellipse to the unit disk and
    /// the pixel to a parallelogram, whose area inside the disk is a sum of
    /// triangles and circular sectors ([`disk_quad_area`]).
    /// [`LightEdge::NONE`] where the camera is in the light (which shows
    /// nothing from inside) or the cone's section is no ellipse in front of
    /// the camera (a light beside or behind it).
    #[inline]
    pub fn of_pixel(camera: &Camera, light: &SphereLight, x: u32, y: u32, width: u32, height: u32) -> Self {
        let to_center = light.center - camera.position;
        let d2 = to_center.dot(to_center);
        let r2 = light.radius * light.radius;
        // Written so that a NaN distance also gives no control variate.
        let outside = d2 > r2;
        if !outside {
            return Self::NONE;
        }
        let w = to_center / d2.sqrt();
        let tan2 = r2 / (d2 - r2);
        let (u1, u2) = orthonormal_basis(w);
        // d(z) = dc + z.x da + z.y db; its part along w (l) and across (p).
        let dc = camera.direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
        let (da, db) = (camera.right * (2.0 / width as f32), camera.up * (-2.0 / height as f32));
        let across = |v: Vec3| Vec2::new(v.dot(u1), v.dot(u2));
        let (pc, pa, pb) = (across(dc), across(da), across(db));
        let (lc, la, lb) = (dc.dot(w), da.dot(w), db.dot(w));
        // tan2 l(z)^2 - |p(z)|^2 = -z'Mz + 2 g'z + g0 >= 0.
        let m00 = pa.dot(pa) - tan2 * la * la;
        let m01 = pa.dot(pb) - tan2 * la * lb;
        let m11 = pb.dot(pb) - tan2 * lb * lb;
        let g = Vec2::new(tan2 * lc * la - pc.dot(pa), tan2 * lc * lb - pc.dot(pb));
        let g0 = tan2 * lc * lc - pc.dot(pc);
        let det = m00 * m11 - m01 * m01;
        // The ellipse's centre z0 = M^-1 g and (z - z0)'M(z - z0) <= k.
        let z0 = Vec2::new(m11 * g.x - m01 * g.y, m00 * g.y - m01 * g.x) / det;
        let k = g0 + g.dot(z0);
        let ahead = lc + la * z0.x + lb * z0.y > 0.0;
        if !(m00 > 0.0 && det > 0.0 && k > 0.0 && ahead) {
            return Self::NONE;
        }
        // M = R'R, R = [[r00, r01], [0, r11]]; y = R (z - z0) / sqrt(k).
        let r00 = m00.sqrt();
        let r01 = m01 / r00;
        let r11 = (m11 - r01 * r01).max(0.0).sqrt();
        let scale = 1.0 / k.sqrt();
        let (a00, a01, a11) = (r00 * scale, r01 * scale, r11 * scale);
        let y0 = -Vec2::new(a00 * z0.x + a01 * z0.y, a11 * z0.y);
        let map = |zx: f32, zy: f32| Vec2::new(a00 * zx + a01 * zy, a11 * zy) + y0;
        // The pixel's corners, counter-clockwise (R keeps the orientation).
        let (area, enters, all_inside) = disk_quad_area(map(-0.5, -0.5), map(0.5, -0.5), map(0.5, 0.5), map(-0.5, 0.5));
        // Exactly 1 or 0 where the disk holds or misses the whole pixel, so
        // that those pixels add nothing at all.
        let share = if all_inside {
            1.0
        } else if !enters && area == 0.0 {
            0.0
        } else {
            (area / (a00 * a11)).clamp(0.0, 1.0)
        };
        Self { a00, a01, a11, y0, share, radiance: light.radiance }
    }

    /// The control variate's term for a sample jittered by `u` in [0, 1)^2:
    /// the radiance times the ellipse's share of the pixel less the
    /// sample's indicator of it. Its mean over `u` uniform is 0.
    #[inline]
    pub fn term(&self, u: Vec2) -> Vec3 {
        let (zx, zy) = (u.x - 0.5, u.y - 0.5);
        let yx = self.a00 * zx + self.a01 * zy + self.y0.x;
        let yy = self.a11 * zy + self.y0.y;
        let inside = if yx * yx + yy * yy <= 1.0 { 1.0 } else { 0.0 };
        self.radiance * (self.share - inside)
    }
}

/// The area of the unit disk inside the convex quadrilateral `c0 c1 c2
/// c3` (counter-clockwise), whether any of its edges passes inside the
/// disk, and whether it lies wholly inside. Written out for four corners,
/// not looped over an array, which the kernel would keep in
/// per-invocation memory.
///
/// The disk's area inside the triangle of its centre and an edge is, with
/// `p1`, `p2` the ends of the edge's chord (both at an end where the edge
/// misses the disk), half the angle the edge subtends plus the triangle of
/// the chord less its circular sector ([`chord_term`]). Around a closed
/// polygon the angles sum to a full turn where the centre is inside and to
/// nothing where it is outside: pi or 0, and one arctangent per edge.
#[inline]
pub fn disk_quad_area(c0: Vec2, c1: Vec2, c2: Vec2, c3: Vec2) -> (f32, bool, bool) {
    let (e0, e1, e2, e3) = (chord_term(c0, c1), chord_term(c1, c2), chord_term(c2, c3), chord_term(c3, c0));
    // The centre (the origin) is left of every edge.
    let left = |a: Vec2, b: Vec2| (b - a).perp_dot(-a) >= 0.0;
    let centre_inside = left(c0, c1) && left(c1, c2) && left(c2, c3) && left(c3, c0);
    let turn = if centre_inside { core::f32::consts::PI } else { 0.0 };
    let area = turn + e0.0 + e1.0 + e2.0 + e3.0;
    let enters = e0.1 || e1.1 || e2.1 || e3.1;
    let all_inside = c0.dot(c0) <= 1.0 && c1.dot(c1) <= 1.0 && c2.dot(c2) <= 1.0 && c3.dot(c3) <= 1.0;
    (area, enters, all_inside)
}

/// The part of the segment from `a` to `b` inside the unit disk, from
/// `p1` to `p2`: half its chord's cross product less half the angle it
/// subtends at the centre (the triangle of the chord less its circular
/// sector; 0 where the segment misses the disk), and whether there is
/// such a part.
#[inline]
pub fn chord_term(a: Vec2, b: Vec2) -> (f32, bool) {
    let d = b - a;
    let dd = d.dot(d);
    let ad = a.dot(d);
    let disc = ad * ad - dd * (a.dot(a) - 1.0);
    // The chord's ends along the segment, clamped to it; both at `b` where
    // the line misses the disk.
    let (t1, t2) = if disc > 0.0 && dd > 0.0 {
        let root = disc.sqrt();
        (((-ad - root) / dd).clamp(0.0, 1.0), ((-ad + root) / dd).clamp(0.0, 1.0))
    } else {
        (1.0, 1.0)
    };
    let (p1, p2) = (a + d * t1, a + d * t2);
    let cross = p1.perp_dot(p2);
    (0.5 * (cross - cross.atan2(p1.dot(p2))), t2 > t1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use spirv_std::glam::Vec2;

    /// The area of the unit disk inside the quadrilateral `corners`
    /// (counter-clockwise), by [`disk_quad_area`].
    fn disk_polygon(corners: &[Vec2; 4]) -> f32 {
        disk_quad_area(corners[0], corners[1], corners[2], corners[3]).0
    }

    /// Case: squares wholly inside the disk, around it, beside it, across
    /// its edge and over its centre, and a thin parallelogram across it.
    /// Exact values where the geometry gives them, else a count on a
    /// 2000 x 2000 grid over the polygon (within 2e-3 of the area).
    #[test]
    fn disk_quad_area_is_a_quadrilaterals_area_inside_the_disk() {
        let square = |cx: f32, cy: f32, h: f32| {
            [Vec2::new(cx - h, cy - h), Vec2::new(cx + h, cy - h), Vec2::new(cx + h, cy + h), Vec2::new(cx - h, cy + h)]
        };
        let close = |a: f32, b: f32, tol: f32| assert!((a - b).abs() <= tol, "{a} against {b}");
        close(disk_polygon(&square(0.1, -0.2, 0.3)), 0.36, 1e-6);
        close(disk_polygon(&square(0.0, 0.0, 3.0)), core::f32::consts::PI, 1e-5);
        close(disk_polygon(&square(3.0, 0.5, 0.4)), 0.0, 1e-6);
        // The circular segment beyond x = 1/2: pi / 3 - sqrt(3) / 4.
        let segment = [Vec2::new(0.5, -2.0), Vec2::new(2.0, -2.0), Vec2::new(2.0, 2.0), Vec2::new(0.5, 2.0)];
        close(disk_polygon(&segment), core::f32::consts::PI / 3.0 - 3.0f32.sqrt() / 4.0, 1e-6);
        let thin = [Vec2::new(-1.5, -0.05), Vec2::new(1.5, 0.0), Vec2::new(1.5, 0.1), Vec2::new(-1.5, 0.05)];
        for corners in [square(0.9, 0.3, 0.25), square(-0.6, -0.7, 0.5), thin] {
            let (lo, hi) = corners
                .iter()
                .fold((Vec2::splat(f32::MAX), Vec2::splat(f32::MIN)), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
            let n = 2000;
            let cell = (hi - lo) / n as f32;
            let mut count = 0u32;
            for i in 0..n {
                for j in 0..n {
                    let p = lo + cell * Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                    let inside_polygon =
                        (0..4).all(|k| (corners[(k + 1) % 4] - corners[k]).perp_dot(p - corners[k]) >= 0.0);
                    count += (inside_polygon && p.dot(p) <= 1.0) as u32;
                }
            }
            close(disk_polygon(&corners), count as f32 * cell.x * cell.y, 2e-3);
        }
    }

    /// The default scene's camera at `size` x `size` pixels, and a light of
    /// `radius` at the default light's centre.
    fn view(radius: f32) -> (Camera, SphereLight) {
        let camera = Camera::look_at(Vec3::new(0.0, 1.0, 3.4), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0, 1.0);
        (camera, SphereLight::new(Vec3::new(0.0, 1.7, 0.0), radius, Vec3::splat(20.0)))
    }

    /// Whether the ray through film point (`fx`, `fy`) meets the light.
    fn meets(camera: &Camera, light: &SphereLight, fx: f32, fy: f32, size: u32) -> bool {
        let ray = camera.ray(fx, fy, size, size);
        crate::sphere::intersect_sphere(light.center, light.radius, &ray, 0.0, f32::MAX) < f32::MAX
    }

    /// Case: every pixel of the default scene's light at 128 x 128 (an
    /// image radius of 7.6 pixels) and of a light of radius 0.02 at 64 x 64
    /// (0.5 pixels). On a 16 x 16 grid of jitters in every pixel, the
    /// term's inside test agrees with the ray's own hit on the sphere;
    /// pixels the ellipse misses or covers have a share of exactly 0 or 1;
    /// in the others, on a 256 x 256 grid, the share is the grid's count of
    /// rays that meet the sphere and the term's mean is 0, both within
    /// 2e-3 (of the pixel, and of the radiance).
    #[test]
    fn the_edge_share_is_the_pixels_share_of_rays_that_meet_the_light() {
        for (radius, size) in [(0.15, 128u32), (0.02, 64)] {
            let (camera, light) = view(radius);
            let mut crossed = 0;
            for y in 0..size {
                for x in 0..size {
                    let edge = LightEdge::of_pixel(&camera, &light, x, y, size, size);
                    assert_eq!(edge.radiance, light.radiance);
                    let jitter =
                        |i: u32, j: u32, n: u32| Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    for i in 0..16 {
                        for j in 0..16 {
                            let u = jitter(i, j, 16);
                            let inside = edge.term(u).x < edge.radiance.x * edge.share;
                            let hit = meets(&camera, &light, x as f32 + u.x, y as f32 + u.y, size);
                            assert_eq!(inside, hit, "pixel ({x}, {y}) at {u}");
                        }
                    }
                    if edge.share == 0.0 || edge.share == 1.0 {
                        continue;
                    }
                    crossed += 1;
                    let n = 256;
                    let (mut hits, mut mean) = (0u32, 0.0f64);
                    for i in 0..n {
                        for j in 0..n {
                            let u = jitter(i, j, n);
                            hits += meets(&camera, &light, x as f32 + u.x, y as f32 + u.y, size) as u32;
                            mean += edge.term(u).x as f64;
                        }
                    }
                    let counted = hits as f32 / (n * n) as f32;
                    assert!((edge.share - counted).abs() < 2e-3, "pixel ({x}, {y}): {} against {counted}", edge.share);
                    mean /= (n * n) as f64;
                    assert!(mean.abs() < 2e-3 * 20.0, "pixel ({x}, {y}): mean term {mean}");
                }
            }
            // A circle of R pixels crosses about 2 pi R * 1.3 pixels (at
            // least one).
            let expected = (2.0 * core::f32::consts::PI * radius / 0.15 * 7.6 * size as f32 / 128.0 * 1.3) as u32;
            assert!(
                crossed >= expected / 2 && crossed <= expected * 2 + 4,
                "radius {radius}: {crossed} pixels crossed"
            );
        }
    }

    /// Case: a camera inside the light, and a light behind the camera: no
    /// control variate.
    #[test]
    fn no_edge_from_inside_the_light_or_behind_the_camera() {
        let (camera, light) = view(0.15);
        let inside = SphereLight::new(camera.position + Vec3::new(0.0, 0.05, 0.0), 0.2, light.radiance);
        assert_eq!(LightEdge::of_pixel(&camera, &inside, 64, 64, 128, 128), LightEdge::NONE);
        let behind = SphereLight::new(camera.position + Vec3::new(0.0, 0.0, 1.0), 0.15, light.radiance);
        for (x, y) in [(0, 0), (64, 64), (127, 127)] {
            assert_eq!(LightEdge::of_pixel(&camera, &behind, x, y, 128, 128), LightEdge::NONE);
        }
        assert_ne!(LightEdge::of_pixel(&camera, &light, 64, 40, 128, 128), LightEdge::NONE);
    }
}
