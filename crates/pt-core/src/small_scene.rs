//! A small scene copied into the invocation's own memory and read at
//! constant indices: the form of the hit tests that a SIMD-on-CPU driver
//! runs fastest.
//!
//! What lavapipe (Mesa 22.3) does with the general loops of
//! [`crate::query::closest_hit`] and [`crate::query::occluded`]:
//! - It reads the uniform block lane by lane: a bounds-checked gather of
//!   one scalar load per lane and component, for every read
//!   (`visit_load_ubo` in `lp_bld_nir_soa.c` broadcasts one load only where
//!   `nir_src_is_always_uniform` holds of the offset, and an offset built
//!   from a descriptor is never that).
//! - An `if` is not a branch: both sides run, under a lane mask. Only a
//!   loop's back edge is, and a loop's body runs at least once, masked off
//!   when it has nothing to do: the shadow-wall loop of a closed room costs
//!   three wall tests per shadow ray.
//!
//! Here the walls and spheres are copied once per pixel and frame, and the
//! tests are unrolled over the copy's capacity: no gathers, no empty loops.
//! The price is a test per unused slot, masked off (2 to 3% of the time
//! each), and the scene must fit ([`SmallScene::fits`]): the kernel comes
//! in the capacities of [`SMALL_SCENE_SIZES`], and the renderer picks the
//! smallest that holds the scene on the adapters where it ran ahead
//! (software ones and NVIDIA's), the general form for other scenes and
//! other adapters (docs/ARCHITECTURE.md has the figures).
//!
//! The two smaller capacities are for a box room: their wall slots are the
//! floor and the ceiling, the back wall and the two side walls, in that
//! order ([`BOX_AXES`]), each with its normal exactly on an axis
//! ([`Wall::normal_axis`]), and they test them with
//! [`crate::wall::intersect_wall_on_axis`]: the same `t` in two fifths of
//! the arithmetic. A scene of five walls whose walls come in another order
//! or lie on no axis takes the capacity of eight walls.
//!
//! The copy can also come from the entry point's specialization constants
//! ([`scene_constants`], [`SmallScene::with_constants`]): set by the host
//! when it makes the pipeline, they let the driver fold the scene, the
//! camera and the settings into the code, operands instead of registers,
//! which is what lavapipe spills most. Compiled in, the copy also holds
//! the walls that can block the light ([`ShadowWalls`]: a light that
//! touches or crosses a wall, a sphere sunk into one), whose shadow tests
//! then cost only the scenes that have such walls
//! ([`SmallScene::fits_compiled`]).

use crate::geometry::Geometry;
use crate::params::FrameParams;
use crate::query::{Hit, SceneView, ShadowWalls, Surface, sphere_blocks, surface_of};
use crate::ray::Ray;
use crate::sphere::Sphere;
use crate::wall::{Wall, intersect_wall, intersect_wall_on_axis};
use spirv_std::glam::Vec3;

/// The capacities (walls, spheres besides the light) the kernel has a
/// small-scene entry point for, smallest first: a box room's five walls
/// ([`BOX_AXES`]: the default scene's) with two spheres, the same box with
/// up to eight, and any closed room of up to eight walls and sixteen
/// spheres.
///
/// Why more than one: where the scene is not compiled into the pipeline
/// (the viewer, whose scene is edited), every slot past the scene's count
/// still costs its masked test, 2 to 3% of the time each; where it is
/// compiled in, the driver drops those slots. Why sixteen spheres: a scene
/// that fits no capacity takes the general loops, which lavapipe runs
/// several times slower (docs/ARCHITECTURE.md has the figures); the last
/// capacity's extra slots cost only the viewer's rooms that are no box.
pub const SMALL_SCENE_SIZES: [(u32, u32); 3] = [(5, 2), (5, 8), (8, 16)];

/// The axis of the normal (0 x, 1 y, 2 z) of each wall slot of the box
/// capacities, `SMALL_SCENE_SIZES[0]` and `[1]`: floor and ceiling, back
/// wall, the two side walls, the order of the scene files of `scenes/`. A
/// scene with fewer walls fills the first slots.
pub const BOX_AXES: [u32; 5] = [1, 1, 2, 0, 0];

/// Whether the capacity with `walls` walls is the box one, whose wall
/// slots have the axes of [`BOX_AXES`].
const fn is_box(walls: u32) -> bool {
    walls == BOX_AXES.len() as u32
}

/// `BOX_AXES[i]` in a form that folds to a constant wherever `i` does
/// (a read of a constant array at a variable index may not).
#[inline(always)]
fn box_axis(i: u32) -> u32 {
    if i < 2 {
        1
    } else if i == 2 {
        2
    } else {
        0
    }
}

/// Whether the first walls of the scene (`params.wall_count` of them, at
/// most five) have the axes of [`BOX_AXES`], in that order.
fn walls_fit_the_box(params: &FrameParams, geometry: &Geometry) -> bool {
    let count = params.wall_count as usize;
    count <= BOX_AXES.len()
        && geometry.walls[..count].iter().zip(BOX_AXES).all(|(w, axis)| w.normal_axis() == Some(axis))
}

/// The largest capacity, which the copy is made for.
const MAX_WALLS: u32 = 8;
const MAX_SPHERES: u32 = 16;

/// Calls `f(0)`, `f(1)`, ..., `f(N - 1)` (N at most 16), each with a literal
/// index: once inlined, every read of the copy has a constant offset, and
/// the driver keeps the copy in registers instead of indexing memory.
#[inline(always)]
fn unrolled<const N: u32>(mut f: impl FnMut(u32)) {
    const { assert!(N <= 16) };
    macro_rules! calls {
        ($($k:literal)*) => { $( if N > $k { f($k); } )* };
    }
    calls!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
}

/// `items[index]` for an index below `N`, read at constant indices only
/// (`items[0]` for any other index).
#[inline(always)]
fn pick<T: Copy, const N: u32, const L: usize>(items: &[T; L], index: u32) -> T {
    let mut item = items[0];
    unrolled::<N>(|i| {
        if i == index {
            item = items[i as usize];
        }
    });
    item
}

/// The first `W` walls and `S` spheres of a scene (at most 8 and 16), with
/// the counts in use. Built once per pixel and frame.
pub struct SmallScene<const W: u32, const S: u32> {
    /// Slots past `W` and `S` are never read, and the compiler drops them.
    walls: [Wall; MAX_WALLS as usize],
    spheres: [Sphere; MAX_SPHERES as usize],
    wall_count: u32,
    sphere_count: u32,
    /// The slots of the walls that shadow rays test, a bit each: the
    /// scene's [`ShadowWalls`] where the copy was compiled in, else none
    /// (where none can block the light, [`SmallScene::fits`]). A constant
    /// either way, so the tests of the other slots fold away.
    shadow_walls: u32,
}

/// Whether capacity `(walls, spheres)` holds the scene's counts and, for
/// a box capacity, its walls ([`BOX_AXES`]).
fn holds(params: &FrameParams, geometry: &Geometry, (walls, spheres): (u32, u32)) -> bool {
    params.wall_count <= walls
        && params.sphere_count <= spheres
        && (!is_box(walls) || walls_fit_the_box(params, geometry))
}

/// The index in [`SMALL_SCENE_SIZES`] of the smallest capacity that fits
/// the scene read from the buffers ([`SmallScene::fits`]), if any: what
/// the renderer runs where the scene is not compiled in.
pub fn smallest_fit(params: &FrameParams, geometry: &Geometry) -> Option<usize> {
    if !ShadowWalls::new(params, geometry).is_empty() {
        return None;
    }
    smallest_fit_compiled(params, geometry)
}

/// The index in [`SMALL_SCENE_SIZES`] of the smallest capacity that fits
/// the scene compiled in ([`SmallScene::fits_compiled`]), if any: what the
/// renderer specializes.
pub fn smallest_fit_compiled(params: &FrameParams, geometry: &Geometry) -> Option<usize> {
    SMALL_SCENE_SIZES.iter().position(|&size| holds(params, geometry, size))
}

impl<const W: u32, const S: u32> SmallScene<W, S> {
    /// Whether this capacity, reading the scene from the buffers
    /// ([`SmallScene::new`]), renders it exactly as the general loops: it
    /// holds every wall and sphere, and no wall can block a shadow ray
    /// (which is what a closed room with the light inside gives), so that
    /// shadow rays test spheres only; and for a box capacity, the walls
    /// have its axes ([`BOX_AXES`]).
    pub fn fits(params: &FrameParams, geometry: &Geometry) -> bool {
        Self::fits_compiled(params, geometry) && ShadowWalls::new(params, geometry).is_empty()
    }

    /// Whether this capacity, with the scene compiled in
    /// ([`scene_constants`]), renders it exactly as the general loops: as
    /// [`SmallScene::fits`], but walls that can block the light are
    /// allowed, since the constants say which they are and shadow rays
    /// test those.
    pub fn fits_compiled(params: &FrameParams, geometry: &Geometry) -> bool {
        holds(params, geometry, (W, S))
    }

    /// The copy of `geometry`'s first walls and spheres. Counts beyond the
    /// capacity are clamped: the caller checks [`SmallScene::fits`].
    pub fn new(params: &FrameParams, geometry: &Geometry) -> Self {
        const { assert!(W <= MAX_WALLS && S <= MAX_SPHERES) };
        let w = &geometry.walls;
        let s = &geometry.spheres;
        Self {
            walls: [w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]],
            spheres: [
                s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8], s[9], s[10], s[11], s[12], s[13], s[14], s[15],
            ],
            wall_count: params.wall_count.min(W),
            sphere_count: params.sphere_count.min(S),
            shadow_walls: 0,
        }
    }
}

/// Words of a scene's constants before its walls: a marker (0 in a
/// module whose constants were not set: read the buffers), the camera
/// (12), the light (7), the background (3), then the image size, the
/// bounce limit, the roulette's start, the wall and sphere counts, the
/// flags and the walls that can block the light (a bit per slot).
const HEAD_WORDS: usize = 31;
/// Words per wall and per sphere.
const WALL_WORDS: usize = 22;
const SPHERE_WORDS: usize = 7;

/// The length of the scene constants of capacity `(walls, spheres)`
/// ([`scene_constants`]): what each small-scene entry point takes as
/// specialization constants.
pub const fn constant_words(walls: u32, spheres: u32) -> usize {
    HEAD_WORDS + walls as usize * WALL_WORDS + spheres as usize * SPHERE_WORDS
}

/// Reads or writes one word of the scene constants at a fixed offset: the
/// one list of offsets ([`visit_constants`]) serves the host, which writes
/// them, and the kernel, which reads them.
trait Words {
    fn word(&mut self, at: usize, value: &mut u32);
    #[inline(always)]
    fn float(&mut self, at: usize, value: &mut f32) {
        let mut bits = value.to_bits();
        self.word(at, &mut bits);
        *value = f32::from_bits(bits);
    }
    #[inline(always)]
    fn vec3(&mut self, at: usize, v: &mut Vec3) {
        self.float(at, &mut v.x);
        self.float(at + 1, &mut v.y);
        self.float(at + 2, &mut v.z);
    }
}

/// The kernel's side: each value from its word.
struct Read<'a, const N: usize>(&'a [u32; N]);

impl<const N: usize> Words for Read<'_, N> {
    #[inline(always)]
    fn word(&mut self, at: usize, value: &mut u32) {
        *value = self.0[at];
    }
}

/// Every per-scene value the kernel reads, each at its offset: what stays
/// the same over a render (camera, light, settings, the copy's walls and
/// spheres); the per-frame values (frame, sample counts, seed, tile,
/// display settings) are never in it.
#[inline(always)]
fn visit_constants<const W: u32, const S: u32>(
    words: &mut impl Words,
    params: &mut FrameParams,
    shadow_walls: &mut u32,
    walls: &mut [Wall; MAX_WALLS as usize],
    spheres: &mut [Sphere; MAX_SPHERES as usize],
) {
    let c = &mut params.camera;
    words.vec3(1, &mut c.position);
    words.vec3(4, &mut c.forward);
    words.vec3(7, &mut c.right);
    words.vec3(10, &mut c.up);
    let l = &mut params.light;
    words.vec3(13, &mut l.center);
    words.float(16, &mut l.radius);
    words.vec3(17, &mut l.radiance);
    words.vec3(20, &mut params.background);
    words.word(23, &mut params.width);
    words.word(24, &mut params.height);
    words.word(25, &mut params.max_bounces);
    words.word(26, &mut params.rr_start);
    words.word(27, &mut params.wall_count);
    words.word(28, &mut params.sphere_count);
    words.word(29, &mut params.flags);
    words.word(30, shadow_walls);
    unrolled::<W>(|i| {
        let (w, at) = (&mut walls[i as usize], HEAD_WORDS + i as usize * WALL_WORDS);
        words.vec3(at, &mut w.corner);
        words.vec3(at + 3, &mut w.edge_u);
        words.vec3(at + 6, &mut w.edge_v);
        words.vec3(at + 9, &mut w.normal);
        words.float(at + 12, &mut w.enclosure_side);
        words.vec3(at + 13, &mut w.coord_u);
        words.vec3(at + 16, &mut w.coord_v);
        words.vec3(at + 19, &mut w.albedo);
    });
    unrolled::<S>(|i| {
        let (s, at) = (&mut spheres[i as usize], HEAD_WORDS + W as usize * WALL_WORDS + i as usize * SPHERE_WORDS);
        words.vec3(at, &mut s.center);
        words.float(at + 3, &mut s.radius);
        words.vec3(at + 4, &mut s.albedo);
    });
}

/// The scene constants of capacity `(W, S)` for `params` and `geometry`,
/// `constant_words(W, S)` words: compiled into a small-scene pipeline, they
/// let the driver fold the scene into the code (a literal operand instead
/// of a register or a spill per value on lavapipe). The caller checks
/// [`SmallScene::fits_compiled`].
#[cfg(not(target_arch = "spirv"))]
pub fn scene_constants<const W: u32, const S: u32>(params: &FrameParams, geometry: &Geometry) -> Vec<u32> {
    struct Write(Vec<u32>);
    impl Words for Write {
        fn word(&mut self, at: usize, value: &mut u32) {
            self.0[at] = *value;
        }
    }
    let mut words = Write(vec![0; constant_words(W, S)]);
    words.0[0] = 1;
    let (mut params, mut walls, mut spheres) =
        (*params, [Wall::default(); MAX_WALLS as usize], [Sphere::default(); MAX_SPHERES as usize]);
    walls.copy_from_slice(&geometry.walls[..MAX_WALLS as usize]);
    spheres.copy_from_slice(&geometry.spheres[..MAX_SPHERES as usize]);
    // The caller checked that the capacity holds every wall: no bit past W.
    let mut shadow_walls = ShadowWalls::new(&params, geometry).first_32();
    visit_constants::<W, S>(&mut words, &mut params, &mut shadow_walls, &mut walls, &mut spheres);
    words.0
}

impl<const W: u32, const S: u32> SmallScene<W, S> {
    /// The frame's parameters and the scene's copy: from `constants` where
    /// they were set ([`scene_constants`]), the per-frame values from
    /// `params` still; else from the buffers, as [`SmallScene::new`].
    #[inline(always)]
    pub fn with_constants<const N: usize>(
        params: &FrameParams,
        geometry: &Geometry,
        constants: &[u32; N],
    ) -> (FrameParams, Self) {
        if constants[0] == 0 {
            (*params, Self::new(params, geometry))
        } else {
            let mut params = *params;
            let (mut walls, mut spheres) =
                ([Wall::default(); MAX_WALLS as usize], [Sphere::default(); MAX_SPHERES as usize]);
            let mut shadow_walls = 0;
            visit_constants::<W, S>(&mut Read(constants), &mut params, &mut shadow_walls, &mut walls, &mut spheres);
            let (wall_count, sphere_count) = (params.wall_count.min(W), params.sphere_count.min(S));
            (params, Self { walls, spheres, wall_count, sphere_count, shadow_walls })
        }
    }

    /// The nearest wall hit in (0, `t_max`) but `skip_wall`, unrolled: the
    /// walls' part of `closest_hit`, and alone `first_wall`.
    #[inline(always)]
    fn nearest_wall(&self, ray: &Ray, skip_wall: u32, t_max: f32) -> Hit {
        let mut hit = Hit::none(t_max);
        unrolled::<W>(|i| {
            if i < self.wall_count && i != skip_wall {
                hit.take_wall(i, self.wall_t(i, ray, hit.t));
            }
        });
        hit
    }

    /// Where the ray meets wall slot `i` in (0, `t_max`), `t_max` if
    /// nowhere: on the slot's axis in a box capacity, which gives the same
    /// `t` in less arithmetic.
    #[inline(always)]
    fn wall_t(&self, i: u32, ray: &Ray, t_max: f32) -> f32 {
        if is_box(W) {
            intersect_wall_on_axis(&self.walls[i as usize], box_axis(i), ray, 0.0, t_max)
        } else {
            intersect_wall(&self.walls[i as usize], ray, 0.0, t_max)
        }
    }
}

impl<const W: u32, const S: u32> SceneView for SmallScene<W, S> {
    /// The same tests as [`crate::query::closest_hit`], in the same
    /// order, on the copy.
    fn closest_hit(&self, ray: &Ray, params: &FrameParams, skip_wall: u32, t_max: f32) -> Hit {
        let mut hit = self.nearest_wall(ray, skip_wall, t_max);
        unrolled::<S>(|i| {
            if i < self.sphere_count {
                hit.test_sphere(i, &self.spheres[i as usize], ray);
            }
        });
        hit.test_light(&params.light, ray);
        hit
    }

    fn first_wall(&self, ray: &Ray, _params: &FrameParams) -> Hit {
        self.nearest_wall(ray, crate::query::NO_WALL, crate::query::T_FAR)
    }

    /// The spheres, and the walls of the copy's own mask: none where the
    /// scene is read from the buffers ([`SmallScene::fits`] leaves no wall
    /// that can block a shadow ray), the scene's [`ShadowWalls`] where it is
    /// compiled in. The same answer as [`crate::query::occluded`].
    fn occluded(&self, ray: &Ray, _params: &FrameParams, _walls: &ShadowWalls, skip_wall: u32, t_max: f32) -> bool {
        let mut blocked = false;
        unrolled::<S>(|i| blocked |= i < self.sphere_count && sphere_blocks(&self.spheres[i as usize], ray, t_max));
        unrolled::<W>(|i| {
            blocked |= (self.shadow_walls >> i) & 1 != 0 && i != skip_wall && self.wall_t(i, ray, t_max) < t_max
        });
        blocked
    }

    /// The object hit, picked from the copy by comparing the hit's index
    /// with each constant index: the buffer read at the hit's index would
    /// be a gather on lavapipe, at two hits (the path's and a
    /// connection's) in every pass of the path loop.
    #[inline(always)]
    fn surface(&self, hit: &Hit, ray: &Ray) -> Surface {
        surface_of(
            hit,
            ray,
            || pick::<Wall, W, { MAX_WALLS as usize }>(&self.walls, hit.index),
            || pick::<Sphere, S, { MAX_SPHERES as usize }>(&self.spheres, hit.index),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{SphereLight, light_cone};
    use crate::query::{HitKind, closest_hit};
    use crate::rng::Rng;
    use spirv_std::glam::Vec3;

    /// Up to 8 walls: the default room (floor, ceiling, back, left, right),
    /// a front wall and two panels inside; up to 16 spheres.
    fn scene(walls: usize, spheres: usize, light: Vec3) -> (FrameParams, Geometry) {
        let v = Vec3::new;
        let a = Vec3::splat(0.73);
        let [floor, ceiling, back, left, right, front] = crate::test_support::closed_room();
        let mut all_walls = [
            floor,
            ceiling,
            back,
            left,
            right,
            front,
            Wall::new(v(-0.5, 0.2, 0.0), v(0.6, 0.3, 0.0), v(0.0, 0.5, 0.4), a),
            Wall::new(v(0.2, 1.0, -0.5), v(0.5, 0.0, 0.2), v(0.1, 0.4, 0.0), a),
        ];
        let mut all_spheres = [
            Sphere::new(v(-0.45, 0.40, -0.30), 0.40, a),
            Sphere::new(v(0.50, 0.28, 0.35), 0.28, a),
            Sphere::new(v(0.6, 1.5, -0.6), 0.2, a),
            Sphere::new(v(-0.6, 1.2, 0.5), 0.1, a),
            Sphere::new(v(0.0, 0.25, 0.65), 0.2, a),
            Sphere::new(v(-0.7, 1.7, -0.7), 0.18, a),
            Sphere::new(v(0.65, 0.9, 0.65), 0.15, a),
            Sphere::new(v(-0.1, 1.0, -0.75), 0.15, a),
            Sphere::new(v(0.7, 0.2, -0.7), 0.15, a),
            Sphere::new(v(-0.75, 0.15, 0.75), 0.12, a),
            Sphere::new(v(0.3, 1.2, 0.2), 0.1, a),
            Sphere::new(v(-0.3, 1.5, 0.1), 0.12, a),
            Sphere::new(v(0.8, 1.8, 0.1), 0.12, a),
            Sphere::new(v(-0.8, 0.8, -0.1), 0.12, a),
            Sphere::new(v(0.1, 0.6, -0.2), 0.12, a),
            Sphere::new(v(0.35, 0.1, -0.1), 0.1, a),
        ];
        // Each object its own albedo, so that shading data read from the
        // wrong one shows.
        for (k, w) in all_walls.iter_mut().enumerate() {
            w.albedo = Vec3::new(0.1 * k as f32, 0.5, 0.9);
        }
        for (k, s) in all_spheres.iter_mut().enumerate() {
            s.albedo = Vec3::new(0.9, 0.05 * k as f32, 0.5);
        }
        let geometry = Geometry::new(&all_walls[..walls], &all_spheres[..spheres]).unwrap();
        let params = FrameParams {
            light: SphereLight::new(light, 0.15, Vec3::splat(20.0)),
            wall_count: walls as u32,
            sphere_count: spheres as u32,
            ..Default::default()
        };
        (params, geometry)
    }

    const LIGHT: Vec3 = Vec3::new(0.0, 1.7, 0.0);
    /// A light of `scene`'s radius 0.15 whose top crosses the ceiling
    /// (y = 2): the ceiling can block it.
    const THROUGH_CEILING: Vec3 = Vec3::new(0.1, 1.95, -0.2);

    /// The copy of capacity `(W, S)` with the scene compiled in, as a
    /// specialized pipeline reads it (`N` is `constant_words(W, S)`).
    fn compiled<const W: u32, const S: u32, const N: usize>(
        params: &FrameParams,
        geometry: &Geometry,
    ) -> SmallScene<W, S> {
        let constants: [u32; N] = scene_constants::<W, S>(params, geometry).try_into().expect("N words");
        SmallScene::<W, S>::with_constants(params, geometry, &constants).1
    }

    #[test]
    fn fits_a_room_with_the_light_inside_and_nothing_more() {
        let fits = |walls, spheres, light| {
            let (params, geometry) = scene(walls, spheres, light);
            SmallScene::<8, 16>::fits(&params, &geometry)
        };
        assert!(fits(5, 2, LIGHT), "the default scene");
        assert!(fits(6, 8, LIGHT), "a closed room, eight spheres");
        assert!(fits(5, 16, LIGHT), "the box, sixteen spheres");
        assert!(!fits(7, 2, LIGHT), "a panel inside the room can shadow the light");
        assert!(!fits(5, 2, Vec3::new(0.0, 1.0, -1.6)), "the back wall is between the light and the room");
        let (mut params, geometry) = scene(5, 2, LIGHT);
        assert!(SmallScene::<5, 2>::fits(&params, &geometry));
        params.sphere_count = 3;
        assert!(!SmallScene::<5, 2>::fits(&params, &geometry));
        assert!(SmallScene::<5, 8>::fits(&params, &geometry));
        assert!(SmallScene::<8, 16>::fits(&params, &geometry));
        params.sphere_count = 9;
        assert!(!SmallScene::<5, 8>::fits(&params, &geometry));
        assert!(SmallScene::<8, 16>::fits(&params, &geometry));
        params.sphere_count = 17;
        assert!(!SmallScene::<8, 16>::fits(&params, &geometry));
        assert_eq!(smallest_fit(&params, &geometry), None, "seventeen spheres: the general loops");
        params.sphere_count = 2;
        params.wall_count = 9;
        assert!(!SmallScene::<8, 16>::fits(&params, &geometry));
        // The renderer's choice: the smallest capacity that fits.
        let choice = |walls, spheres, light| {
            let (params, geometry) = scene(walls, spheres, light);
            smallest_fit(&params, &geometry).map(|i| SMALL_SCENE_SIZES[i])
        };
        assert_eq!(choice(5, 2, LIGHT), Some((5, 2)));
        assert_eq!(choice(5, 3, LIGHT), Some((5, 8)), "the box, more spheres");
        assert_eq!(choice(5, 8, LIGHT), Some((5, 8)));
        assert_eq!(choice(5, 9, LIGHT), Some((8, 16)), "the box, more spheres than its forms hold");
        assert_eq!(choice(5, 16, LIGHT), Some((8, 16)));
        assert_eq!(choice(6, 0, LIGHT), Some((8, 16)));
        assert_eq!(choice(6, 16, LIGHT), Some((8, 16)));
        assert_eq!(choice(7, 2, LIGHT), None);
        assert_eq!(choice(5, 2, Vec3::new(0.0, 1.0, -1.6)), None);
        assert_eq!(choice(5, 2, THROUGH_CEILING), None);
        // Compiled in, the copy holds the walls that can block the light.
        let compiled_choice = |walls, spheres, light| {
            let (params, geometry) = scene(walls, spheres, light);
            smallest_fit_compiled(&params, &geometry).map(|i| SMALL_SCENE_SIZES[i])
        };
        assert_eq!(compiled_choice(5, 2, LIGHT), Some((5, 2)));
        assert_eq!(compiled_choice(5, 2, THROUGH_CEILING), Some((5, 2)));
        assert_eq!(compiled_choice(5, 2, Vec3::new(0.0, 1.0, -1.6)), Some((5, 2)));
        assert_eq!(compiled_choice(5, 5, THROUGH_CEILING), Some((5, 8)));
        assert_eq!(compiled_choice(7, 2, LIGHT), Some((8, 16)), "a panel inside the room");
        assert_eq!(compiled_choice(5, 12, THROUGH_CEILING), Some((8, 16)));
        let (mut params, geometry) = scene(5, 16, THROUGH_CEILING);
        params.sphere_count = 17;
        assert_eq!(smallest_fit_compiled(&params, &geometry), None, "seventeen spheres");
        let (params, geometry) = scene(7, 2, THROUGH_CEILING);
        assert!(SmallScene::<8, 16>::fits_compiled(&params, &geometry));
        assert!(!SmallScene::<8, 16>::fits(&params, &geometry));
        assert!(!SmallScene::<5, 8>::fits_compiled(&params, &geometry), "seven walls");
    }

    /// The scene constants give back exactly the scene they were made of:
    /// every per-scene value of the parameters and the copy's walls and
    /// spheres, for each capacity, with the per-frame values still read
    /// from the parameters given. Unset constants (zeros) read the buffers.
    #[test]
    fn scene_constants_give_back_the_scene() {
        fn check<const W: u32, const S: u32, const N: usize>(walls: usize, spheres: usize) {
            let (mut params, geometry) = scene(walls, spheres, LIGHT);
            params.rr_start = 3;
            params.flags = 0x1d7;
            params.background = Vec3::new(0.1, 0.2, 0.3);
            let constants: [u32; N] = scene_constants::<W, S>(&params, &geometry).try_into().expect("N words");
            assert_eq!(N, constant_words(W, S));
            // The frame's own values, and nothing of the scene, in the buffers.
            let frame =
                FrameParams { frame: 9, samples_per_frame: 3, sample_offset: 12, seed: 4, ..Default::default() };
            let empty = Geometry::new(&[], &[]).unwrap();
            let (got, copy) = SmallScene::<W, S>::with_constants(&frame, &empty, &constants);
            let want = FrameParams { frame: 9, samples_per_frame: 3, sample_offset: 12, seed: 4, ..params };
            assert_eq!(got, want);
            let reference = SmallScene::<W, S>::new(&params, &geometry);
            assert_eq!((copy.wall_count, copy.sphere_count), (walls as u32, spheres as u32));
            assert_eq!(copy.shadow_walls, ShadowWalls::new(&params, &geometry).first_32());
            assert_eq!(reference.shadow_walls, 0, "read from the buffers, the scene has none");
            assert_eq!(copy.walls[..walls], reference.walls[..walls]);
            assert_eq!(copy.spheres[..spheres], reference.spheres[..spheres]);
            // Unset: the buffers' values.
            let (got, copy) = SmallScene::<W, S>::with_constants(&params, &geometry, &[0; N]);
            assert_eq!(got, params);
            assert_eq!((copy.walls, copy.spheres, copy.shadow_walls), (reference.walls, reference.spheres, 0));
        }
        check::<5, 2, { constant_words(5, 2) }>(5, 2);
        check::<5, 8, { constant_words(5, 8) }>(5, 8);
        check::<5, 8, { constant_words(5, 8) }>(5, 3);
        check::<8, 16, { constant_words(8, 16) }>(8, 16);
        check::<8, 16, { constant_words(8, 16) }>(6, 3);
        check::<8, 16, { constant_words(8, 16) }>(5, 11);
        // The walls that can block the light: the two panels of 8 walls.
        let (params, geometry) = scene(8, 8, LIGHT);
        assert_eq!(compiled::<8, 16, { constant_words(8, 16) }>(&params, &geometry).shadow_walls, 0b1100_0000);
    }

    #[test]
    fn the_box_slots_fold_to_their_axes() {
        assert_eq!((0..5).map(box_axis).collect::<Vec<_>>(), BOX_AXES);
        assert!(is_box(5) && !is_box(8));
        assert_eq!(SMALL_SCENE_SIZES[0].0, BOX_AXES.len() as u32, "the smallest capacity is the box");
        assert_eq!(SMALL_SCENE_SIZES[1].0, BOX_AXES.len() as u32, "so is the next, with more spheres");
    }

    #[test]
    fn the_box_capacity_takes_walls_on_its_axes_in_its_order_only() {
        let (params, geometry) = scene(5, 2, LIGHT);
        let with_walls = |walls: &[Wall]| {
            // Rebuilt, so that each wall knows it bounds the scene.
            let g = Geometry::new(walls, &geometry.spheres[..2]).unwrap();
            let p = FrameParams { wall_count: walls.len() as u32, ..params };
            (SmallScene::<5, 2>::fits(&p, &g), smallest_fit(&p, &g).map(|i| SMALL_SCENE_SIZES[i]))
        };
        let [floor, ceiling, back, left, right, _] = crate::test_support::closed_room();
        assert_eq!(with_walls(&[floor, ceiling, back, left, right]), (true, Some((5, 2))));
        assert_eq!(with_walls(&[floor, ceiling, back]), (true, Some((5, 2))), "the first slots");
        // The side walls first: the slots' axes differ, the capacity of
        // eight walls (every wall tested in full) takes the scene.
        assert_eq!(with_walls(&[left, right, back, floor, ceiling]), (false, Some((8, 16))));
        // A floor whose edges are turned in its plane is still on its axis;
        // a tilted ceiling is not.
        let turned =
            Wall::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(-1.0, 0.0, -1.0), floor.albedo);
        assert_eq!(with_walls(&[turned, ceiling, back, left, right]), (true, Some((5, 2))));
        let tilted =
            Wall::new(ceiling.corner, ceiling.edge_u, ceiling.edge_v + Vec3::new(0.0, 0.01, 0.0), ceiling.albedo);
        assert_eq!(with_walls(&[floor, tilted, back, left, right]), (false, Some((8, 16))));
    }

    /// Capacity `(W, S)`'s copy read from the buffers and compiled in, and
    /// whether the scene fits the first form.
    fn forms<const W: u32, const S: u32, const N: usize>(
        params: &FrameParams,
        geometry: &Geometry,
    ) -> (Box<dyn SceneView>, Box<dyn SceneView>, bool) {
        let buffers = SmallScene::<W, S>::new(params, geometry);
        (Box::new(buffers), Box::new(compiled::<W, S, N>(params, geometry)), SmallScene::<W, S>::fits(params, geometry))
    }

    /// Rays from random points in the room in random directions, and from
    /// points on its surfaces (leaving their wall): the copy finds exactly
    /// the hit that the uniform block's loops find, for every count of
    /// walls and spheres it holds, read from the buffers and compiled in;
    /// shadow rays toward the light are blocked exactly when the general
    /// test says so, where the scene fits the form (compiled in, also
    /// where walls can block the light: a panel, a light through the
    /// ceiling, a light behind the back wall).
    #[test]
    fn answers_exactly_as_the_general_loops() {
        let mut rng = Rng::new(9, 8, 7, 6, 5);
        let mut shadow_rays = (0, 0);
        let behind_the_back_wall = Vec3::new(0.0, 1.0, -1.6);
        let inside = [(0, 0), (3, 1), (5, 2), (5, 3), (5, 8), (5, 9), (6, 4), (8, 3), (8, 8), (6, 16), (7, 2)]
            .map(|(w, s)| (w, s, LIGHT));
        let through = [(5, 2), (5, 6), (5, 13), (6, 2)].map(|(w, s)| (w, s, THROUGH_CEILING));
        for (walls, spheres, light) in inside.into_iter().chain(through).chain([(5, 2, behind_the_back_wall)]) {
            let (params, geometry) = scene(walls, spheres, light);
            // The smallest capacity that holds the counts, as the renderer
            // picks (the first five walls of `scene` are the box's).
            let (buffers, compiled, fits) = if walls <= 5 && spheres <= 2 {
                forms::<5, 2, { constant_words(5, 2) }>(&params, &geometry)
            } else if walls <= 5 && spheres <= 8 {
                forms::<5, 8, { constant_words(5, 8) }>(&params, &geometry)
            } else {
                forms::<8, 16, { constant_words(8, 16) }>(&params, &geometry)
            };
            let (buffers, compiled) = (&*buffers, &*compiled);
            let shadow_walls = ShadowWalls::new(&params, &geometry);
            assert_eq!(fits, shadow_walls.is_empty(), "{walls} walls, light at {light}");
            let mut kinds = [0u32; 4];
            let mut seen = [0u32; 4];
            // Shadow rays that a wall alone blocks.
            let mut by_walls = 0;
            for i in 0..4000 {
                let mut r = || rng.next_f32();
                let (origin, skip) = if i % 2 == 0 || walls == 0 {
                    (Vec3::new(2.0 * r() - 1.0, 2.0 * r(), 2.0 * r() - 1.0), u32::MAX)
                } else {
                    let k = i as u32 % walls as u32;
                    let w = &geometry.walls[k as usize];
                    (w.corner + w.edge_u * r() + w.edge_v * r(), k)
                };
                let z = 1.0 - 2.0 * r();
                let phi = 2.0 * crate::sampling::PI * r();
                let s = (1.0 - z * z).max(0.0).sqrt();
                let ray = Ray { origin, dir: Vec3::new(s * phi.cos(), s * phi.sin(), z) };
                let want = closest_hit(&ray, &params, &geometry, skip, f32::MAX);
                for small in [buffers, compiled] {
                    let got = small.closest_hit(&ray, &params, skip, f32::MAX);
                    assert_eq!((got.t, got.kind, got.index), (want.t, want.kind, want.index), "{walls} walls, ray {i}");
                    if want.kind == HitKind::Wall || want.kind == HitKind::Sphere {
                        // The shading data, picked from the copy, is the scene's own.
                        let (a, b) = (small.surface(&got, &ray), geometry.surface(&want, &ray));
                        assert_eq!(
                            (a.point, a.normal, a.albedo, a.magnitude, a.wall),
                            (b.point, b.normal, b.albedo, b.magnitude, b.wall),
                            "{walls} walls, ray {i}"
                        );
                    }
                }
                kinds[want.kind as usize] += 1;
                if want.kind == HitKind::Wall || want.kind == HitKind::Sphere {
                    seen[want.kind as usize] |= 1 << want.index;
                }
                let (dir, dist) = light_cone(&params.light, origin).sample(r(), r());
                let shadow = Ray { origin, dir };
                let want = geometry.occluded(&shadow, &params, &shadow_walls, skip, dist);
                assert_eq!(compiled.occluded(&shadow, &params, &shadow_walls, skip, dist), want, "shadow ray {i}");
                let spheres_alone = buffers.occluded(&shadow, &params, &shadow_walls, skip, dist);
                if fits {
                    assert_eq!(spheres_alone, want, "shadow ray {i}");
                }
                by_walls += (want && !spheres_alone) as u32;
                shadow_rays = (shadow_rays.0 + 1, shadow_rays.1 + want as u32);
            }
            // Every kind of hit the scene has was met.
            assert!(kinds[HitKind::Light as usize] > 0 && (walls == 0 || kinds[HitKind::Wall as usize] > 0));
            assert!(spheres == 0 || kinds[HitKind::Sphere as usize] > 0, "{kinds:?}");
            // Every wall and sphere was hit, so each index's pick was checked.
            assert_eq!(seen[HitKind::Wall as usize], (1 << walls) - 1, "walls hit");
            assert_eq!(seen[HitKind::Sphere as usize], (1 << spheres) - 1, "spheres hit");
            // Where walls can block the light, some shadow rays are blocked
            // by walls alone: the compiled form's wall tests were needed.
            assert_eq!(by_walls > 20, !fits, "{walls} walls, light at {light}: {by_walls} blocked by walls alone");
        }
        // Some shadow rays were blocked, most not.
        assert!(shadow_rays.1 > 100 && shadow_rays.1 < shadow_rays.0 / 2, "{shadow_rays:?}");
    }
}
