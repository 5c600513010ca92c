//! Walls: two-sided Lambertian parallelograms, and ray/wall intersection.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::ray::Ray;

/// Slack of the inside test in parametric units (fractions of an edge).
///
/// Walls that meet at an edge each extend 1e-5 of their size past it, so a
/// ray aimed exactly at a seam hits at least one of them whatever the
/// rounding: the room is watertight. 1e-5 of a wall is far below a pixel.
pub const EDGE_SLACK: f32 = 1e-5;

/// A planar parallelogram `corner + a * edge_u + b * edge_v`, a, b in [0, 1],
/// as the kernel reads it. Build it with [`Wall::new`], which derives the
/// normal and `w` from the edges.
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
    /// Padding.
    pub _pad3: f32,
    /// `(edge_u x edge_v) / |edge_u x edge_v|^2`: `w . (q x edge_v)` and
    /// `w . (edge_u x q)` are the parametric coordinates of a point `q`
    /// relative to `corner` (Shirley, "Ray Tracing: The Next Week", 6.4).
    pub w: Vec3,
    /// Padding.
    pub _pad4: f32,
    /// Diffuse reflectance per RGB channel, each in [0, 1].
    pub albedo: Vec3,
    /// Padding to a 16-byte multiple.
    pub _pad5: f32,
}

impl Wall {
    /// A wall from a corner, two edges and an albedo. The edges must not be
    /// parallel (the scene loader rejects zero-area walls before this).
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3, albedo: Vec3) -> Self {
        let n = edge_u.cross(edge_v);
        let n2 = n.dot(n);
        let (normal, w) = if n2 > 0.0 {
            (n / n2.sqrt(), n / n2)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        Self {
            corner,
            edge_u,
            edge_v,
            normal,
            w,
            albedo,
            ..Self::default()
        }
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
    let a = wall.w.dot(q.cross(wall.edge_v));
    let b = wall.w.dot(wall.edge_u.cross(q));
    let lo = -EDGE_SLACK;
    let hi = 1.0 + EDGE_SLACK;
    if a >= lo && a <= hi && b >= lo && b <= hi {
        t
    } else {
        t_max
    }
}
