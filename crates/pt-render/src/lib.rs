//! Host side of the path tracer: scene files, the wgpu renderer, the CPU
//! renderer, image output and error metrics.

pub mod accuracy;
pub mod cpu;
pub mod gpu;
#[cfg(target_arch = "x86_64")]
pub mod lanes;
pub mod metrics;
pub mod output;
pub mod parts;
pub mod renderer;
pub mod scene;
pub mod strategy;

pub use cpu::CpuRenderer;
pub use gpu::{GpuContext, GpuError, GpuRenderer, KERNEL_SPV};
pub use renderer::{Device, Renderer};
pub use scene::{RenderSettings, Scene, SceneError};
