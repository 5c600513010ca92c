//! Scene queries: what a ray hits first, whether a shadow ray is blocked,
//! and the shading data of a hit. [`SceneView`] is the one interface the
//! path loop asks them through; the uniform block ([`Geometry`], in loops,
//! for any scene) and a copy of a small scene
//! ([`crate::small_scene::SmallScene`], unrolled) both implement it. A new
//! kind of shape adds its hit test to [`Hit`], its loop to [`closest_hit`]
//! and [`occluded`], and its shading data to [`surface`].

use spirv_std::glam::Vec3;

use crate::geometry::{Geometry, MAX_SPHERES, MAX_WALLS};
use crate::light::SphereLight;
use crate::params::FrameParams;
use crate::ray::Ray;
use crate::sphere::{Sphere, intersect_sphere, sphere_hit_point, sphere_meets_segment};
use crate::wall::{Wall, intersect_wall};

/// What a ray hit. `u32`-sized: SPIR-V has no 8-bit integers without the
/// Int8 capability.
#[repr(u32)]
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// Nothing: the ray leaves the scene.
    Nothing,
    /// Wall number `index`.
    Wall,
    /// Sphere number `index`.
    Sphere,
    /// The light.
    Light,
}

/// The closest hit along a ray.
#[derive(Copy, Clone, Debug)]
pub struct Hit {
    /// Ray parameter of the hit (the search limit when nothing was hit).
    pub t: f32,
    /// What was hit.
    pub kind: HitKind,
    /// Index of the wall or sphere hit.
    pub index: u32,
}

/// The steps of a closest-hit search, shared by the general loops
/// ([`closest_hit`]) and the small-scene copy
/// ([`crate::small_scene::SmallScene`]): each keeps an object that the ray
/// meets before the hit so far.
impl Hit {
    /// Nothing found in (0, `t_max`) yet.
    pub fn none(t_max: f32) -> Self {
        Self { t: t_max, kind: HitKind::Nothing, index: 0 }
    }

    /// Tests wall number `index`.
    #[inline]
    pub fn test_wall(&mut self, index: u32, wall: &Wall, ray: &Ray) {
        self.take_wall(index, intersect_wall(wall, ray, 0.0, self.t));
    }

    /// Takes wall number `index` met at `t` where that is nearer.
    #[inline]
    pub fn take_wall(&mut self, index: u32, t: f32) {
        if t < self.t {
            *self = Self { t, kind: HitKind::Wall, index };
        }
    }

    /// Tests sphere number `index`.
    #[inline]
    pub fn test_sphere(&mut self, index: u32, sphere: &Sphere, ray: &Ray) {
        let t = intersect_sphere(sphere.center, sphere.radius, ray, 0.0, self.t);
        if t < self.t {
            *self = Self { t, kind: HitKind::Sphere, index };
        }
    }

    /// Tests the light.
    #[inline]
    pub fn test_light(&mut self, light: &SphereLight, ray: &Ray) {
        let t = intersect_sphere(light.center, light.radius, ray, 0.0, self.t);
        if t < self.t {
            *self = Self { t, kind: HitKind::Light, index: 0 };
        }
    }
}

/// Whether `sphere` blocks the shadow ray in (0, `t_max`).
#[inline]
pub fn sphere_blocks(sphere: &Sphere, ray: &Ray, t_max: f32) -> bool {
    sphere_meets_segment(sphere.center, sphere.radius, ray, t_max)
}

/// "No limit" for ray parameters: far beyond any scene (positions are
/// relative to the camera, and f32 precision ends long before this). Not
/// `f32::INFINITY`: naga rejects an infinite literal in a SPIR-V module.
/// Not `f32::MAX`: naga writes it to WGSL as `3.4028235e38f`, which is
/// above f32::MAX read exactly, and browsers reject the module.
pub const T_FAR: f32 = 1e30;

/// No wall to skip.
pub const NO_WALL: u32 = u32::MAX;

/// The walls and spheres in use, clamped to the block's arrays: the loops
/// below then need no bounds checks, and a bad count cannot read past them.
#[inline]
pub fn counts(params: &FrameParams) -> (u32, u32) {
    (params.wall_count.min(MAX_WALLS as u32), params.sphere_count.min(MAX_SPHERES as u32))
}

/// The closest hit in (0, `t_max`) over walls, spheres and the light, brute
/// force. `skip_wall` is the wall the ray leaves from: a plane cannot be hit
/// again by a ray that leaves it, so testing it could only find rounding
/// noise.
#[inline]
pub fn closest_hit(ray: &Ray, params: &FrameParams, geometry: &Geometry, skip_wall: u32, t_max: f32) -> Hit {
    let mut hit = nearest_wall(ray, params, geometry, skip_wall, t_max);
    let (_, sphere_count) = counts(params);
    let mut i = 0;
    while i < sphere_count {
        hit.test_sphere(i, &geometry.spheres[i as usize], ray);
        i += 1;
    }
    hit.test_light(&params.light, ray);
    hit
}

/// The nearest wall hit in (0, `t_max`) but `skip_wall`: the walls' part of
/// [`closest_hit`], and alone [`SceneView::first_wall`].
#[inline]
fn nearest_wall(ray: &Ray, params: &FrameParams, geometry: &Geometry, skip_wall: u32, t_max: f32) -> Hit {
    let mut hit = Hit::none(t_max);
    let (wall_count, _) = counts(params);
    let mut i = 0;
    while i < wall_count {
        if i != skip_wall {
            hit.test_wall(i, &geometry.walls[i as usize], ray);
        }
        i += 1;
    }
    hit
}

/// The walls that can block a shadow ray toward the frame's light: those
/// that are not [`crate::wall::Wall::cannot_shadow`], as a bit mask over
/// wall indices, 32 per word. It depends on the light and the geometry
/// only, so a pixel works it out once per frame, not once per shadow ray;
/// in a closed room with the light inside, no wall is left.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ShadowWalls {
    /// Walls 0 to 31.
    low: u32,
    /// Walls 32 to 63.
    middle: u32,
    /// Walls 64 to 95.
    high: u32,
}

// Three words of 32 bits hold every wall.
const _: () = assert!(MAX_WALLS <= 96);

impl ShadowWalls {
    /// The walls in use that can block a shadow ray toward `params.light`.
    #[inline]
    pub fn new(params: &FrameParams, geometry: &Geometry) -> Self {
        let mut walls = Self { low: 0, middle: 0, high: 0 };
        let (wall_count, _) = counts(params);
        let mut i = 0;
        while i < wall_count {
            if !geometry.walls[i as usize].cannot_shadow(&params.light) {
                if i < 32 {
                    walls.low |= 1 << i;
                } else if i < 64 {
                    walls.middle |= 1 << (i - 32);
                } else {
                    walls.high |= 1 << (i - 64);
                }
            }
            i += 1;
        }
        walls
    }

    /// Whether wall `i` can block a shadow ray (is in the mask).
    #[inline]
    pub fn contains(&self, i: u32) -> bool {
        let word = if i < 32 {
            self.low
        } else if i < 64 {
            self.middle
        } else {
            self.high
        };
        i < 96 && (word >> (i % 32)) & 1 != 0
    }

    /// The mask of walls 0 to 31, a bit each: all of a scene's walls
    /// where it has at most 32.
    #[inline]
    pub fn first_32(&self) -> u32 {
        self.low
    }

    /// Whether no wall can block a shadow ray.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.low | self.middle | self.high == 0
    }

    /// Every wall in use, for tests to compare against.
    #[cfg(test)]
    pub(crate) fn all(params: &FrameParams) -> Self {
        let bits = |first: u32| match counts(params).0.saturating_sub(first) {
            0 => 0,
            n if n >= 32 => u32::MAX,
            n => (1 << n) - 1,
        };
        Self { low: bits(0), middle: bits(32), high: bits(64) }
    }
}

/// Whether one of the walls in `bits` (wall `first` and on) blocks the
/// shadow ray; the loop ends after the last wall left in the mask.
#[inline]
fn walls_block(mut bits: u32, first: u32, ray: &Ray, geometry: &Geometry, skip_wall: u32, t_max: f32) -> bool {
    let mut i = first;
    while bits != 0 {
        if bits & 1 != 0 && i != skip_wall && intersect_wall(&geometry.walls[i as usize], ray, 0.0, t_max) < t_max {
            return true;
        }
        bits >>= 1;
        i += 1;
    }
    false
}

/// Whether a wall or sphere blocks the shadow ray, which leaves a surface
/// and ends on the light at `t_max`, in (0, `t_max`). The light is no
/// occluder of itself. Only the walls in `walls` are tested: in a closed
/// room with the light inside, only the objects in it cast shadows, and a
/// shadow ray costs the spheres alone.
#[inline]
pub fn occluded(
    ray: &Ray,
    params: &FrameParams,
    geometry: &Geometry,
    walls: &ShadowWalls,
    skip_wall: u32,
    t_max: f32,
) -> bool {
    if walls_block(walls.low, 0, ray, geometry, skip_wall, t_max)
        || walls_block(walls.middle, 32, ray, geometry, skip_wall, t_max)
        || walls_block(walls.high, 64, ray, geometry, skip_wall, t_max)
    {
        return true;
    }
    let (_, sphere_count) = counts(params);
    let mut i = 0;
    while i < sphere_count {
        if sphere_blocks(&geometry.spheres[i as usize], ray, t_max) {
            return true;
        }
        i += 1;
    }
    false
}

/// Where a path meets a wall or sphere, and what shading needs of it.
#[derive(Copy, Clone, Debug)]
pub struct Surface {
    /// The hit point.
    pub point: Vec3,
    /// The surface's unit normal there, on either side (walls are
    /// two-sided; the path loop turns it toward the ray).
    pub normal: Vec3,
    /// Lambertian albedo.
    pub albedo: Vec3,
    /// A bound on the magnitudes `point`'s coordinates were computed from,
    /// per axis: the scale of its rounding error, for the ray offset.
    pub magnitude: Vec3,
    /// The wall hit ([`NO_WALL`] for a sphere): the next ray leaves it and
    /// skips it.
    pub wall: u32,
}

/// The shading data of `hit`, a wall or sphere hit of `ray` among
/// `geometry`'s objects. Always inlined, as are the trait methods that
/// forward to it: as a call, with the struct returned through memory, it
/// cost the CPU renderer a quarter of its speed.
#[inline(always)]
pub fn surface(geometry: &Geometry, hit: &Hit, ray: &Ray) -> Surface {
    let i = hit.index as usize;
    surface_of(hit, ray, || geometry.walls[i], || geometry.spheres[i])
}

/// [`surface`] with the object hit read by `wall` (a wall hit) or `sphere`
/// (a sphere hit), whichever the hit's kind calls for: a scene stored
/// another way supplies its own reads.
#[inline(always)]
pub fn surface_of(hit: &Hit, ray: &Ray, wall: impl Fn() -> Wall, sphere: impl Fn() -> Sphere) -> Surface {
    if hit.kind == HitKind::Wall {
        let w = wall();
        let magnitude = ray.origin.abs() + (ray.dir * hit.t).abs();
        Surface { point: ray.at(hit.t), normal: w.normal, albedo: w.albedo, magnitude, wall: hit.index }
    } else {
        let s = sphere();
        let (point, normal) = sphere_hit_point(s.center, s.radius, ray, hit.t);
        Surface { point, normal, albedo: s.albedo, magnitude: s.center.abs() + Vec3::splat(s.radius), wall: NO_WALL }
    }
}

/// The scene as the path loop sees it: closest hits, shadow rays and the
/// shading data of a hit, however the objects are stored and read.
pub trait SceneView {
    /// The closest hit in (0, `t_max`): see [`closest_hit`].
    fn closest_hit(&self, ray: &Ray, params: &FrameParams, skip_wall: u32, t_max: f32) -> Hit;
    /// The closest wall hit in (0, infinity), spheres and light ignored.
    fn first_wall(&self, ray: &Ray, params: &FrameParams) -> Hit;
    /// Whether the shadow ray is blocked in (0, `t_max`): see [`occluded`].
    fn occluded(&self, ray: &Ray, params: &FrameParams, walls: &ShadowWalls, skip_wall: u32, t_max: f32) -> bool;
    /// The shading data of a wall or sphere hit: see [`surface`].
    fn surface(&self, hit: &Hit, ray: &Ray) -> Surface;
}

impl SceneView for Geometry {
    #[inline]
    fn closest_hit(&self, ray: &Ray, params: &FrameParams, skip_wall: u32, t_max: f32) -> Hit {
        closest_hit(ray, params, self, skip_wall, t_max)
    }

    #[inline]
    fn first_wall(&self, ray: &Ray, params: &FrameParams) -> Hit {
        nearest_wall(ray, params, self, NO_WALL, T_FAR)
    }

    #[inline]
    fn occluded(&self, ray: &Ray, params: &FrameParams, walls: &ShadowWalls, skip_wall: u32, t_max: f32) -> bool {
        occluded(ray, params, self, walls, skip_wall, t_max)
    }

    #[inline(always)]
    fn surface(&self, hit: &Hit, ray: &Ray) -> Surface {
        surface(self, hit, ray)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Case: watertightness. 1,000,000 rays from inside a closed box (the
    /// default room with its front wall), aimed exactly at its 12 edges and
    /// 8 corners, where two or three walls meet: none escapes through a
    /// seam.
    #[test]
    fn rays_at_the_edges_and_corners_of_a_closed_box_never_escape() {
        let v = Vec3::new;
        let walls = crate::test_support::closed_room();
        let geometry = Geometry::new(&walls, &[]).expect("six walls fit");
        let params = FrameParams {
            light: SphereLight::new(v(0.0, 1.7, 0.0), 0.15, Vec3::splat(20.0)),
            wall_count: walls.len() as u32,
            ..Default::default()
        };
        let corner = |k: u32| {
            v(
                if k & 1 == 0 { -1.0 } else { 1.0 },
                if k & 2 == 0 { 0.0 } else { 2.0 },
                if k & 4 == 0 { -1.0 } else { 1.0 },
            )
        };
        let mut rng = Rng::new(99, 0, 0, 0, 0);
        let mut escaped = 0;
        for i in 0..1_000_000u32 {
            let o = v(2.0 * rng.next_f32() - 1.0, 2.0 * rng.next_f32(), 2.0 * rng.next_f32() - 1.0) * 0.999;
            // A corner, or a point on the edge from a corner along one axis.
            let target = if i % 8 == 0 {
                corner(rng.next_u32() % 8)
            } else {
                let a = corner(rng.next_u32() % 8);
                let mut b = a;
                match rng.next_u32() % 3 {
                    0 => b.x = -a.x,
                    1 => b.y = 2.0 - a.y,
                    _ => b.z = -a.z,
                }
                a.lerp(b, rng.next_f32())
            };
            let Some(dir) = (target - o).try_normalize() else { continue };
            let hit = closest_hit(&Ray { origin: o, dir }, &params, &geometry, NO_WALL, T_FAR);
            escaped += (hit.kind == HitKind::Nothing) as u32;
        }
        assert_eq!(escaped, 0, "rays escaped through a seam");
    }
}
