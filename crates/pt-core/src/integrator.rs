//! The path loop: closest hits, next-event estimation with MIS,
//! connections through lit wall points, Russian roulette, and the
//! per-pixel sample loop that the kernel wraps.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use spirv_std::glam::Vec3;

use crate::accum::{PixelSamples, is_finite, kahan_add};
use crate::bsdf::{Scatter, glow_probability};
use crate::camera::LightEdge;
use crate::geometry::Geometry;
use crate::instrument::{NoRayCount, RayCounter};
use crate::light::light_cone;
use crate::params::{
    FLAG_CONNECT, FLAG_LIGHT_EDGE, FLAG_MIS, FLAG_NEE, FLAG_NEE_CONTROL, FLAG_NEE_PROJECTED, FLAG_RR_LUMINANCE,
    FLAG_SOBOL, FLAG_SOBOL_DEEP, FrameParams,
};
use crate::query::{Hit, HitKind, NO_WALL, SceneView, ShadowWalls, T_FAR};
use crate::ray::{Ray, offset_origin};
use crate::rng::Rng;
use crate::sampler::{Sampler, SobolSampler};
use crate::sampling::{PI, power_heuristic, sin_cos_of_turn};
use crate::small_scene::SmallScene;

/// Minimum Russian roulette survival probability: a path is never killed
/// with certainty, and its weight grows by at most 1/0.05 = 20.
pub const RR_MIN_SURVIVAL: f32 = 0.05;

/// One path in flight: what the path loop carries from one segment to the
/// next. [`Path::step`] traces one segment; a path is unbiased for
/// `params.max_bounces` scattering events (docs/ARCHITECTURE.md, Conventions).
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
    /// Density (solid angle) of the BSDF sample that made the current ray,
    /// whatever NEE did: the connection MIS weight needs it.
    scatter_pdf: f32,
    /// The share of the light reached from the current ray's origin vertex
    /// (by NEE or by a BSDF ray) that this path counts: below 1 where a
    /// connection from the vertex before could have found that vertex.
    direct_weight: f32,
    /// The path ended after its last direction was drawn (Russian roulette,
    /// or a direction below the surface): its next step traces nothing and
    /// hands its radiance back.
    dead: bool,
    sampler: S,
}

impl<S: Sampler> Path<S> {
    /// Camera sample `s` of pixel (`x`, `y`) in this frame, whose sampler
    /// part is `pixel` (`S::for_pixel(x, y, params)`): a primary ray
    /// jittered uniformly in the pixel (a box filter) by the sampler's first
    /// pair.
    /// `edge` is the pixel's [`LightEdge`] ([`LightEdge::NONE`] without
    /// `FLAG_LIGHT_EDGE`).
    pub fn camera(x: u32, y: u32, pixel: S::Pixel, s: u32, edge: &LightEdge, params: &FrameParams) -> Self {
        let mut path = Self::start(pixel, s, params);
        let u = path.sampler.next_2d(pixel);
        path.aim_camera(x, y, u, edge, params);
        path
    }

    /// Camera sample `s` before its first draw: no ray yet
    /// ([`Path::aim_camera`] aims it).
    fn start(pixel: S::Pixel, s: u32, params: &FrameParams) -> Self {
        Self {
            origin: Vec3::ZERO,
            dir: Vec3::Z,
            sampler: S::for_camera_sample(pixel, s, params),
            radiance: Vec3::ZERO,
            throughput: Vec3::ONE,
            bounces: 0,
            skip_wall: NO_WALL,
            bsdf_pdf: 0.0,
            nee_pdf: 0.0,
            scatter_pdf: 0.0,
            direct_weight: 1.0,
            dead: false,
        }
    }

    /// The primary ray through pixel (`x`, `y`) jittered by `u`, the
    /// first pair of a path just started, which starts with the light
    /// edge's control variate term at `u`.
    fn aim_camera(&mut self, x: u32, y: u32, u: spirv_std::glam::Vec2, edge: &LightEdge, params: &FrameParams) {
        let ray = params.camera.ray(x as f32 + u.x, y as f32 + u.y, params.width, params.height);
        (self.origin, self.dir) = (ray.origin, ray.dir);
        self.radiance = edge.term(u);
    }

    /// Traces the current ray to its closest hit in `scene` and shades it:
    /// emission, one shadow ray (NEE), a connection through a lit wall
    /// point (`FLAG_CONNECT`, the function `connection`), the next direction and
    /// Russian roulette. Shadow rays test `shadow_walls`, which must be
    /// `ShadowWalls::new` of the scene's parameters and geometry. Its rays
    /// are counted in `rays` ([`NoRayCount`] in the renderers).
    ///
    /// Where the path ends before its next direction is drawn (a miss, the
    /// light, the bounce limit, the last vertex; or a path that ended at its
    /// previous step), the step writes its radiance to `finished`, returns
    /// true, and starts the pixel's next sample (`next` of pixel (`x`, `y`),
    /// light edge `edge`, sampler part `pixel`) in its place: the next sample's camera ray
    /// takes the draw that a continuing path spends on its BSDF direction.
    /// lavapipe runs every line of the loop in every pass, masked, so a
    /// camera draw of its own, after the step, cost a Sobol draw per pass
    /// (docs/ARCHITECTURE.md, "The small-scene kernel"). A path that ends
    /// after that draw (Russian roulette, a direction below the surface) is
    /// marked `dead`, and its next step traces nothing and ends it. The
    /// samples are those of a loop that ends each path at once.
    ///
    /// A path that ends part-way through the shading is only marked, and
    /// runs on (its state then dropped), and the shadow tests run whatever
    /// the cosine: on lavapipe a return masks all the code after it and
    /// cost more than the work it skipped.
    ///
    /// `CONNECT` false leaves the connection's code out, for flags that
    /// make no connections ([`connects`]), `GLOW` false the glow lobe's,
    /// for flags without it (`glow_probability` 0), and `ROULETTE` false
    /// Russian roulette's, for frames where it cannot act
    /// ([`roulette_acts`]): the same path, without code that lavapipe
    /// would run masked whatever the flags.
    ///
    /// `pixel` is an argument of its own: inside the tuple, a struct
    /// beside the reference made rust-gpu emit a struct with a pointer
    /// member, which naga rejects.
    #[allow(clippy::too_many_arguments)]
    pub fn step<V: SceneView, C: RayCounter, const CONNECT: bool, const GLOW: bool, const ROULETTE: bool>(
        &mut self,
        params: &FrameParams,
        scene: &V,
        shadow_walls: &ShadowWalls,
        rays: &mut C,
        (x, y, next, edge): (u32, u32, u32, &LightEdge),
        pixel: S::Pixel,
        finished: &mut Vec3,
    ) -> bool {
        let nee = params.flags & FLAG_NEE != 0;
        let mis = params.flags & FLAG_MIS != 0;
        let light = params.light;
        let ray = Ray { origin: self.origin, dir: self.dir };
        let live = !self.dead;

        let mut hit = Hit::none(T_FAR);
        if live {
            rays.ray();
            hit = scene.closest_hit(&ray, params, self.skip_wall, T_FAR);
        }
        let missed = live && hit.kind == HitKind::Nothing;
        let at_light = hit.kind == HitKind::Light;
        if missed {
            self.radiance += self.throughput * params.background;
        }
        // The light emits outward only; from inside it shows nothing.
        if at_light && ray.dir.dot(ray.at(hit.t) - light.center) < 0.0 {
            let weight = if self.bounces == 0 || !nee || self.nee_pdf == 0.0 {
                // Camera rays, or no NEE could have found this light.
                1.0
            } else if mis {
                power_heuristic(self.bsdf_pdf, self.nee_pdf)
            } else {
                // NEE alone accounts for light reached after a bounce.
                0.0
            };
            // 1 without connections' code: lavapipe would not fold the
            // field's constant through the loop.
            let direct_weight = if CONNECT { self.direct_weight } else { 1.0 };
            self.radiance += self.throughput * light.radiance * (weight * direct_weight);
        }
        // The three ways a path ends at its hit, and a dead path.
        let mut ended = !live || missed || at_light || self.bounces >= params.max_bounces;

        // The vertex's share of the direction draw below, set where the path
        // goes on from the hit.
        let mut scatter = Scatter::NONE;
        let (mut origin, mut n, mut albedo) = (Vec3::ZERO, Vec3::Z, Vec3::ZERO);
        let (mut wall_index, mut last, mut projected, mut control, mut cone_pdf) = (NO_WALL, false, false, false, 0.0);
        if !ended {
            let surface = scene.surface(&hit, &ray);
            let p = surface.point;
            (albedo, wall_index) = (surface.albedo, surface.wall);
            // Shade the side the ray arrived on: walls are two-sided, and a
            // camera inside a sphere sees its inside.
            n = if surface.normal.dot(ray.dir) < 0.0 { surface.normal } else { -surface.normal };
            origin = offset_origin(p, n, surface.magnitude);
            let connect = CONNECT && connects(params.flags) && shadow_walls.is_empty();
            // The share of this vertex's direct light this path counts: the
            // rest belongs to the connection from the vertex before, which
            // could have chosen this wall point.
            self.direct_weight = if connect && self.bounces > 0 && wall_index != NO_WALL {
                let to_light = light.center - p;
                let d2 = to_light.dot(to_light);
                let cos_light = n.dot(to_light);
                if cos_light > 0.0 {
                    let cos_in = -n.dot(ray.dir);
                    let bsdf_area = self.scatter_pdf * cos_in / (hit.t * hit.t);
                    power_heuristic(bsdf_area, connection_pdf(cos_light / d2.sqrt(), d2))
                } else {
                    1.0
                }
            } else {
                1.0
            };

            // Next-event estimation: one shadow ray toward the light's cone. The
            // cone is seen from the hit point itself: from the offset origin,
            // nearer the light, it would be brighter by twice the offset over
            // the distance (8e-6 in the spherical-room accuracy case).
            let cone = light_cone(&light, p);
            cone_pdf = cone.pdf();
            // At the last vertex NEE takes all of the light's MIS weight and the
            // BSDF ray none (weights that sum to one per direction keep MIS
            // unbiased; Veach 1997, section 9.2): that ray could then only add
            // background, and with a black one it is not traced.
            last = nee && !cone.is_empty() && self.bounces + 1 >= params.max_bounces;
            // After the last vertex no light found by the BSDF counts (MIS weight
            // 0), so the glow lobe could only find background there.
            scatter = Scatter::new(n, &cone, if last || !GLOW { 0.0 } else { glow_probability(params.flags) });
            // Where the whole cone is above the horizon NEE samples it by
            // projected solid angle and takes all of the light (no MIS).
            let above = nee && cone.above_horizon(n);
            projected = above && params.flags & FLAG_NEE_PROJECTED != 0;
            // The control variate (`FLAG_NEE_CONTROL`): the cone's signed
            // cosine has a known integral, and where the light is wholly
            // visible above the horizon the estimate is exactly that.
            control = nee && nee_control(params.flags) && !cone.is_empty();
            if nee && !cone.is_empty() {
                let u = self.sampler.next_2d(pixel);
                let (dir, dist) = if projected { cone.sample_projected(n, u.x, u.y) } else { cone.sample(u.x, u.y) };
                let cos = n.dot(dir);
                let shadow = Ray { origin, dir };
                // Traced whatever the cosine (see above).
                let blocked = scene.occluded(&shadow, params, shadow_walls, wall_index, dist);
                if cos > 0.0 {
                    rays.ray();
                }
                let whole = cone.projected_over_pi(n);
                let value = if projected {
                    whole
                } else {
                    let bsdf = cos * (1.0 / PI);
                    let weight =
                        if mis && !last && !control { power_heuristic(cone_pdf, scatter.pdf(dir)) } else { 1.0 };
                    // f cos / pdf = (albedo / pi) cos / cone_pdf
                    bsdf * weight / cone_pdf
                };
                // The control variate counts every ray: `beta` times the
                // integral of the cone's signed cosine over pi (`whole`),
                // plus the sample's estimate where the ray reaches the light
                // above the horizon, less `beta` times its estimate of the
                // signed cosine. Unbiased for any `beta` fixed before the
                // draw; `beta` is 1 where the cone is wholly above the
                // horizon, and the estimate is then `whole` wherever nothing
                // blocks the light (`LightCone::control_weight`). One
                // addition for both: on lavapipe each costs its code in
                // every pass.
                let (counts, value) = if control {
                    let kept = if blocked || cos <= 0.0 { 0.0 } else { 1.0 };
                    let beta = cone.control_weight(n);
                    (true, beta * whole + value * (kept - beta))
                } else {
                    (cos > 0.0 && !blocked, value)
                };
                if counts {
                    self.radiance += self.throughput * albedo * light.radiance * (value * self.direct_weight);
                }
            }
            if connect && self.bounces + 1 < params.max_bounces {
                let (u, v) = (self.sampler.next_2d(pixel), self.sampler.next_2d(pixel));
                let through = connection(n, origin, &scatter, u, v, params, scene, shadow_walls, rays);
                self.radiance += self.throughput * albedo * through;
            }
            ended = last && params.background.max_element() == 0.0;
        }

        // The path's sample is done: hand it back and start the next one.
        if ended {
            *finished = self.radiance;
            *self = Self::start(pixel, next, params);
        }
        // One draw: the next sample's pixel jitter, or the BSDF direction.
        let u = self.sampler.next_2d(pixel);
        if ended {
            self.aim_camera(x, y, u, edge, params);
        } else {
            // BSDF sampling. The throughput takes f cos / pdf = albedo cos / (pi
            // pdf): albedo alone for the cosine lobe. A glow-lobe direction below
            // the surface carries nothing and ends the path. After the last
            // vertex, and after one whose NEE took all of the light (by
            // projected solid angle or with the control variate), a BSDF-found
            // light has MIS weight 0: its pdf is kept as 0 for
            // `power_heuristic`.
            let dir = scatter.sample(u);
            let cos = n.dot(dir);
            let pdf = scatter.pdf(dir);
            let mut dead = !(cos > 0.0 && pdf > 0.0);
            self.bsdf_pdf = if last || projected || control { 0.0 } else { pdf };
            self.scatter_pdf = pdf;
            self.nee_pdf = cone_pdf;
            self.throughput *= albedo * (cos * (1.0 / PI) / pdf);
            self.bounces += 1;

            // Russian roulette: survive with a probability that follows the
            // throughput, and divide by it so the estimate stays unbiased.
            if ROULETTE && self.bounces >= params.rr_start {
                let t = self.throughput;
                let follow = if params.flags & FLAG_RR_LUMINANCE != 0 {
                    t.dot(Vec3::new(0.2126, 0.7152, 0.0722))
                } else {
                    t.max_element()
                };
                let survive = follow.clamp(RR_MIN_SURVIVAL, 1.0);
                dead |= self.sampler.next_1d(pixel) >= survive;
                self.throughput /= survive;
            }

            (self.origin, self.dir) = (origin, dir);
            self.skip_wall = wall_index;
            self.dead = dead;
        }
        ended
    }
}

/// Whether Russian roulette can act on a path of the frame `params`
/// describe: whether a path can draw a direction at a vertex after which
/// it has made `rr_start` scattering events or more.
///
/// A path draws at most `max_bounces` directions, so roulette from a later
/// bounce never acts. Roulette from the last one acts only where a path
/// draws a direction at its last vertex, which it does not where NEE takes
/// all of the light there and the background is black (the path then ends
/// at that vertex, [`Path::step`]). One exception: NEE finds no light from
/// a surface point inside the light, and a path at such a point does draw
/// on; only a scene whose surfaces cut into the light has one, and leaving
/// the roulette out is unbiased there too (it only saves work). Where this
/// is false, [`Path::step`] without the roulette's code traces the same
/// samples.
#[inline]
pub fn roulette_acts(params: &FrameParams) -> bool {
    let ends_at_last_vertex = params.flags & FLAG_NEE != 0 && params.background.max_element() == 0.0;
    params.rr_start < params.max_bounces || (params.rr_start == params.max_bounces && !ends_at_last_vertex)
}

/// Whether NEE under integrator `flags` takes the control variate:
/// `FLAG_NEE_CONTROL`, which
/// needs `FLAG_NEE`, where `FLAG_NEE_PROJECTED` does not sample those
/// vertices by projected solid angle instead.
#[inline]
pub fn nee_control(flags: u32) -> bool {
    flags & (FLAG_NEE | FLAG_NEE_PROJECTED | FLAG_NEE_CONTROL) == FLAG_NEE | FLAG_NEE_CONTROL
}

/// The light edge's control variate for pixel (`x`, `y`) of the frame
/// `params` describe: [`LightEdge::of_pixel`] under `FLAG_LIGHT_EDGE`, else
/// [`LightEdge::NONE`].
#[inline]
pub fn light_edge(x: u32, y: u32, params: &FrameParams) -> LightEdge {
    if params.flags & FLAG_LIGHT_EDGE == 0 {
        return LightEdge::NONE;
    }
    LightEdge::of_pixel(&params.camera, &params.light, x, y, params.width, params.height)
}

/// Whether integrator `flags` make connections through lit wall points
/// (where no wall shadows the light): `FLAG_CONNECT`, which needs `FLAG_NEE`.
#[inline]
pub fn connects(flags: u32) -> bool {
    flags & FLAG_NEE != 0 && flags & FLAG_CONNECT != 0
}

/// A direction uniform over the unit sphere, from `u` in [0, 1)^2.
#[inline]
fn uniform_sphere(u: spirv_std::glam::Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_of_turn(u.y);
    Vec3::new(s * cos_phi, s * sin_phi, z)
}

/// Area density on a wall of the connection's wall points at a point that
/// sees the light's centre at distance squared `d2`, the wall's cosine
/// toward it `cos`: a direction uniform over the sphere about the centre,
/// `1 / 4 pi` per steradian, and `cos / d2` steradians per unit area.
#[inline]
fn connection_pdf(cos: f32, d2: f32) -> f32 {
    cos / (4.0 * PI * d2)
}

/// The connection from a vertex (normal `n` on the side the path is on,
/// ray origin `origin`, BSDF sampling `scatter`): light that reaches the
/// vertex after one diffuse bounce at a wall point `y`, estimated through `y`
/// instead of through a BSDF ray. `y` is where a direction uniform about
/// the light's centre (`u`) first meets a wall: with no wall shadowing the
/// light the room is convex, so every wall point is reachable, with density
/// [`connection_pdf`], highest where the light shines most. Then `y`'s
/// direct light is one NEE sample (`v`), and the path through `y` takes
/// its power-heuristic weight against the BSDF sample that could have found
/// `y`. Returns the radiance over `p`'s albedo.
#[allow(clippy::too_many_arguments)]
#[inline]
fn connection<V: SceneView, C: RayCounter>(
    n: Vec3,
    origin: Vec3,
    scatter: &Scatter,
    u: spirv_std::glam::Vec2,
    v: spirv_std::glam::Vec2,
    params: &FrameParams,
    scene: &V,
    shadow_walls: &ShadowWalls,
    rays: &mut C,
) -> Vec3 {
    let light = params.light;
    let from_light = Ray { origin: light.center, dir: uniform_sphere(u) };
    rays.ray();
    let hit = scene.first_wall(&from_light, params);
    if hit.kind != HitKind::Wall {
        return Vec3::ZERO;
    }
    // From here on every step runs whatever the ones before it found, and
    // `found` says at the end whether the path through `y` carries light,
    // as in `Path::step`; `&`, not `&&`, so that no branch skips a shadow
    // test.
    let wall = scene.surface(&hit, &from_light);
    let y = wall.point;
    // The wall's side toward the light.
    let ny = if wall.normal.dot(from_light.dir) < 0.0 { wall.normal } else { -wall.normal };
    let pdf_area = connection_pdf(-ny.dot(from_light.dir), hit.t * hit.t);
    let to_y = y - origin;
    let d2 = to_y.dot(to_y);
    let dist = d2.sqrt();
    let dir = to_y / dist;
    let (cos_p, cos_y) = (n.dot(dir), -ny.dot(dir));
    let cone = light_cone(&light, y);
    let facing = cos_p > 0.0 && cos_y > 0.0 && pdf_area > 0.0 && !cone.is_empty();
    let segment = Ray { origin, dir };
    if facing {
        rays.ray();
    }
    let hides = crate::sphere::sphere_meets_segment(light.center, light.radius, &segment, dist);
    let seen = !hides & !scene.occluded(&segment, params, shadow_walls, hit.index, dist);
    let projected = params.flags & FLAG_NEE_PROJECTED != 0 && cone.above_horizon(ny);
    let (to_light, light_dist) = if projected { cone.sample_projected(ny, v.x, v.y) } else { cone.sample(v.x, v.y) };
    // Written so that a NaN direction finds nothing.
    let cos_light = ny.dot(to_light);
    let towards = facing && seen && cos_light > 0.0;
    if towards {
        rays.ray();
    }
    let shadow = Ray { origin: offset_origin(y, ny, wall.magnitude), dir: to_light };
    let found = towards & !scene.occluded(&shadow, params, shadow_walls, hit.index, light_dist);
    let direct = if projected { cone.projected_over_pi(ny) } else { cos_light * (1.0 / PI) / cone.pdf() };
    let bsdf_area = scatter.pdf(dir) * cos_y / d2;
    let weight = power_heuristic(pdf_area, bsdf_area);
    // f(p) cos_p G V / pdf, with f(p) = albedo / pi (albedo applied by the caller).
    let geometry = cos_p * cos_y / (PI * d2 * pdf_area);
    if found { wall.albedo * light.radiance * (direct * geometry * weight) } else { Vec3::ZERO }
}

/// The samples of pixel (`x`, `y`) for one frame: `samples_per_frame`
/// camera samples, from independent PCG streams or from the randomised
/// Sobol sequence (`FLAG_SOBOL`), non-finite results counted and discarded.
pub fn render_pixel(x: u32, y: u32, params: &FrameParams, geometry: &Geometry) -> PixelSamples {
    pixel(x, y, params, geometry, geometry, &mut NoRayCount)
}

/// [`render_pixel`] on a copy of the scene read at constant indices
/// ([`SmallScene`] of capacity `W` walls and `S` spheres), for a scene that
/// [`SmallScene::fits`], with the sampler `Smp` fixed at compile time: it
/// must be the one the flags pick ([`SamplerKind::of`]); and with the
/// connections' code only where `CONNECT`, which must be true where the
/// flags make connections ([`connects`]), and the glow lobe's only where
/// `GLOW`, which must be true where the flags have it
/// ([`glow_probability`] not 0), and Russian roulette's only where
/// `ROULETTE`, which must be true where it acts ([`roulette_acts`]). The
/// same samples as [`render_pixel`], faster on lavapipe.
///
/// lavapipe runs both sides of every branch, masked, and a loop at least
/// once: [`render_pixel`]'s choice among three samplers, each with its own
/// path loop, would run all three loops' set-up and one pass of each loop
/// body in every invocation (docs/ARCHITECTURE.md, "The small-scene
/// kernel").
pub fn render_pixel_small<
    Smp: Sampler,
    const W: u32,
    const S: u32,
    const CONNECT: bool,
    const GLOW: bool,
    const ROULETTE: bool,
>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
) -> PixelSamples {
    // Unset constants: the scene from the buffers.
    render_pixel_specialized::<Smp, W, S, CONNECT, GLOW, ROULETTE, 1>(x, y, params, geometry, &[0])
}

/// [`render_pixel_small`] with the scene's values taken from `constants`
/// where they were set (`small_scene::scene_constants`): the same samples,
/// from values a driver can fold into the code when they are compiled in
/// as specialization constants, for a scene that
/// [`SmallScene::fits_compiled`] (walls that can block the light
/// included). Unset (a first word of 0), it is `render_pixel_small`.
pub fn render_pixel_specialized<
    Smp: Sampler,
    const W: u32,
    const S: u32,
    const CONNECT: bool,
    const GLOW: bool,
    const ROULETTE: bool,
    const N: usize,
>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
    constants: &[u32; N],
) -> PixelSamples {
    let (params, scene) = SmallScene::<W, S>::with_constants(params, geometry, constants);
    pixel_samples::<Smp, _, _, CONNECT, GLOW, ROULETTE>(x, y, &params, geometry, &scene, &mut NoRayCount)
}

/// The three samplers the path loop can draw from, as the flags pick them:
/// the kernel's small-scene entry points come in one form per sampler.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum SamplerKind {
    /// Independent PCG numbers ([`Rng`]): no `FLAG_SOBOL`.
    Independent,
    /// Sobol points for the first draws, then PCG ([`SobolSampler`]):
    /// `FLAG_SOBOL`.
    Sobol,
    /// Sobol points for every draw: `FLAG_SOBOL | FLAG_SOBOL_DEEP`.
    SobolDeep,
}

impl SamplerKind {
    /// Every kind, in the order of their discriminants (`kind as usize`
    /// indexes it) and of the kernel's entry points.
    pub const ALL: [SamplerKind; 3] = [SamplerKind::Independent, SamplerKind::Sobol, SamplerKind::SobolDeep];

    /// The sampler that integrator `flags` pick.
    pub fn of(flags: u32) -> Self {
        if flags & FLAG_SOBOL == 0 {
            SamplerKind::Independent
        } else if flags & FLAG_SOBOL_DEEP == 0 {
            SamplerKind::Sobol
        } else {
            SamplerKind::SobolDeep
        }
    }
}

/// [`render_pixel`] with its rays counted, with the sampler the flags pick
/// ([`SamplerKind::of`], which the small-scene kernels' host also asks).
pub(crate) fn pixel<V: SceneView, C: RayCounter>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
    scene: &V,
    rays: &mut C,
) -> PixelSamples {
    match SamplerKind::of(params.flags) {
        SamplerKind::Independent => pixel_samples::<Rng, V, C, true, true, true>(x, y, params, geometry, scene, rays),
        SamplerKind::Sobol => {
            pixel_samples::<SobolSampler, V, C, true, true, true>(x, y, params, geometry, scene, rays)
        }
        SamplerKind::SobolDeep => {
            pixel_samples::<SobolSampler<{ u32::MAX }>, V, C, true, true, true>(x, y, params, geometry, scene, rays)
        }
    }
}

/// The pixel's samples, one segment per loop iteration: when a path ends,
/// the next camera sample starts in the same iteration's place (path
/// regeneration, Novak, Havran and Dachsbacher 2010; [`Path::step`] starts
/// it). SIMD lanes (8 on
/// lavapipe, 32 on NVIDIA) then stay busy until the pixel's last sample
/// instead of waiting each sample for their longest path. Samples are added
/// in order 0, 1, ..., so the sum is the one a sample-by-sample loop makes.
fn pixel_samples<
    S: Sampler,
    V: SceneView,
    C: RayCounter,
    const CONNECT: bool,
    const GLOW: bool,
    const ROULETTE: bool,
>(
    x: u32,
    y: u32,
    params: &FrameParams,
    geometry: &Geometry,
    scene: &V,
    rays: &mut C,
) -> PixelSamples {
    let mut out = PixelSamples::default();
    // Kahan compensation of the frame's sum: thousands of samples per frame
    // would otherwise drift (a sum of 65536 x 0.1 in f32 is off by 6e-4).
    let mut compensation = Vec3::ZERO;
    let shadow_walls = ShadowWalls::new(params, geometry);
    let pixel = S::for_pixel(x, y, params);
    let edge = light_edge(x, y, params);
    let mut s = 0;
    let mut path = Path::<S>::camera(x, y, pixel, s, &edge, params);
    let mut l = Vec3::ZERO;
    while s < params.samples_per_frame {
        // After the pixel's last sample the step starts one more, unused.
        if path.step::<V, C, CONNECT, GLOW, ROULETTE>(
            params,
            scene,
            &shadow_walls,
            rays,
            (x, y, s + 1, &edge),
            pixel,
            &mut l,
        ) {
            if is_finite(l) {
                // Always true; the compiler cannot know it (see kahan_add).
                kahan_add(&mut out.sum, &mut compensation, l, params.keeps_sums());
                out.valid += 1;
            } else {
                out.non_finite += 1;
            }
            s += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The connections' wall-point density: its integral over each wall
    /// of a closed room (midpoint sums on 200x200 cells, exact to far below
    /// the tolerance: the integrand is smooth there) is the share of the
    /// directions about the light's centre that meet that wall first, which
    /// 200,000 directions through `SceneView::first_wall` count, and the
    /// six integrals sum to one.
    #[test]
    fn connection_density_is_that_of_wall_points_met_from_the_light() {
        use crate::geometry::Geometry;
        let walls = crate::test_support::closed_room();
        let geometry = Geometry::new(&walls, &[]).expect("six walls fit");
        let center = Vec3::new(0.3, 1.2, -0.4);
        let params = FrameParams {
            light: crate::light::SphereLight::new(center, 0.1, Vec3::ONE),
            wall_count: walls.len() as u32,
            ..Default::default()
        };
        let n = 200;
        let integrals: Vec<f64> = walls
            .iter()
            .map(|w| {
                let cell = w.edge_u.cross(w.edge_v).length() as f64 / (n * n) as f64;
                let mut sum = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        let (a, b) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                        let to = center - (w.corner + w.edge_u * a + w.edge_v * b);
                        let d2 = to.dot(to);
                        sum += connection_pdf(w.normal.dot(to).abs() / d2.sqrt(), d2) as f64 * cell;
                    }
                }
                sum
            })
            .collect();
        let total: f64 = integrals.iter().sum();
        assert!((total - 1.0).abs() < 1e-4, "{total}");
        let mut rng = Rng::new(5, 4, 3, 2, 1);
        let draws = 200_000;
        let mut counts = [0u32; 6];
        for _ in 0..draws {
            let u = spirv_std::glam::Vec2::new(rng.next_f32(), rng.next_f32());
            let ray = Ray { origin: center, dir: uniform_sphere(u) };
            let hit = geometry.first_wall(&ray, &params);
            assert_eq!(hit.kind, HitKind::Wall, "a closed room catches every direction");
            counts[hit.index as usize] += 1;
        }
        for (k, (&c, &p)) in counts.iter().zip(&integrals).enumerate() {
            // Binomial standard error; 5 of them is far beyond chance.
            let sigma = (draws as f64 * p * (1.0 - p)).sqrt();
            assert!((c as f64 - draws as f64 * p).abs() < 5.0 * sigma, "wall {k}: {c} against {}", draws as f64 * p);
        }
    }

    /// The kind the flags pick (`FLAG_SOBOL_DEEP` means nothing without
    /// `FLAG_SOBOL`), and `ALL` lists the kinds in the order of their
    /// discriminants.
    #[test]
    fn the_control_variate_needs_nee_and_gives_way_to_projection() {
        assert!(nee_control(FLAG_NEE | FLAG_NEE_CONTROL));
        assert!(nee_control(FLAG_NEE | FLAG_NEE_CONTROL | FLAG_MIS | FLAG_CONNECT));
        assert!(!nee_control(FLAG_NEE_CONTROL));
        assert!(!nee_control(FLAG_NEE | FLAG_NEE_CONTROL | FLAG_NEE_PROJECTED));
        assert!(!nee_control(FLAG_NEE));
    }

    #[test]
    fn sampler_kind_follows_the_flags() {
        assert_eq!(SamplerKind::of(0), SamplerKind::Independent);
        assert_eq!(SamplerKind::of(FLAG_SOBOL_DEEP), SamplerKind::Independent);
        assert_eq!(SamplerKind::of(FLAG_SOBOL), SamplerKind::Sobol);
        assert_eq!(SamplerKind::of(FLAG_SOBOL | FLAG_SOBOL_DEEP), SamplerKind::SobolDeep);
        assert_eq!(SamplerKind::of(crate::params::FLAGS_DEFAULT), SamplerKind::Sobol);
        for (i, kind) in SamplerKind::ALL.into_iter().enumerate() {
            assert_eq!(kind as usize, i);
        }
    }
}
