//! The CPU renderer: the kernel's own `render_pixel`, in parallel over rows
//! with rayon. It is the reference in tests and a user-selectable backend.
//! Where the CPU has AVX2 it runs the same path loop eight pixels at a time
//! ([`crate::lanes`]), which returns the same samples bit for bit.

use pt_core::tonemap::{display_color, pack_rgba8};
use pt_core::{AccumPixel, FrameParams, Geometry, Sphere, Wall, integrator};

use crate::scene::{TooManyObjects, geometry};
use rayon::prelude::*;

/// The progressive CPU renderer for one scene and image size.
pub struct CpuRenderer {
    params: FrameParams,
    geometry: Box<Geometry>,
    accum: Vec<AccumPixel>,
    next_frame: u32,
    /// Samples per pixel accumulated so far (Sobol index).
    samples_done: u32,
    /// Whether frames run eight pixels at a time ([`crate::lanes`]).
    lanes: bool,
}

impl CpuRenderer {
    /// A renderer for `params` and geometry, with an empty accumulation of
    /// `params.tile`.
    pub fn new(params: FrameParams, walls: &[Wall], spheres: &[Sphere]) -> Result<Self, TooManyObjects> {
        let pixels = params.tile.pixels() as usize;
        Ok(Self {
            params,
            geometry: Box::new(geometry(walls, spheres)?),
            accum: vec![AccumPixel::default(); pixels],
            next_frame: 0,
            samples_done: 0,
            lanes: lanes_available(),
        })
    }

    /// Runs every frame one pixel at a time, as the kernel does, even where
    /// the eight-lane loop is available: for tests that compare the two.
    #[cfg(test)]
    fn one_pixel_at_a_time(mut self) -> Self {
        self.lanes = false;
        self
    }

    /// The current parameters.
    pub fn params(&self) -> &FrameParams {
        &self.params
    }

    /// Adds one frame of `samples` samples per pixel, as the GPU's
    /// `accumulate` entry point does, with the same frame numbering.
    pub fn render_frame(&mut self, samples: u32) {
        self.params.frame = self.next_frame;
        self.params.samples_per_frame = samples;
        self.params.sample_offset = self.samples_done;
        self.samples_done = self.samples_done.saturating_add(samples);
        let params = self.params;
        let geometry = &*self.geometry;
        let tile = params.tile;
        let lanes = self.lanes;
        self.accum.par_chunks_mut(tile.width.max(1) as usize).enumerate().for_each(|(y, row)| {
            let y = tile.y + y as u32;
            #[cfg(target_arch = "x86_64")]
            if lanes {
                // SAFETY: `lanes` is set only where the CPU has AVX2.
                unsafe {
                    crate::lanes::render_row(&params, geometry, tile.x, y, tile.width, |x, s| row[x].add(s, true))
                };
                return;
            }
            let _ = lanes;
            for (x, px) in row.iter_mut().enumerate() {
                px.add(integrator::render_pixel(tile.x + x as u32, y, &params, geometry), true);
            }
        });
        self.next_frame = crate::renderer::frame_index(self.next_frame.wrapping_add(1));
    }

    /// Continues a render that stopped after `frames` frames and `samples`
    /// samples per pixel, as [`crate::GpuRenderer::start_at`].
    pub fn start_at(&mut self, frames: u32, samples: u32) {
        self.next_frame = crate::renderer::frame_index(frames);
        self.samples_done = samples;
    }

    /// Frames accumulated so far.
    pub fn frames(&self) -> u32 {
        self.next_frame
    }

    /// The accumulation buffer.
    pub fn accum(&self) -> &[AccumPixel] {
        &self.accum
    }

    /// The display pass on the CPU: the same transform as the kernel's.
    pub fn display(&self, exposure: f32, tonemap: u32) -> Vec<u32> {
        self.accum.par_iter().map(|p| pack_rgba8(display_color(p.mean(), exposure, tonemap))).collect()
    }
}

/// Whether the CPU renderer runs eight pixels at a time on this machine
/// ([`crate::lanes`]): then it is faster than lavapipe on the same cores.
pub fn lanes_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        crate::lanes::available()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{RenderSettings, Scene};
    use pt_core::Tile;

    /// Three frames of a tile of the default scene: the renderer's
    /// accumulation is the same bit for bit whether it runs eight pixels
    /// at a time or one, and it runs eight on an x86-64 CPU with AVX2.
    #[test]
    fn lanes_and_single_pixels_accumulate_the_same() {
        let scene = Scene::default_scene();
        let settings = RenderSettings { width: 40, height: 30, spp: 0, max_bounces: 5, rr_start: 5 };
        let mut params = scene.frame_params(&settings, 4, 11);
        params.tile = Tile { x: 5, y: 7, width: 19, height: 9 };
        let new = || CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
        let (mut lanes, mut single) = (new(), new().one_pixel_at_a_time());
        assert_eq!(lanes.lanes, cfg!(target_arch = "x86_64") && lanes_available());
        assert!(!single.lanes);
        for spp in [4, 1, 9] {
            lanes.render_frame(spp);
            single.render_frame(spp);
        }
        assert_eq!(lanes.accum().len(), 19 * 9);
        assert!(lanes.accum().iter().all(|p| p.samples == 14));
        assert_eq!(lanes.accum(), single.accum());
    }
}
