//! The wgpu backend: the rust-gpu kernel dispatched one thread per pixel,
//! progressive accumulation in a GPU buffer, and the display pass.
//!
//! - [`context`]: the device on the best adapter, and its compiled kernel.
//! - [`kernel`]: the kernel module and its compute pipelines.
//! - [`bindings`]: the kernel's binding numbers, named once.
//! - [`renderer`]: the progressive renderer for one scene and image size.
//! - [`timer`]: GPU timestamps around a frame.
//! - [`blit`]: the viewer's draw of the display buffer.

pub mod bindings;
pub mod blit;
pub mod context;
pub mod kernel;
pub mod renderer;
pub mod timer;

pub use blit::Blit;
pub use context::{GpuContext, PendingRead};
pub use kernel::{
    TraceKernel, WORKGROUP_SHAPES, kernel_words, small_scene_entries, small_scene_misfit, specialized_spirv,
};
pub use renderer::GpuRenderer;
pub use timer::GpuTimer;

use crate::scene::TooManyObjects;

/// The kernel's SPIR-V: the committed module `shaders-rs/compiled/pt_kernel.spv`
/// unless `build.rs` was told to use another (`PT_KERNEL_SPV`, or the
/// `build-kernel` feature).
pub const KERNEL_SPV: &[u8] = include_bytes!(env!("PT_KERNEL_MODULE"));

/// Errors of the GPU backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error(
        "no GPU adapter found, not even a software Vulkan driver; install a Vulkan driver \
         (on Debian: `apt-get install mesa-vulkan-drivers` for lavapipe) or use `--backend cpu`"
    )]
    NoAdapter,
    /// The adapter would not create a device.
    #[error("the adapter {adapter} could not create a device: {source}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason.
        source: wgpu::RequestDeviceError,
    },
    /// The device was lost (driver reset, GPU removed, out of memory).
    #[error("the GPU device was lost: {0}")]
    DeviceLost(String),
    /// wgpu rejected a resource or the kernel.
    #[error("GPU error: {0}")]
    Validation(String),
    /// The image does not fit the adapter's buffer limits.
    #[error("a {width}x{height} image needs a {bytes}-byte GPU buffer, above this adapter's limit of {limit} bytes")]
    TooLarge {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Bytes needed.
        bytes: u64,
        /// The adapter's limit.
        limit: u64,
    },
    /// More walls or spheres than the kernel's geometry block holds.
    #[error(transparent)]
    TooManyObjects(#[from] TooManyObjects),
}
