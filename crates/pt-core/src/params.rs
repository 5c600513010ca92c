//! Per-frame parameters: everything the kernel reads besides the geometry.

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::camera::Camera;
use crate::light::SphereLight;

/// `flags` bit: next-event estimation (shadow rays to the light).
pub const FLAG_NEE: u32 = 1;
/// `flags` bit: combine next-event estimation with BSDF sampling by MIS
/// (power heuristic). Without it, light reached by BSDF rays is dropped
/// while NEE is on.
pub const FLAG_MIS: u32 = 2;
/// `flags` bit: samples from the randomised Sobol sequence
/// (`sampler::SobolSampler`) instead of independent PCG streams.
pub const FLAG_SOBOL: u32 = 4;
/// `flags` bit: BSDF sampling mixes the glow lobe around the light
/// (`light::GlowLobe`) into the cosine lobe.
pub const FLAG_GLOW: u32 = 16;
/// `flags` bit, with `FLAG_NEE`: where the light's cone lies wholly above
/// a vertex's horizon, NEE samples it by projected solid angle
/// (`LightCone::sample_projected`), whose estimate is exact wherever the
/// light is wholly visible or hidden; BSDF rays that reach the light from
/// such a vertex count nothing, with or without MIS. Elsewhere NEE samples
/// the cone uniformly, as without the flag.
pub const FLAG_NEE_PROJECTED: u32 = 64;
/// `flags` bit, with `FLAG_GLOW`: BSDF sampling picks the glow lobe with
/// probability `bsdf::GLOW_PROBABILITY_SPARSE` (0.1) instead of
/// `bsdf::GLOW_PROBABILITY` (0.25): for large lights and bright rooms.
pub const FLAG_GLOW_SPARSE: u32 = 128;
/// `flags` bit, with `FLAG_NEE`, in a room whose walls cannot shadow the
/// light: at each vertex a second next-event estimate reaches the light
/// through a wall point chosen as a light would light it (a direction
/// uniform about the light's centre), combined by MIS with the BSDF ray
/// that could find the same wall point (`integrator`, "Connections").
pub const FLAG_CONNECT: u32 = 256;
/// `flags` bit, with `FLAG_NEE`: where `FLAG_NEE_PROJECTED` is off, the
/// uniform cone sample's estimate takes a control variate, the cone's
/// signed cosine to the normal, whose integral (`LightCone::projected_over_pi`)
/// is known at every tilt, weighted by `LightCone::control_weight` (1
/// where the cone lies wholly above the vertex's horizon, falling to 0
/// where it lies wholly below). Where the light is wholly visible above
/// the horizon the estimate is then exact, as with projection, for the
/// cost of a dot product; where the cone crosses the horizon the estimate
/// is less noisy than the clamped cosine alone. NEE then takes all of the
/// vertex's light: BSDF rays that reach the light count nothing.
pub const FLAG_NEE_CONTROL: u32 = 512;
/// `flags` bit: camera samples take the control variate of the light's
/// silhouette (`camera::LightEdge`): in pixels that the light's edge
/// crosses, the share of the pixel inside the light's image (an ellipse on
/// the film) is known exactly, and each sample adds the light's radiance
/// times that share less its own indicator of the ellipse, so the step
/// from the room to the light adds no noise where nothing hides it.
pub const FLAG_LIGHT_EDGE: u32 = 1024;
/// The default, chosen by `pathtracer bench` (docs/PERFORMANCE.md): NEE
/// (without MIS, by projected solid angle where the light is wholly above
/// the horizon) and the glow lobe, on randomised Sobol samples for the
/// first draws of each path. MIS makes the same image in the default scene
/// and costs more per sample.
pub const FLAGS_DEFAULT: u32 = FLAG_NEE | FLAG_NEE_PROJECTED | FLAG_SOBOL | FLAG_GLOW;

// Comparison-only flags. `pathtracer bench` sets them to compare
// alternatives with the default, and the accuracy suite to check that they
// stay unbiased; no command-line option or viewer setting turns them on,
// and the path loop reads each in one place.

/// `flags` bit: Russian roulette survives with the throughput's luminance
/// (Rec. 709 weights) instead of its largest component: shorter paths after
/// strongly coloured bounces, at the price of more colour noise there.
pub const FLAG_RR_LUMINANCE: u32 = 8;
/// `flags` bit, with `FLAG_SOBOL`: every draw of a path is a Sobol point,
/// not only the first `sampler::SOBOL_DRAWS` (the default, which takes the
/// later ones from a PCG stream).
pub const FLAG_SOBOL_DEEP: u32 = 32;

/// `tonemap`: clamp to [0, 1] (no curve).
pub const TONEMAP_CLAMP: u32 = 0;
/// `tonemap`: the ACES filmic fit of Narkowicz (2015).
pub const TONEMAP_ACES: u32 = 1;

/// The rectangle of the image that a renderer accumulates: its buffers hold
/// this rectangle only, row by row, while pixel coordinates (and with them
/// camera rays and sample streams) stay those of the whole image. An image
/// too large for the adapter's buffers renders as several tiles that make
/// the same pixels as one.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct Tile {
    /// Column of the tile's first pixel in the image.
    pub x: u32,
    /// Row of the tile's first pixel in the image (row 0 at the top).
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Tile {
    /// The whole `width` x `height` image as one tile.
    pub fn whole(width: u32, height: u32) -> Self {
        Self { x: 0, y: 0, width, height }
    }

    /// Pixels in the tile.
    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
}

/// The kernel's uniform block. Every `Vec3` sits at a multiple of 16 bytes
/// and the struct is a multiple of 16 bytes, which satisfies std140.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameParams {
    /// The camera.
    pub camera: Camera,
    /// The light.
    pub light: SphereLight,
    /// Radiance of rays that leave the scene, linear RGB.
    pub background: Vec3,
    /// Display exposure in stops: the mean is scaled by 2^exposure before
    /// tone mapping. Display only: never restarts accumulation.
    pub exposure: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Frame index: one per accumulation dispatch, part of the RNG seed.
    pub frame: u32,
    /// Camera samples per pixel in this frame.
    pub samples_per_frame: u32,
    /// Maximum scattering events on a path (docs/ARCHITECTURE.md, Conventions).
    pub max_bounces: u32,
    /// Russian roulette starts once a path has this many bounces.
    pub rr_start: u32,
    /// User seed, mixed into the RNG.
    pub seed: u32,
    /// Number of walls in the wall buffer.
    pub wall_count: u32,
    /// Number of spheres in the sphere buffer.
    pub sphere_count: u32,
    /// Tone mapper of the display pass (`TONEMAP_*`). Display only.
    pub tonemap: u32,
    /// Integrator switches (`FLAG_*`).
    pub flags: u32,
    /// Samples per pixel accumulated before this frame: the Sobol index of
    /// this frame's first sample.
    pub sample_offset: u32,
    /// The part of the image this renderer accumulates.
    pub tile: Tile,
}

impl FrameParams {
    /// Always true, from a value no shader compiler can know: the `keep`
    /// of `accum::kahan_add`. The frame index is read from the parameter
    /// buffer on every pipeline (a pipeline with the scene compiled in
    /// knows the image size, the flags and the rest as constants, and a
    /// test on those folds away and with it the compensation), and the
    /// renderers never write `u32::MAX` there.
    #[inline]
    pub fn keeps_sums(&self) -> bool {
        self.frame != u32::MAX
    }
}
