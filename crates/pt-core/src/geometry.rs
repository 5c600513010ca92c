//! The scene's walls and spheres as the kernel reads them: fixed-size arrays
//! in one uniform block.
//!
//! Why a uniform block and not storage buffers: every ray tests every wall
//! and sphere in the same order, so all invocations read the same element at
//! the same time. lavapipe (Mesa's llvmpipe) turns a uniform-block read at a
//! dynamically uniform offset into one scalar load broadcast to its SIMD
//! lanes, but reads a storage buffer one lane at a time behind a bounds
//! check (Mesa 22.3, `emit_load_ubo` against `emit_load_mem` in
//! `lp_bld_nir_soa.c`); GPUs serve such reads from their constant caches.
//! docs/PERFORMANCE.md has the measured difference.

use bytemuck::{Pod, Zeroable};

use crate::sphere::Sphere;
use crate::wall::Wall;

/// Most walls a scene may have. With [`MAX_SPHERES`] it keeps the block
/// within 16 KiB, the smallest uniform-block size Vulkan guarantees.
pub const MAX_WALLS: usize = 96;

/// Most spheres (besides the light) a scene may have.
pub const MAX_SPHERES: usize = 128;

/// Walls and spheres; `FrameParams::wall_count` and `sphere_count` say how
/// many of each are in use, the rest are zero.
#[repr(C)]
#[derive(Copy, Clone, Debug, PartialEq, Pod, Zeroable)]
pub struct Geometry {
    /// Walls `0..wall_count`.
    pub walls: [Wall; MAX_WALLS],
    /// Spheres `0..sphere_count`.
    pub spheres: [Sphere; MAX_SPHERES],
}

#[cfg(not(target_arch = "spirv"))]
impl Geometry {
    /// The block holding `walls` and `spheres`, or `None` when there are
    /// more than [`MAX_WALLS`] walls or [`MAX_SPHERES`] spheres (the scene
    /// loader rejects such scenes with a message first).
    pub fn new(walls: &[Wall], spheres: &[Sphere]) -> Option<Self> {
        if walls.len() > MAX_WALLS || spheres.len() > MAX_SPHERES {
            return None;
        }
        let mut g = Self::zeroed();
        g.walls[..walls.len()].copy_from_slice(walls);
        g.spheres[..spheres.len()].copy_from_slice(spheres);
        Some(g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spirv_std::glam::Vec3;

    #[test]
    fn new_copies_in_order_and_refuses_too_many() {
        let w = Wall::new(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE);
        let s = Sphere::new(Vec3::ONE, 0.5, Vec3::splat(0.5));
        let g = Geometry::new(&[w], &[s, s]).unwrap();
        assert_eq!(g.walls[0], w);
        assert_eq!(g.walls[1], Wall::zeroed());
        assert_eq!(g.spheres[1], s);
        assert_eq!(g.spheres[2], Sphere::zeroed());
        assert!(Geometry::new(&[w; MAX_WALLS], &[s; MAX_SPHERES]).is_some());
        assert!(Geometry::new(&[w; MAX_WALLS + 1], &[]).is_none());
        assert!(Geometry::new(&[], &[s; MAX_SPHERES + 1]).is_none());
    }
}
