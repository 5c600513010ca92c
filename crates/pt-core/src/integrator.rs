//! The path loop: closest hits, next-event estimation with MIS, Russian
//! roulette, and the per-pixel sample loop that the kernel wraps.

use spirv_std::glam::Vec3;

use crate::accum::{PixelSamples, is_finite, kahan_add};
use crate::light::light_cone;
use crate::params::FLAG_SOBOL;
use crate::params::{FLAG_MIS, FLAG_NEE, FrameParams};
use crate::ray::{Ray, offset_origin};
use crate::rng::Rng;
use crate::sampler::{Sampler, SobolSampler};
use crate::sampling::{PI, cosine_hemisphere, power_heuristic};
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

/// "No limit" for ray parameters. Not `f32::INFINITY`: naga rejects an
/// infinite literal in a SPIR-V module.
pub const T_FAR: f32 = f32::MAX;

/// No wall to skip.
pub const NO_WALL: u32 = u32::MAX;

/// Minimum Russian roulette survival probability: a path is never killed
/// with certainty, and its weight grows by at most 1/0.05 = 20.
pub const RR_MIN_SURVIVAL: f32 = 0.05;

/// The closest hit in (0, `t_max`) over walls, spheres and the light, brute
/// force. `skip_wall` is the wall the ray leaves from: a plane cannot be hit
/// again by a ray that leaves it, so testing it could only find rounding
/// noise.
pub fn closest_hit(
    ray: &Ray,
    params: &FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    skip_wall: u32,
    t_max: f32,
) -> Hit {
    let mut hit = Hit { t: t_max, kind: HitKind::Nothing, index: 0 };
    let mut i = 0;
    while i < params.wall_count {
        if i != skip_wall {
            let t = intersect_wall(&walls[i as usize], ray, 0.0, hit.t);
            if t < hit.t {
                hit = Hit { t, kind: HitKind::Wall, index: i };
            }
        }
        i += 1;
    }
    let mut i = 0;
    while i < params.sphere_count {
        let s = spheres[i as usize];
        let t = intersect_sphere(s.center, s.radius, ray, 0.0, hit.t);
        if t < hit.t {
            hit = Hit { t, kind: HitKind::Sphere, index: i };
        }
        i += 1;
    }
    let t = intersect_sphere(params.light.center, params.light.radius, ray, 0.0, hit.t);
    if t < hit.t {
        hit = Hit { t, kind: HitKind::Light, index: 0 };
    }
    hit
}

/// Whether a wall or sphere blocks the ray in (0, `t_max`). The light is no
/// occluder of itself: shadow rays end on its surface.
pub fn occluded(
    ray: &Ray,
    params: &FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    skip_wall: u32,
    t_max: f32,
) -> bool {
    let mut i = 0;
    while i < params.wall_count {
        if i != skip_wall && intersect_wall(&walls[i as usize], ray, 0.0, t_max) < t_max {
            return true;
        }
        i += 1;
    }
    let mut i = 0;
    while i < params.sphere_count {
        let s = spheres[i as usize];
        if intersect_sphere(s.center, s.radius, ray, 0.0, t_max) < t_max {
            return true;
        }
        i += 1;
    }
    false
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

/// Radiance arriving along `ray`: one path sample, unbiased for
/// `params.max_bounces` scattering events (DESIGN sections 4 and 5). Its
/// rays are counted in `rays` ([`NoRayCount`] in the renderers).
pub fn trace_path<S: Sampler, C: RayCounter>(
    mut ray: Ray,
    params: &FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    rng: &mut S,
    rays: &mut C,
) -> Vec3 {
    let nee = params.flags & FLAG_NEE != 0;
    let mis = params.flags & FLAG_MIS != 0;
    let light = params.light;
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let mut bounces = 0u32;
    let mut skip_wall = NO_WALL;
    // Densities with which the BSDF and NEE could have produced the current
    // ray's direction (solid angle), for the MIS weight of a light hit.
    let mut bsdf_pdf = 0.0f32;
    let mut nee_pdf = 0.0f32;

    loop {
        rays.ray();
        let hit = closest_hit(&ray, params, walls, spheres, skip_wall, T_FAR);
        if hit.kind == HitKind::Nothing {
            radiance += throughput * params.background;
            break;
        }
        if hit.kind == HitKind::Light {
            // The light emits outward only; from inside it shows nothing.
            let front = ray.dir.dot(ray.at(hit.t) - light.center) < 0.0;
            if front {
                let weight = if bounces == 0 || !nee || nee_pdf == 0.0 {
                    // Camera rays, or no NEE could have found this light.
                    1.0
                } else if mis {
                    power_heuristic(bsdf_pdf, nee_pdf)
                } else {
                    // NEE alone accounts for light reached after a bounce.
                    0.0
                };
                radiance += throughput * light.radiance * weight;
            }
            break;
        }
        if bounces >= params.max_bounces {
            break;
        }

        // The surface point, its normal, its albedo and a bound on the
        // magnitudes its coordinates were computed from.
        let (p, normal, albedo, magnitude, wall_index) = if hit.kind == HitKind::Wall {
            let w = walls[hit.index as usize];
            let magnitude = ray.origin.abs() + (ray.dir * hit.t).abs();
            (ray.at(hit.t), w.normal, w.albedo, magnitude, hit.index)
        } else {
            let s = spheres[hit.index as usize];
            let (p, n) = sphere_hit_point(s.center, s.radius, &ray, hit.t);
            (p, n, s.albedo, s.center.abs() + Vec3::splat(s.radius), NO_WALL)
        };
        // Shade the side the ray arrived on: walls are two-sided, and a
        // camera inside a sphere sees its inside.
        let n = if normal.dot(ray.dir) < 0.0 { normal } else { -normal };
        let origin = offset_origin(p, n, magnitude);

        // Next-event estimation: one shadow ray toward the light's cone.
        let cone = light_cone(&light, origin);
        let cone_pdf = cone.pdf();
        if nee && !cone.is_empty() {
            let u = rng.next_2d();
            let (dir, dist) = cone.sample(u.x, u.y);
            let cos = n.dot(dir);
            if cos > 0.0 {
                let shadow = Ray { origin, dir };
                rays.ray();
                if !occluded(&shadow, params, walls, spheres, wall_index, dist) {
                    let bsdf = cos * (1.0 / PI);
                    let weight = if mis { power_heuristic(cone_pdf, bsdf) } else { 1.0 };
                    // f cos / pdf = (albedo / pi) cos / cone_pdf
                    radiance += throughput * albedo * light.radiance * (bsdf * weight / cone_pdf);
                }
            }
        }

        // BSDF sampling: cosine-weighted, so f cos / pdf = albedo.
        let u = rng.next_2d();
        let dir = cosine_hemisphere(n, u.x, u.y);
        bsdf_pdf = n.dot(dir).max(0.0) * (1.0 / PI);
        nee_pdf = cone_pdf;
        throughput *= albedo;
        bounces += 1;

        // Russian roulette: survive with a probability that follows the
        // throughput, and divide by it so the estimate stays unbiased.
        if bounces >= params.rr_start {
            let survive = throughput.max_element().clamp(RR_MIN_SURVIVAL, 1.0);
            if rng.next_1d() >= survive {
                break;
            }
            throughput /= survive;
        }

        ray = Ray { origin, dir };
        skip_wall = wall_index;
    }
    radiance
}

/// Rays traced by the samples of pixel (`x`, `y`) in one frame: what
/// [`render_pixel`] does, counting instead of accumulating (benchmarks).
#[cfg(not(target_arch = "spirv"))]
pub fn count_pixel_rays(x: u32, y: u32, params: &FrameParams, walls: &[Wall], spheres: &[Sphere]) -> u64 {
    let mut count = RayCount::default();
    for s in 0..params.samples_per_frame {
        camera_sample(x, y, s, params, walls, spheres, &mut count);
    }
    count.0
}

/// The primary ray of pixel (`x`, `y`), jittered uniformly in the pixel
/// (a box filter) by the sampler's first pair.
pub fn camera_ray<S: Sampler>(x: u32, y: u32, params: &FrameParams, sampler: &mut S) -> Ray {
    let u = sampler.next_2d();
    params.camera.ray(x as f32 + u.x, y as f32 + u.y, params.width, params.height)
}

/// Camera sample `s` of pixel (`x`, `y`) in this frame: the radiance of one
/// path, on independent PCG streams or the Owen-scrambled Sobol sequence
/// (`FLAG_SOBOL`). The one place that picks the sampler.
fn camera_sample<C: RayCounter>(
    x: u32,
    y: u32,
    s: u32,
    params: &FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    rays: &mut C,
) -> Vec3 {
    if params.flags & FLAG_SOBOL != 0 {
        let mut sampler = SobolSampler::new(x, y, params.sample_offset + s, params.seed);
        let ray = camera_ray(x, y, params, &mut sampler);
        trace_path(ray, params, walls, spheres, &mut sampler, rays)
    } else {
        let mut rng = Rng::new(x, y, params.frame, s, params.seed);
        let ray = camera_ray(x, y, params, &mut rng);
        trace_path(ray, params, walls, spheres, &mut rng, rays)
    }
}

/// The samples of pixel (`x`, `y`) for one frame: `samples_per_frame`
/// camera samples, from independent PCG streams or from the Owen-scrambled
/// Sobol sequence (`FLAG_SOBOL`), non-finite results counted and discarded.
pub fn render_pixel(x: u32, y: u32, params: &FrameParams, walls: &[Wall], spheres: &[Sphere]) -> PixelSamples {
    let mut out = PixelSamples::default();
    // Kahan compensation of the frame's sum: thousands of samples per frame
    // would otherwise drift (a sum of 65536 x 0.1 in f32 is off by 6e-4).
    let mut compensation = Vec3::ZERO;
    let mut s = 0;
    while s < params.samples_per_frame {
        let l = camera_sample(x, y, s, params, walls, spheres, &mut NoRayCount);
        if is_finite(l) {
            // width != 0 always; the compiler cannot know it (see kahan_add).
            kahan_add(&mut out.sum, &mut compensation, l, params.width != 0);
            out.valid += 1;
        } else {
            out.non_finite += 1;
        }
        s += 1;
    }
    out
}
