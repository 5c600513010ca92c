//! The kernel's bindings (descriptor set 0), named once for the host. The
//! kernel's `#[spirv(binding = N)]` attributes must be literals, so the
//! numbers are written there too; `tests/layout.rs` checks that each name
//! here binds the type the kernel declares at that number.

use pt_core::FrameParams;

/// `FrameParams` (read-only storage): size, camera, light, settings of the
/// frame. Not a uniform block: lavapipe (Mesa 22.3) looks for uniform-block
/// values that steer a large shader's branches and loops
/// (`lvp_find_inlinable_uniforms`), and then, on every dispatch after the
/// block was written, clones the shader, folds the values in and
/// re-optimises it (`update_inline_shader_state`) before it looks for a
/// compiled variant: a fixed cost per dispatch, whatever the image size
/// (docs/ARCHITECTURE.md). A storage buffer is never inlined.
pub const PARAMS: u32 = 0;
/// `Geometry` (uniform): the walls and spheres.
pub const GEOMETRY: u32 = 1;
/// `[AccumPixel]` (storage): the per-pixel compensated sums.
pub const ACCUM: u32 = 2;
/// `[u32]` (storage): the display image, RGBA8 packed per pixel.
pub const DISPLAY: u32 = 3;
/// `[u32]` (storage): one counter of non-finite samples discarded.
pub const NON_FINITE: u32 = 4;

pub(super) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// `FrameParams` at [`PARAMS`], read-only, for `visibility`.
pub(super) fn params_entry(visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding: PARAMS,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<FrameParams>() as u64),
        },
        count: None,
    }
}

/// A uniform block of type `T` at `binding`, for the compute stage.
pub(super) fn uniform_entry<T>(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<T>() as u64),
        },
        count: None,
    }
}

/// A layout of `FrameParams` at [`PARAMS`] plus `others`.
pub(super) fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    others: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    let mut entries = vec![params_entry(wgpu::ShaderStages::COMPUTE)];
    entries.extend_from_slice(others);
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

pub(super) fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> =
        buffers.iter().map(|&(binding, b)| wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }).collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("pt-kernel"), layout, entries: &entries })
}
