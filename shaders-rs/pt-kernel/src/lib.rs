//! The path tracer's compute entry points. Each is a thin wrapper: the work
//! is done by `pt-core` functions that the CPU renderer and tests also call.
//!
//! Bindings (descriptor set 0), shared by both entry points:
//! 0 `FrameParams` (uniform), 1 walls, 2 spheres, 3 accumulation buffer,
//! 4 display buffer (RGBA8 packed in u32). `pt-render` creates the layout.
#![cfg_attr(target_arch = "spirv", no_std)]

use pt_core::glam::UVec3;
use pt_core::{AccumPixel, FrameParams, Sphere, Wall, integrator, tonemap};
use spirv_std::spirv;

/// Adds one frame of `samples_per_frame` samples to every pixel's sum.
#[spirv(compute(threads(8, 8)))]
pub fn accumulate(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(uniform, descriptor_set = 0, binding = 0)] params: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 1)] walls: &[Wall],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 2)] spheres: &[Sphere],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] accum: &mut [AccumPixel],
) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let samples = integrator::render_pixel(id.x, id.y, params, walls, spheres);
    accum[(id.y * params.width + id.x) as usize].add(samples);
}

/// Turns every pixel's mean into a display colour: exposure, tone map, sRGB.
#[spirv(compute(threads(8, 8)))]
pub fn display(
    #[spirv(global_invocation_id)] id: UVec3,
    #[spirv(uniform, descriptor_set = 0, binding = 0)] params: &FrameParams,
    #[spirv(storage_buffer, descriptor_set = 0, binding = 3)] accum: &[AccumPixel],
    #[spirv(storage_buffer, descriptor_set = 0, binding = 4)] out: &mut [u32],
) {
    if id.x >= params.width || id.y >= params.height {
        return;
    }
    let i = (id.y * params.width + id.x) as usize;
    let color = tonemap::display_color(accum[i].mean(), params.exposure, params.tonemap);
    out[i] = tonemap::pack_rgba8(color);
}
