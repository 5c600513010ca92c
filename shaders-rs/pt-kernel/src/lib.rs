//! The path tracer's GPU entry points. Each is a thin wrapper: the work is
//! done by `pt-core` functions that the CPU renderer and tests also call.
//!
//! Bindings (descriptor set 0); the host names them in
//! `pt-render/src/gpu/bindings.rs`, and its layout test checks these
//! numbers against those names:
//! 0 `FrameParams` (read-only storage), 1 `Geometry` (uniform: walls and
//! spheres),
//! 2 accumulation buffer, 3 display buffer (RGBA8 packed in u32),
//! 4 non-finite sample counter.
#![cfg_attr(target_arch = "spirv", no_std)]

use pt_core::glam::{UVec3, Vec2, Vec4};
use pt_core::rng::Rng;
use pt_core::sampler::{Sampler, SobolSampler};
use pt_core::small_scene::constant_words;
use pt_core::{AccumPixel, FrameParams, Geometry, PixelSamples, integrator, tonemap};
use spirv_std::memory::{Scope, Semantics};
use spirv_std::spirv;

/// Adds one frame of `samples_per_frame` samples to the sum of pixel `id`
/// of the tile (`params.tile`: the buffers hold the tile only; the pixel's
/// coordinates in the image pick its camera ray and samples), and counts
/// the non-finite samples it discarded. The `accumulate*` entry
/// points differ only in their workgroup shape (`pathtracer bench`
/// compares them); `accumulate` (8 x 8) is the default. The
/// `accumulate_small_*` entry points trace a copy of a small scene with one
/// sampler each (`render` is then [`small`]).
fn accumulate_pixel(
    id: UVec3,
    params: &FrameParams,
    geometry: &Geometry,
    accum: &mut [AccumPixel],
    non_finite: &mut [u32],
    render: impl Fn(u32, u32, &FrameParams, &Geometry) -> PixelSamples,
) {
    let tile = params.tile;
    if id.x >= tile.width || id.y >= tile.height {
        return;
    }
    let samples = render(tile.x + id.x, tile.y + id.y, params, geometry);
    // Always true; the driver cannot know it (see `kahan_add`).
    accum[(id.y * tile.width + id.x) as usize].add(samples, params.keeps_sums());
    // Rare: the atomic costs nothing on clean frames.
    if samples.non_finite > 0 {
        // SAFETY: a relaxed add on a u32 in a storage buffer, at queue-family
        // scope (device scope needs a capability the Vulkan memory model
        // lacks here); the counter is only read after the frame completes.
        unsafe {
            spirv_std::arch::atomic_i_add::<u32, { Scope::QueueFamily as u32 }, { Semantics::NONE.bits() }>(
                &mut non_finite[0],
                samples.non_finite,
            );
        }
    }
}

/// [`integrator::render_pixel_small`] for a scene of at most `W` walls and
/// `S` spheres with sampler `Smp`, the connections' code only where
/// `CONNECT`, the glow lobe's only where `GLOW` and Russian roulette's only
/// where `ROULETTE`, with the parameters copied into the invocation's own
/// memory too: lavapipe would otherwise gather each of them from the buffer
/// at every read.
///
/// `constants` are the entry point's specialization constants: the
/// scene's values (`small_scene::scene_constants`) where the host compiled
/// them into the pipeline, zeros (read the buffers) where it did not.
fn small<
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
    let params = *params;
    integrator::render_pixel_specialized::<Smp, W, S, CONNECT, GLOW, ROULETTE, N>(x, y, &params, geometry, constants)
}

macro_rules! accumulate_entry {
    ($name:ident, $x:literal, $y:literal) => {
        accumulate_entry!($name, $x, $y, integrator::render_pixel);
    };
    // With `constants: TYPE` after the render function, the entry point
    // also takes specialization constants 0, 1, ... as `constants`.
    ($name:ident, $x:literal, $y:literal, $render:expr $(, $constants:ident: $ty:ty)?) => {
        /// [`accumulate_pixel`] in workgroups of this shape.
        #[spirv(compute(threads($x, $y)))]
        pub fn $name(
            #[spirv(global_invocation_id)] id: UVec3,
            #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] params: &FrameParams,
            #[spirv(uniform, descriptor_set = 0, binding = 1)] geometry: &Geometry,
            #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] accum: &mut [AccumPixel],
            #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] non_finite: &mut [u32],
            $(#[spirv(spec_constant(id = 0, default = 0))] $constants: $ty,)?
        ) {
            accumulate_pixel(id, params, geometry, accum, non_finite, $render);
        }
    };
}

/// A small-scene entry point and its twin without Russian roulette's code
/// (`_noroulette`), for frames where the roulette cannot act
/// (`integrator::roulette_acts`).
macro_rules! small_entries {
    ($name:ident, $noroulette:ident, $smp:ty, $w:literal, $s:literal, $connect:literal, $glow:literal) => {
        small_entry!($name, $smp, $w, $s, $connect, $glow, true);
        small_entry!($noroulette, $smp, $w, $s, $connect, $glow, false);
    };
}

/// One small-scene entry point: [`accumulate_pixel`] with [`small`], in 8 x
/// 8 workgroups, with the scene constants of its capacity as
/// specialization constants 0, 1, ... (`constant_words` of them).
macro_rules! small_entry {
    ($name:ident, $smp:ty, $w:literal, $s:literal, $connect:literal, $glow:literal, $roulette:literal) => {
        accumulate_entry!(
            $name,
            8,
            8,
            |x, y, p, g| {
                small::<$smp, $w, $s, $connect, $glow, $roulette, { constant_words($w, $s) }>(x, y, p, g, &constants)
            },
            constants: [u32; constant_words($w, $s)]
        );
    };
}

// Entry point names end in a letter: naga's WGSL writer, which a browser's
// WebGPU backend goes through, appends `_` to a name that ends in a digit,
// and the pipeline would then not find its entry point.
accumulate_entry!(accumulate, 8, 8);
// Benchmark-only: the same kernel in other workgroup shapes, which
// `pathtracer bench` times against 8 x 8 (the renderers never pick them).
accumulate_entry!(accumulate_16x4_groups, 16, 4);
accumulate_entry!(accumulate_32x2_groups, 32, 2);
accumulate_entry!(accumulate_4x4_groups, 4, 4);
// For scenes that `SmallScene::fits` (or, with the scene compiled in as
// specialization constants, `SmallScene::fits_compiled`), one per capacity in
// `small_scene::SMALL_SCENE_SIZES`, sampler (`integrator::SamplerKind`, in
// its order) and code compiled in (`kernel::SmallVariant` in pt-render):
// the connections' and the glow lobe's; the glow lobe's alone
// (`_unconnected`, for flags that make no connections); neither
// (`_unconnected_noglow`, for flags with neither); each with Russian
// roulette's code and without it (`_noroulette`). The renderer's choice on
// lavapipe.
type SobolDeep = SobolSampler<{ u32::MAX }>;
small_entries!(accumulate_small_5w_2s_pcg, accumulate_small_5w_2s_pcg_noroulette, Rng, 5, 2, true, true);
small_entries!(
    accumulate_small_5w_2s_pcg_unconnected,
    accumulate_small_5w_2s_pcg_unconnected_noroulette,
    Rng,
    5,
    2,
    false,
    true
);
small_entries!(
    accumulate_small_5w_2s_pcg_unconnected_noglow,
    accumulate_small_5w_2s_pcg_unconnected_noglow_noroulette,
    Rng,
    5,
    2,
    false,
    false
);
small_entries!(accumulate_small_5w_2s_sobol, accumulate_small_5w_2s_sobol_noroulette, SobolSampler, 5, 2, true, true);
small_entries!(
    accumulate_small_5w_2s_sobol_unconnected,
    accumulate_small_5w_2s_sobol_unconnected_noroulette,
    SobolSampler,
    5,
    2,
    false,
    true
);
small_entries!(
    accumulate_small_5w_2s_sobol_unconnected_noglow,
    accumulate_small_5w_2s_sobol_unconnected_noglow_noroulette,
    SobolSampler,
    5,
    2,
    false,
    false
);
small_entries!(
    accumulate_small_5w_2s_sobol_deep,
    accumulate_small_5w_2s_sobol_deep_noroulette,
    SobolDeep,
    5,
    2,
    true,
    true
);
small_entries!(
    accumulate_small_5w_2s_sobol_deep_unconnected,
    accumulate_small_5w_2s_sobol_deep_unconnected_noroulette,
    SobolDeep,
    5,
    2,
    false,
    true
);
small_entries!(
    accumulate_small_5w_2s_sobol_deep_unconnected_noglow,
    accumulate_small_5w_2s_sobol_deep_unconnected_noglow_noroulette,
    SobolDeep,
    5,
    2,
    false,
    false
);
small_entries!(accumulate_small_5w_8s_pcg, accumulate_small_5w_8s_pcg_noroulette, Rng, 5, 8, true, true);
small_entries!(
    accumulate_small_5w_8s_pcg_unconnected,
    accumulate_small_5w_8s_pcg_unconnected_noroulette,
    Rng,
    5,
    8,
    false,
    true
);
small_entries!(
    accumulate_small_5w_8s_pcg_unconnected_noglow,
    accumulate_small_5w_8s_pcg_unconnected_noglow_noroulette,
    Rng,
    5,
    8,
    false,
    false
);
small_entries!(accumulate_small_5w_8s_sobol, accumulate_small_5w_8s_sobol_noroulette, SobolSampler, 5, 8, true, true);
small_entries!(
    accumulate_small_5w_8s_sobol_unconnected,
    accumulate_small_5w_8s_sobol_unconnected_noroulette,
    SobolSampler,
    5,
    8,
    false,
    true
);
small_entries!(
    accumulate_small_5w_8s_sobol_unconnected_noglow,
    accumulate_small_5w_8s_sobol_unconnected_noglow_noroulette,
    SobolSampler,
    5,
    8,
    false,
    false
);
small_entries!(
    accumulate_small_5w_8s_sobol_deep,
    accumulate_small_5w_8s_sobol_deep_noroulette,
    SobolDeep,
    5,
    8,
    true,
    true
);
small_entries!(
    accumulate_small_5w_8s_sobol_deep_unconnected,
    accumulate_small_5w_8s_sobol_deep_unconnected_noroulette,
    SobolDeep,
    5,
    8,
    false,
    true
);
small_entries!(
    accumulate_small_5w_8s_sobol_deep_unconnected_noglow,
    accumulate_small_5w_8s_sobol_deep_unconnected_noglow_noroulette,
    SobolDeep,
    5,
    8,
    false,
    false
);
small_entries!(accumulate_small_8w_16s_pcg, accumulate_small_8w_16s_pcg_noroulette, Rng, 8, 16, true, true);
small_entries!(
    accumulate_small_8w_16s_pcg_unconnected,
    accumulate_small_8w_16s_pcg_unconnected_noroulette,
    Rng,
    8,
    16,
    false,
    true
);
small_entries!(
    accumulate_small_8w_16s_pcg_unconnected_noglow,
    accumulate_small_8w_16s_pcg_unconnected_noglow_noroulette,
    Rng,
    8,
    16,
    false,
    false
);
small_entries!(
    accumulate_small_8w_16s_sobol,
    accumulate_small_8w_16s_sobol_noroulette,
    SobolSampler,
    8,
    16,
    true,
    true
);
small_entries!(
    accumulate_small_8w_16s_sobol_unconnected,
    accumulate_small_8w_16s_sobol_unconnected_noroulette,
    SobolSampler,
    8,
    16,
    false,
    true
);
small_entries!(
    accumulate_small_8w_16s_sobol_unconnected_noglow,
    accumulate_small_8w_16s_sobol_unconnected_noglow_noroulette,
    SobolSampler,
    8,
    16,
    false,
    false
);
small_entries!(
    accumulate_small_8w_16s_sobol_deep,
    accumulate_small_8w_16s_sobol_deep_noroulette,
    SobolDeep,
    8,
    16,
    true,
    true
);
small_entries!(
    accumulate_small_8w_16s_sobol_deep_unconnected,
    accumulate_small_8w_16s_sobol_deep_unconnected_noroulette,
    SobolDeep,
    8,
    16,
    false,
    true
);
small_entries!(
    accumulate_small_8w_16s_sobol_deep_unconnected_noglow,
    accumulate_small_8w_16s_sobol_deep_unconnected_noglow_noroulette,
    SobolDeep,
    8,
    16,
    false,
    false
);

/// Turns every pixel's mean into a display colour: exposure, tone map, sRGB
/// (pixel `id` of the tile).
#[spirv(compute(threads(8, 8)))]
pub fn display(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] params: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] accum: &[AccumPixel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] out: &mut [u32],
) {
    if id.x >= params.tile.width || id.y >= params.tile.height {
        return;
    }
    let i = (id.y * params.tile.width + id.x) as usize;
    let color = tonemap::display_color(accum[i].mean(), params.exposure, params.tonemap);
    out[i] = tonemap::pack_rgba8(color);
}

/// A triangle that covers the viewport (vertices 0, 1, 2), with `uv` from
/// (0, 0) at the viewport's top left to (1, 1) at its bottom right.
#[spirv(vertex)]
pub fn blit_vs(#[spirv(vertex_index)] index: i32, #[spirv(position)] position: &mut Vec4, uv: &mut Vec2) {
    *position = tonemap::fullscreen_triangle(index as u32);
    *uv = Vec2::new(position.x + 1.0, 1.0 - position.y) * 0.5;
}

/// Shows the display buffer (a tile, the whole image in the viewer) in a
/// viewport of exactly its size, one pixel per framebuffer pixel.
#[spirv(fragment)]
pub fn blit_fs(
    uv: Vec2,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 0)] params: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] display: &[u32],
    color: &mut Vec4,
) {
    // uv * size lands on pixel centres (x + 0.5): the floor is the pixel.
    let tile = params.tile;
    let (x, y) = ((uv.x * tile.width as f32) as u32, (uv.y * tile.height as f32) as u32);
    *color = if x < tile.width && y < tile.height {
        tonemap::unpack_rgba8(display[(y * tile.width + x) as usize])
    } else {
        Vec4::new(0.0, 0.0, 0.0, 1.0)
    };
}
