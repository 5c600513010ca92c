//! The path loop: closest hits, next-event estimation with MIS, Russian
//! roulette, and the per-pixel sample loop that the kernel wraps.

use spirv_std::glam::{Vec2, Vec3};

use crate::accum::{PixelSamples, is_finite, kahan_add};
use crate::geometry::{Geometry, MAX_SPHERES, MAX_WALLS};
use crate::light::{GlowLobe, LightCone, SphereLight, light_cone};
use crate::params::{FLAG_GLOW, FLAG_MIS, FLAG_NEE, FLAG_RR_LUMINANCE, FLAG_SOBOL, FLAG_SOBOL_DEEP, FrameParams};
use crate::ray::{Ray, offset_origin};
use crate::rng::Rng;
use crate::sampler::{Sampler, SobolSampler};
use crate::sampling::{PI, about_axis, cosine_polar, power_heuristic};
use crate::small_scene::SmallScene;
use crate::sphere::{Sphere, intersect_sphere, sphere_hit_point};
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
        let t = intersect_wall(wall, ray, 0.0, self.t);
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
    intersect_sphere(sphere.center, sphere.radius, ray, 0.0, t_max) < t_max
}

/// "No limit" for ray parameters. Not `f32::INFINITY`: naga rejects an
/// infinite literal in a SPIR-V module.
pub const T_FAR: f32 = f32::MAX;

/// No wall to skip.
pub const NO_WALL: u32 = u32::MAX;

/// Minimum Russian roulette survival probability: a path is never killed
/// with certainty, and its weight grows by at most 1/0.05 = 20.
pub const RR_MIN_SURVIVAL: f32 = 0.05;

/// The walls and spheres in use, clamped to the block's arrays: the loops
/// below then need no bounds checks, and a bad count cannot read past them.
fn counts(params: &FrameParams) -> (u32, u32) {
    (params.wall_count.min(MAX_WALLS as u32), params.sphere_count.min(MAX_SPHERES as u32))
}

/// The closest hit in (0, `t_max`) over walls, spheres and the light, brute
/// force. `skip_wall` is the wall the ray leaves from: a plane cannot be hit
/// again by a ray that leaves it, so testing it could only find rounding
/// noise.
pub fn closest_hit(ray: &Ray, params: &FrameParams, geometry: &Geometry, skip_wall: u32, t_max: f32) -> Hit {
    let mut hit = Hit::none(t_max);
    let (wall_count, sphere_count) = counts(params);
    let mut i = 0;
    while i < wall_count {
        if i != skip_wall {
            hit.test_wall(i, &geometry.walls[i as usize], ray);
        }
        i += 1;
    }
    let mut i = 0;
    while i < sphere_count {
        hit.test_sphere(i, &geometry.spheres[i as usize], ray);
        i += 1;
    }
    hit.test_light(&params.light, ray);
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

    /// Whether no wall can block a shadow ray.
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

/// The walls and spheres a path is traced against, and how they are read:
/// the uniform block itself ([`Geometry`], in loops, for any scene), or a
/// copy of a small one ([`crate::small_scene::SmallScene`]).
pub trait Objects {
    /// The closest hit in (0, `t_max`): see [`closest_hit`].
    fn closest_hit(&self, ray: &Ray, params: &FrameParams, skip_wall: u32, t_max: f32) -> Hit;
    /// Whether the shadow ray is blocked in (0, `t_max`): see [`occluded`].
    fn occluded(&self, ray: &Ray, params: &FrameParams, walls: &ShadowWalls, skip_wall: u32, t_max: f32) -> bool;
}

impl Objects for Geometry {
    fn closest_hit(&self, ray: &Ray, params: &FrameParams, skip_wall: u32, t_max: f32) -> Hit {
        closest_hit(ray, params, self, skip_wall, t_max)
    }

    fn occluded(&self, ray: &Ray, params: &FrameParams, walls: &ShadowWalls, skip_wall: u32, t_max: f32) -> bool {
        occluded(ray, params, self, walls, skip_wall, t_max)
    }
}

/// Counts the rays a path traces (closest-hit and shadow rays), for the
/// benchmark's rays per second. The renderers use [`NoRayCount`], which
/// compiles to nothing.
pub trait RayCounter {
    /// One ray was traced.
    fn ray(&mut self);
}

/// The counter that counts nothing.
pub struct NoRayCount;

impl RayCounter for NoRayCount {
    #[inline]
    fn ray(&mut self) {}
}

/// A counter of rays (CPU only: the kernel never counts).
#[cfg(not(target_arch = "spirv"))]
#[derive(Default)]
pub struct RayCount(pub u64);

#[cfg(not(target_arch = "spirv"))]
impl RayCounter for RayCount {
    #[inline]
    fn ray(&mut self) {
        self.0 += 1;
    }
}

/// Probability that BSDF sampling draws from the glow lobe instead of the
/// cosine lobe (with `FLAG_GLOW`): chosen by `pathtracer bench`.
pub const GLOW_PROBABILITY: f32 = 0.25;

/// BSDF sampling at a diffuse vertex: the cosine lobe about the shading
/// normal, mixed with the glow lobe around the light. One draw picks a lobe
/// with fixed probabilities and the estimate divides by the mixture's
/// density (one-sample MIS with the balance heuristic; Veach 1997, 9.2.4),
/// which is never below 3/4 of the cosine lobe's: no direction the BSDF
/// reaches gets a large weight.
struct Scatter {
    n: Vec3,
    glow: GlowLobe,
    /// 0 without the glow lobe.
    glow_probability: f32,
}

impl Scatter {
    /// Sampling about unit normal `n`, with the glow lobe around `cone` when
    /// `glow` is set, the cone is not empty and the lobe is not wholly below
    /// the surface (the unlit side of a sphere keeps all of its samples).
    /// Without it the lobe is not built (a logarithm per vertex).
    fn new(n: Vec3, cone: &LightCone, glow: bool) -> Self {
        let glow = glow && !cone.is_empty();
        let lobe = if glow { GlowLobe::new(cone) } else { GlowLobe::UNUSED };
        let glow_probability = if glow && !lobe.below_horizon(n) { GLOW_PROBABILITY } else { 0.0 };
        Self { n, glow: lobe, glow_probability }
    }

    /// A direction from `u` in [0, 1)^2: `u.x` picks the lobe and is
    /// stretched back to [0, 1) for it, which keeps its stratification.
    ///
    /// Both lobes are symmetric about an axis, so only the axis and the
    /// polar angle depend on the pick; the basis and the turn about the axis
    /// are shared. SIMD lanes that pick different lobes then run one basis
    /// and one sine and cosine, not both lobes' (a GPU runs both sides of a
    /// divergent branch).
    fn sample(&self, u: Vec2) -> Vec3 {
        let p = self.glow_probability;
        let (axis, (cos_theta, sin_theta)) = if u.x < p {
            (self.glow.axis(), self.glow.polar(u.x / p))
        } else {
            (self.n, cosine_polar((u.x - p) / (1.0 - p)))
        };
        about_axis(axis, cos_theta, sin_theta, u.y)
    }

    /// Solid-angle density of [`Scatter::sample`] at unit `dir`.
    fn pdf(&self, dir: Vec3) -> f32 {
        let p = self.glow_probability;
        let cosine = self.n.dot(dir).max(0.0) * (1.0 / PI);
        let glow = if p > 0.0 { self.glow.pdf(dir) } else { 0.0 };
        (1.0 - p) * cosine + p * glow
    }
}

/// One path in flight: what the path loop carries from one segment to the
/// next. [`Path::step`] traces one segment; a path is unbiased for
/// `params.max_bounces` scattering events (DESIGN sections 4 and 5).
///
/// `repr(C)` with the ray as two vectors and the sampler last: naga rounds a
/// struct's size up to 16 bytes when it holds a `Vec3`, so a `Ray` member
/// (24 bytes, rounded to 32) followed by another member at Rust's offset 24
/// fails validation as an overlap, and Rust's own field order would not be
/// the declared one.
#[repr(C)]
pub struct Path<S> {
    /// Origin of the ray to trace next.
    origin: Vec3,
    /// Its unit direction.
    dir: Vec3,
    /// Radiance gathered so far: the sample's value once the path has ended.
    pub radiance: Vec3,
    throughput: Vec3,
    bounces: u32,
    skip_wall: u32,
    /// Densities with which the BSDF and NEE could have produced the current
    /// ray's direction (solid angle), for the MIS weight of a light hit.
    bsdf_pdf: f32,
    nee_pdf: f32,
    sampler: S,
}

impl<S: Sampler> Path<S> {
    /// Camera sample `s` of pixel (`x`, `y`) in this frame, whose sampler
    /// part is `pixel` (`S::for_pixel(x, y, params)`): a primary ray
    /// jittered uniformly in the pixel (a box filter) by the sampler's first
    /// pair.
    pub fn camera(x: u32, y: u32, pixel: S::Pixel, s: u32, params: &FrameParams) -> Self {
        let mut sampler = S::for_camera_sample(pixel, s, params);
        let u = sampler.next_2d();
        let ray = params.camera.ray(x as f32 + u.x, y as f32 + u.y, params.width, params.height);
        Self {
            origin: ray.origin,
            dir: ray.dir,
            sampler,
            radiance: Vec3::ZERO,
            throughput: Vec3::ONE,
            bounces: 0,
            skip_wall: NO_WALL,
            bsdf_pdf: 0.0,
            nee_pdf: 0.0,
        }
    }

    /// Traces the current ray to its closest hit among `objects` and shades
    /// it: emission, one shadow ray (NEE), the next direction and Russian
    /// roulette. `objects` holds the walls and spheres of `geometry`, which
    /// shading reads the hit's normal and albedo from. Shadow rays test
    /// `shadow_walls`, which must be `ShadowWalls::new(params, geometry)`.
    /// Returns whether the path has ended; its rays are counted in `rays`
    /// ([`NoRayCount`] in the renderers).
    pub fn step<O: Objects, C: RayCounter>(
        &mut self,
        params: &FrameParams,
        geometry: &Geometry,
        objects: &O,
        shadow_walls: &ShadowWalls,
        rays: &mut C,
    ) -> bool {
        let nee = params.flags & FLAG_NEE != 0;
        let mis = params.flags & FLAG_MIS != 0;
        let light = params.light;
        let ray = Ray { origin: self.origin, dir: self.dir };

        rays.ray();
        let hit = objects.closest_hit(&ray, params, self.skip_wall, T_FAR);
        if hit.kind == HitKind::Nothing {
            self.radiance += self.throughput * params.background;
            return true;
        }
        if hit.kind == HitKind::Light {
            // The light emits outward only; from inside it shows nothing.
            let front = ray.dir.dot(ray.at(hit.t) - light.center) < 0.0;
            if front {
                let weight = if self.bounces == 0 || !nee || self.nee_pdf == 0.0 {
                    // Camera rays, or no NEE could have found this light.
                    1.0
                } else if mis {
                    power_heuristic(self.bsdf_pdf, self.nee_pdf)
                } else {
                    // NEE alone accounts for light reached after a bounce.
                    0.0
                };
                self.radiance += self.throughput * light.radiance * weight;
            }
            return true;
        }
        if self.bounces >= params.max_bounces {
            return true;
        }

        // The surface point, its normal, its albedo and a bound on the
        // magnitudes its coordinates were computed from.
        let (p, normal, albedo, magnitude, wall_index) = if hit.kind == HitKind::Wall {
            let w = geometry.walls[hit.index as usize];
            let magnitude = ray.origin.abs() + (ray.dir * hit.t).abs();
            (ray.at(hit.t), w.normal, w.albedo, magnitude, hit.index)
        } else {
            let s = geometry.spheres[hit.index as usize];
            let (p, n) = sphere_hit_point(s.center, s.radius, &ray, hit.t);
            (p, n, s.albedo, s.center.abs() + Vec3::splat(s.radius), NO_WALL)
        };
        // Shade the side the ray arrived on: walls are two-sided, and a
        // camera inside a sphere sees its inside.
        let n = if normal.dot(ray.dir) < 0.0 { normal } else { -normal };
        let origin = offset_origin(p, n, magnitude);

        // Next-event estimation: one shadow ray toward the light's cone. The
        // cone is seen from the hit point itself: from the offset origin,
        // nearer the light, it would be brighter by twice the offset over
        // the distance (8e-6 in the spherical-room accuracy case).
        let cone = light_cone(&light, p);
        let cone_pdf = cone.pdf();
        // At the last vertex NEE takes all of the light's MIS weight and the
        // BSDF ray none (weights that sum to one per direction keep MIS
        // unbiased; Veach 1997, section 9.2): that ray could then only add
        // background, and with a black one it is not traced.
        let last = nee && !cone.is_empty() && self.bounces + 1 >= params.max_bounces;
        // After the last vertex no light found by the BSDF counts (MIS weight
        // 0), so the glow lobe could only find background there.
        let scatter = Scatter::new(n, &cone, params.flags & FLAG_GLOW != 0 && !last);
        if nee && !cone.is_empty() {
            let u = self.sampler.next_2d();
            let (dir, dist) = cone.sample(u.x, u.y);
            let cos = n.dot(dir);
            if cos > 0.0 {
                let shadow = Ray { origin, dir };
                rays.ray();
                if !objects.occluded(&shadow, params, shadow_walls, wall_index, dist) {
                    let bsdf = cos * (1.0 / PI);
                    let weight = if mis && !last { power_heuristic(cone_pdf, scatter.pdf(dir)) } else { 1.0 };
                    // f cos / pdf = (albedo / pi) cos / cone_pdf
                    self.radiance += self.throughput * albedo * light.radiance * (bsdf * weight / cone_pdf);
                }
            }
        }

        if last && params.background.max_element() == 0.0 {
            return true;
        }

        // BSDF sampling. The throughput takes f cos / pdf = albedo cos / (pi
        // pdf): albedo alone for the cosine lobe. A glow-lobe direction below
        // the surface carries nothing and ends the path. After the last
        // vertex a BSDF-found light has MIS weight 0: its pdf is kept as 0 for
        // `power_heuristic`.
        let dir = scatter.sample(self.sampler.next_2d());
        let cos = n.dot(dir);
        let pdf = scatter.pdf(dir);
        if !(cos > 0.0 && pdf > 0.0) {
            return true;
        }
        self.bsdf_pdf = if last { 0.0 } else { pdf };
        self.nee_pdf = cone_pdf;
        self.throughput *= albedo * (cos * (1.0 / PI) / pdf);
        self.bounces += 1;

        // Russian roulette: survive with a probability that follows the
        // throughput, and divide by it so the estimate stays unbiased.
        if self.bounces >= params.rr_start {
            let t = self.throughput;
            let follow = if params.flags & FLAG_RR_LUMINANCE != 0 {
                t.dot(Vec3::new(0.2126, 0.7152, 0.0722))
            } else {
                t.max_element()
            };
            let survive = follow.clamp(RR_MIN_SURVIVAL, 1.0);
            if self.sampler.next_1d() >= survive {
                return true;
            }
            self.throughput /= survive;
        }

        (self.origin, self.dir) = (origin, dir);
        self.skip_wall = wall_index;
        false
    }
}

/// The samples of pixel (`x`, `y`) for one frame: `samples_per_frame`
/// camera samples, from independent PCG streams or from the Owen-scrambled
/// Sobol sequence (`FLAG_SOBOL`), non-finite results counted and discarded.
pub fn render_pixel(x: u32, y: u32, params: &FrameParams, geometry: &Geometry) -> PixelSamples {
    pixel(x, y, params, geometry, geometry, &mut NoRayCount)
}

/// [`render_pixel`] on a copy of the scene read at constant indices
/// ([`SmallScene`] of capacity `W` walls and `S` spheres), for a scene that
/// [`SmallScene::fits`]: the same samples, faster on lavapipe.
pub fn render_pixel_small<const W: u32, const S: u32>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
) -> PixelSamples {
    pixel(x, y, params, geometry, &SmallScene::<W, S>::new(params, geometry), &mut NoRayCount)
}

/// Rays traced by the samples of pixel (`x`, `y`) in one frame: what
/// [`render_pixel`] does, counting its rays (benchmarks).
#[cfg(not(target_arch = "spirv"))]
pub fn count_pixel_rays(x: u32, y: u32, params: &FrameParams, geometry: &Geometry) -> u64 {
    let mut count = RayCount::default();
    pixel(x, y, params, geometry, geometry, &mut count);
    count.0
}

/// [`render_pixel`] with its rays counted: the one place that picks the
/// sampler.
fn pixel<O: Objects, C: RayCounter>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
    objects: &O,
    rays: &mut C,
) -> PixelSamples {
    if params.flags & FLAG_SOBOL != 0 {
        if params.flags & FLAG_SOBOL_DEEP != 0 {
            pixel_samples::<SobolSampler<{ u32::MAX }>, O, C>(x, y, params, geometry, objects, rays)
        } else {
            pixel_samples::<SobolSampler, O, C>(x, y, params, geometry, objects, rays)
        }
    } else {
        pixel_samples::<Rng, O, C>(x, y, params, geometry, objects, rays)
    }
}

/// The pixel's samples, one segment per loop iteration: when a path ends,
/// the next camera sample starts in the same iteration's place (path
/// regeneration, Novak, Havran and Dachsbacher 2010). SIMD lanes (8 on
/// lavapipe, 32 on NVIDIA) then stay busy until the pixel's last sample
/// instead of waiting each sample for their longest path. Samples are added
/// in order 0, 1, ..., so the sum is the one a sample-by-sample loop makes.
fn pixel_samples<S: Sampler, O: Objects, C: RayCounter>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
    objects: &O,
    rays: &mut C,
) -> PixelSamples {
    let mut out = PixelSamples::default();
    // Kahan compensation of the frame's sum: thousands of samples per frame
    // would otherwise drift (a sum of 65536 x 0.1 in f32 is off by 6e-4).
    let mut compensation = Vec3::ZERO;
    let shadow_walls = ShadowWalls::new(params, geometry);
    let pixel = S::for_pixel(x, y, params);
    let mut s = 0;
    let mut path = Path::<S>::camera(x, y, pixel, s, params);
    while s < params.samples_per_frame {
        if path.step(params, geometry, objects, &shadow_walls, rays) {
            let l = path.radiance;
            if is_finite(l) {
                // width != 0 always; the compiler cannot know it (see kahan_add).
                kahan_add(&mut out.sum, &mut compensation, l, params.width != 0);
                out.valid += 1;
            } else {
                out.non_finite += 1;
            }
            s += 1;
            if s < params.samples_per_frame {
                path = Path::camera(x, y, pixel, s, params);
            }
        }
    }
    out
}
