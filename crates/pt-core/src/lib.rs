//! The path tracer's core, shared by the rust-gpu kernel and the CPU.
//!
//! Everything here is plain functions over `#[repr(C)]` GPU types: the
//! kernel entry points in `shaders-rs/pt-kernel` wrap them, the CPU renderer
//! and the tests call them directly. No std and no allocation on the GPU side.
#![cfg_attr(target_arch = "spirv", no_std)]
#![deny(missing_docs)]

pub mod accum;
pub mod bsdf;
pub mod camera;
pub mod geometry;
pub mod instrument;
pub mod integrator;
pub mod light;
pub mod params;
pub mod query;
pub mod ray;
pub mod rng;
pub mod sampler;
pub mod sampling;
pub mod small_scene;
pub mod sphere;
pub mod tonemap;
pub mod wall;

#[cfg(test)]
mod test_support;

pub use spirv_std::glam;

pub use accum::{AccumPixel, PixelSamples};
pub use camera::Camera;
pub use geometry::Geometry;
pub use light::SphereLight;
pub use params::{FrameParams, Tile};
pub use ray::Ray;
pub use sphere::Sphere;
pub use wall::Wall;

/// Workgroup edge of the kernel's 2D dispatch (threads are `WORKGROUP_SIZE`
/// x `WORKGROUP_SIZE`). The kernel's `threads(8, 8)` must match.
pub const WORKGROUP_SIZE: u32 = 8;
