//! The pinhole camera and primary rays.

#[cfg(target_arch = "spirv")]
use spirv_std::num_traits::Float;

use bytemuck::{Pod, Zeroable};
use spirv_std::glam::Vec3;

use crate::ray::Ray;

/// A pinhole camera as the kernel reads it. `right` and `up` are scaled so
/// that film coordinates in [-1, 1] span the field of view.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Camera {
    /// Pinhole position, world space.
    pub position: Vec3,
    /// Padding.
    pub _pad0: f32,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Padding.
    pub _pad1: f32,
    /// Right vector times tan(vfov / 2) times the aspect ratio (width/height).
    pub right: Vec3,
    /// Padding.
    pub _pad2: f32,
    /// Up vector times tan(vfov / 2).
    pub up: Vec3,
    /// Padding.
    pub _pad3: f32,
}

impl Camera {
    /// A camera at `position` looking at `target` with `up` as the rough up
    /// direction, vertical field of view `vfov_degrees`, film `aspect` =
    /// width / height. The caller ensures `target != position` and `up` is
    /// not parallel to the view direction (the scene loader checks both).
    pub fn look_at(position: Vec3, target: Vec3, up: Vec3, vfov_degrees: f32, aspect: f32) -> Self {
        let forward = (target - position).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        let tan_half = (vfov_degrees.to_radians() * 0.5).tan();
        Self { position, forward, right: right * (tan_half * aspect), up: true_up * tan_half, ..Self::default() }
    }

    /// The primary ray through film point (`fx`, `fy`) in pixels, row 0 at
    /// the top, for a `width` x `height` image.
    pub fn ray(&self, fx: f32, fy: f32, width: u32, height: u32) -> Ray {
        let sx = 2.0 * fx / width as f32 - 1.0;
        let sy = 1.0 - 2.0 * fy / height as f32;
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray { origin: self.position, dir }
    }
}
