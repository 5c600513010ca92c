//! The scene's walls and spheres as the kernel reads them: fixed-size arrays
//! in one uniform block.
//!
//! Why a uniform block and not storage buffers: every ray tests every wall
//! and sphere in the same order, so all invocations read the same element at
//! the same time, which GPUs serve from their constant caches. lavapipe
//! (Mesa's llvmpipe) reads either kind lane by lane, but a uniform read as
//! one bounds-checked gather, a storage read as a loop over the lanes with a
//! branch in each (Mesa 22.3, `emit_load_ubo` against `emit_load_mem` in
//! `lp_bld_nir_soa.c`); docs/ARCHITECTURE.md has the measured difference.
//! For small scenes lavapipe avoids both: see [`crate::small_scene`].

use bytemuck::{Pod, Zeroable};

use crate::sphere::Sphere;
use crate::wall::Wall;
#[cfg(not(target_arch = "spirv"))]
use spirv_std::glam::Vec3;

/// Most walls a scene may have. With [`MAX_SPHERES`] it keeps the block
/// within 16 KiB, the smallest uniform-block size Vulkan guarantees.
pub const MAX_WALLS: usize = 96;

/// Most spheres (besides the light) a scene may have.
pub const MAX_SPHERES: usize = 128;

/// Walls and spheres; `FrameParams::wall_count` and `sphere_count` say how
/// many of each are in use, the rest are zero.
#[repr(C)]
#[derive(Copy, Clone, Debug, PartialEq, Pod, Zeroable)]
pub struct Geometry {
    /// Walls `0..wall_count`.
    pub walls: [Wall; MAX_WALLS],
    /// Spheres `0..sphere_count`.
    pub spheres: [Sphere; MAX_SPHERES],
}

#[cfg(not(target_arch = "spirv"))]
impl Geometry {
    /// The block holding `walls` and `spheres`, or `None` when there are
    /// more than [`MAX_WALLS`] walls or [`MAX_SPHERES`] spheres (the scene
    /// loader rejects such scenes with a message first).
    pub fn new(walls: &[Wall], spheres: &[Sphere]) -> Option<Self> {
        if walls.len() > MAX_WALLS || spheres.len() > MAX_SPHERES {
            return None;
        }
        let mut g = Self::zeroed();
        g.walls[..walls.len()].copy_from_slice(walls);
        g.spheres[..spheres.len()].copy_from_slice(spheres);
        // The tolerance of `enclosure_side`: 1e-6 of the largest coordinate.
        let scale = walls
            .iter()
            .flat_map(corners)
            .map(|p| p.abs().max_element())
            .chain(spheres.iter().map(|s| s.center.abs().max_element() + s.radius))
            .fold(0.0f32, f32::max);
        for (i, w) in g.walls[..walls.len()].iter_mut().enumerate() {
            w.enclosure_side = enclosure_side(walls, spheres, i, 1e-6 * scale);
        }
        Some(g)
    }
}

/// The four corners of a wall.
#[cfg(not(target_arch = "spirv"))]
fn corners(w: &Wall) -> [Vec3; 4] {
    [w.corner, w.corner + w.edge_u, w.corner + w.edge_v, w.corner + w.edge_u + w.edge_v]
}

/// The side (+1 or -1 along its normal) of wall `i`'s plane on which every
/// other wall and sphere lies, or 0 when there are some on both sides
/// ([`Wall::enclosure_side`]).
///
/// Points may stray to the wrong side by `tolerance`, 1e-6 of the scene's
/// largest coordinate (8 float steps): walls that meet at a seam are
/// coplanar there up to rounding. A point straying so little could see the light through
/// the wall only that close to it; the walls' edge slack (`EDGE_SLACK`) is
/// left out for the same reason. Geometry further out keeps the wall
/// tested: a tighter tolerance can only cost speed.
#[cfg(not(target_arch = "spirv"))]
fn enclosure_side(walls: &[Wall], spheres: &[Sphere], i: usize, tolerance: f32) -> f32 {
    let wall = &walls[i];
    let others = walls.iter().enumerate().filter(|&(j, _)| j != i).map(|(_, w)| w);
    // The signed distances' range over all other points.
    let distance = |p: Vec3| wall.normal.dot(p - wall.corner);
    let (mut lo, mut hi) = (0.0f32, 0.0f32);
    for d in others.flat_map(corners).map(distance) {
        (lo, hi) = (lo.min(d), hi.max(d));
    }
    for s in spheres {
        let d = distance(s.center);
        (lo, hi) = (lo.min(d - s.radius), hi.max(d + s.radius));
    }
    if lo >= -tolerance {
        1.0
    } else if hi <= tolerance {
        -1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spirv_std::glam::Vec3;

    #[test]
    fn new_copies_in_order_and_refuses_too_many() {
        let w = Wall::new(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE);
        let s = Sphere::new(Vec3::ONE, 0.5, Vec3::splat(0.5));
        let g = Geometry::new(&[w], &[s, s]).unwrap();
        // The spheres lie on the wall's +z side.
        assert_eq!(g.walls[0], Wall { enclosure_side: 1.0, ..w });
        assert_eq!(g.walls[1], Wall::zeroed());
        assert_eq!(g.spheres[1], s);
        assert_eq!(g.spheres[2], Sphere::zeroed());
        assert!(Geometry::new(&[w; MAX_WALLS], &[s; MAX_SPHERES]).is_some());
        assert!(Geometry::new(&[w; MAX_WALLS + 1], &[]).is_none());
        assert!(Geometry::new(&[], &[s; MAX_SPHERES + 1]).is_none());
    }

    /// The default scene's room: five walls of a 2x2x2 box open toward +z
    /// (floor, ceiling, back, left, right), as in scenes/default.toml.
    fn room() -> Vec<Wall> {
        let v = Vec3::new;
        let grey = Vec3::splat(0.73);
        vec![
            Wall::new(v(-1.0, 0.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -2.0), grey),
            Wall::new(v(-1.0, 2.0, 1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -2.0), grey),
            Wall::new(v(-1.0, 0.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), grey),
            Wall::new(v(-1.0, 0.0, 1.0), v(0.0, 0.0, -2.0), v(0.0, 2.0, 0.0), grey),
            Wall::new(v(1.0, 0.0, 1.0), v(0.0, 0.0, -2.0), v(0.0, 2.0, 0.0), grey),
        ]
    }

    fn spheres() -> Vec<Sphere> {
        vec![
            Sphere::new(Vec3::new(-0.45, 0.40, -0.30), 0.40, Vec3::splat(0.73)),
            Sphere::new(Vec3::new(0.50, 0.28, 0.35), 0.28, Vec3::splat(0.5)),
        ]
    }

    #[test]
    fn the_rooms_walls_enclose_the_scene_and_a_partition_does_not() {
        let g = Geometry::new(&room(), &spheres()).unwrap();
        let inside = Vec3::new(0.0, 1.0, 0.0);
        for w in &g.walls[..5] {
            // The side is the one facing into the room.
            assert_eq!(w.enclosure_side, w.normal.dot(inside - w.corner).signum(), "{w:?}");
        }
        // A partition across the room has geometry on both sides; a sphere
        // behind the back wall puts that wall between it and the room.
        let mut walls = room();
        walls.push(Wall::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 1.0, 0.0), Vec3::ONE));
        let mut balls = spheres();
        balls.push(Sphere::new(Vec3::new(0.0, 1.0, -1.5), 0.2, Vec3::ONE));
        let g = Geometry::new(&walls, &balls).unwrap();
        let sides: Vec<f32> = g.walls[..6].iter().map(|w| w.enclosure_side).collect();
        assert_eq!(sides[2], 0.0, "back wall");
        assert_eq!(sides[5], 0.0, "partition");
        assert!(sides[..2].iter().chain(&sides[3..5]).all(|&s| s != 0.0), "{sides:?}");
    }

    /// Walls in every word of the shadow-wall mask block shadow rays: 96
    /// unit squares side by side along x, square i in the plane z = -i, each
    /// hit only by the ray that starts just behind it.
    #[test]
    fn shadow_walls_cover_every_wall_index() {
        use crate::params::FrameParams;
        use crate::query::{ShadowWalls, occluded};
        use crate::ray::Ray;

        let mut geometry = Geometry::zeroed();
        for (i, w) in geometry.walls.iter_mut().enumerate() {
            *w = Wall::new(Vec3::new(3.0 * i as f32, 0.0, -(i as f32)), Vec3::X, Vec3::Y, Vec3::ONE);
        }
        let light = crate::light::SphereLight::new(Vec3::new(0.0, 0.0, 200.0), 1.0, Vec3::ONE);
        for wall_count in [0u32, 5, 32, 33, 64, 70, 96] {
            let params = FrameParams { light, wall_count, ..Default::default() };
            // No wall here has everything on one side, so none is culled.
            let walls = ShadowWalls::new(&params, &geometry);
            assert_eq!(walls, ShadowWalls::all(&params), "{wall_count} walls");
            assert!((0..100).all(|k| walls.contains(k) == (k < wall_count)), "{wall_count} walls");
            for k in [0u32, 1, 31, 32, 33, 63, 64, 65, 95] {
                let ray = Ray { origin: Vec3::new(3.0 * k as f32 + 0.5, 0.5, -(k as f32) - 0.5), dir: Vec3::Z };
                let in_use = k < wall_count;
                assert_eq!(occluded(&ray, &params, &geometry, &walls, u32::MAX, 1.0), in_use, "wall {k}");
                assert!(!occluded(&ray, &params, &geometry, &walls, k, 1.0), "wall {k} skipped");
                assert!(!occluded(&ray, &params, &geometry, &walls, u32::MAX, 0.25), "wall {k} beyond t_max");
            }
        }
    }

    /// Shadow rays from random surface points toward random points of the
    /// light: `occluded` with the hull walls skipped answers exactly as with
    /// every wall tested, for a light inside the room and for one behind
    /// the back wall (which must then still cast its shadow).
    #[test]
    fn skipping_hull_walls_changes_no_shadow_ray() {
        use crate::light::{SphereLight, light_cone};
        use crate::params::FrameParams;
        use crate::query::{ShadowWalls, occluded};
        use crate::ray::{Ray, offset_origin};
        use crate::rng::Rng;

        let (walls, balls) = (room(), spheres());
        let geometry = Geometry::new(&walls, &balls).unwrap();
        let mut rng = Rng::new(1, 2, 3, 4, 5);
        for (center, skipped, min_blocked) in [(Vec3::new(0.0, 1.7, 0.0), 5, 0.0), (Vec3::new(0.0, 1.0, -1.6), 4, 0.5)]
        {
            let light = SphereLight::new(center, 0.15, Vec3::ONE);
            let params = FrameParams {
                light,
                wall_count: walls.len() as u32,
                sphere_count: balls.len() as u32,
                ..Default::default()
            };
            assert_eq!(geometry.walls[..5].iter().filter(|w| w.cannot_shadow(&light)).count(), skipped);
            let (culled, all) = (ShadowWalls::new(&params, &geometry), ShadowWalls::all(&params));
            let (mut rays, mut blocked) = (0, 0);
            for i in 0..20_000u32 {
                // A point on wall or sphere i % 7, its normal facing the light.
                let k = (i % 7) as usize;
                let (p, normal, skip) = if k < 5 {
                    let w = &walls[k];
                    (w.corner + w.edge_u * rng.next_f32() + w.edge_v * rng.next_f32(), w.normal, k as u32)
                } else {
                    let s = &balls[k - 5];
                    let z = 1.0 - 2.0 * rng.next_f32();
                    let phi = 2.0 * crate::sampling::PI * rng.next_f32();
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                    (s.center + d * s.radius, d, u32::MAX)
                };
                let n = if normal.dot(center - p) >= 0.0 { normal } else { -normal };
                let origin = offset_origin(p, n, p.abs());
                let cone = light_cone(&light, p);
                let (dir, dist) = cone.sample(rng.next_f32(), rng.next_f32());
                if n.dot(dir) <= 0.0 {
                    continue;
                }
                let ray = Ray { origin, dir };
                let answer = occluded(&ray, &params, &geometry, &culled, skip, dist);
                assert_eq!(answer, occluded(&ray, &params, &geometry, &all, skip, dist), "ray {i} from {p}");
                rays += 1;
                blocked += answer as u32;
            }
            assert!(rays > 10_000 && blocked as f32 >= min_blocked * rays as f32, "{blocked} of {rays} blocked");
        }
    }
}
