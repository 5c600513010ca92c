//! Benchmark instrumentation, fenced off from the product path: the path
//! loop counts its rays through [`RayCounter`], and the renderers pass
//! [`NoRayCount`], which compiles to nothing. Only `pathtracer bench`
//! counts (rays per sample, on the CPU).

#[cfg(not(target_arch = "spirv"))]
use crate::geometry::Geometry;
#[cfg(not(target_arch = "spirv"))]
use crate::integrator::pixel;
#[cfg(not(target_arch = "spirv"))]
use crate::params::FrameParams;

/// Counts the rays a path traces (closest-hit and shadow rays), for the
/// benchmark's rays per second. The renderers use [`NoRayCount`], which
/// compiles to nothing.
pub trait RayCounter {
    /// One ray was traced.
    fn ray(&mut self);
}

/// The counter that counts nothing.
pub struct NoRayCount;

impl RayCounter for NoRayCount {
    #[inline]
    fn ray(&mut self) {}
}

/// A counter of rays (CPU only: the kernel never counts).
#[cfg(not(target_arch = "spirv"))]
#[derive(Default)]
pub struct RayCount(pub u64);

#[cfg(not(target_arch = "spirv"))]
impl RayCounter for RayCount {
    #[inline]
    fn ray(&mut self) {
        self.0 += 1;
    }
}

/// Rays traced by the samples of pixel (`x`, `y`) in one frame: what
/// [`crate::integrator::render_pixel`] does, counting its rays (benchmarks).
#[cfg(not(target_arch = "spirv"))]
pub fn count_pixel_rays(x: u32, y: u32, params: &FrameParams, geometry: &Geometry) -> u64 {
    let mut count = RayCount::default();
    pixel(x, y, params, geometry, geometry, &mut count);
    count.0
}
