//! Helpers for the cross-crate tests: renders of a scene on either backend,
//! as mean-radiance images.

use pt_core::AccumPixel;
use pt_render::renderer::render_accum;
use pt_render::{Device, GpuContext, RenderSettings, Scene};

/// A GPU context, or a panic that says why: GPU tests never skip silently.
/// CI installs Mesa's lavapipe, so an adapter is always there.
pub fn gpu() -> GpuContext {
    GpuContext::new().unwrap_or_else(|e| panic!("GPU tests need a Vulkan adapter (lavapipe in CI): {e}"))
}

/// Mean radiance per pixel of an accumulation.
pub fn means(accum: &[AccumPixel]) -> Vec<[f32; 3]> {
    accum.iter().map(|p| p.mean().to_array()).collect()
}

/// Renders `scene` at `settings` on the GPU with `seed`, in frames of
/// `per_frame` samples; returns the accumulation.
pub fn render_gpu(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &RenderSettings,
    per_frame: u32,
    seed: u32,
) -> Vec<AccumPixel> {
    let params = scene.frame_params(settings, per_frame, seed);
    render_accum(Device::Gpu(ctx), params, &scene.gpu_walls(), &scene.gpu_spheres(), settings.spp, per_frame)
        .expect("GPU render")
}

/// The same on the CPU.
pub fn render_cpu(scene: &Scene, settings: &RenderSettings, per_frame: u32, seed: u32) -> Vec<AccumPixel> {
    let params = scene.frame_params(settings, per_frame, seed);
    render_accum(Device::Cpu, params, &scene.gpu_walls(), &scene.gpu_spheres(), settings.spp, per_frame)
        .expect("CPU render")
}
