//! The CPU renderer: the kernel's own `render_pixel`, in parallel over rows
//! with rayon. It is the reference in tests and a user-selectable backend.

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
        })
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
        self.accum.par_chunks_mut(tile.width.max(1) as usize).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                px.add(integrator::render_pixel(tile.x + x as u32, tile.y + y as u32, &params, geometry), true);
            }
        });
        self.next_frame += 1;
    }

    /// Continues a render that stopped after `frames` frames and `samples`
    /// samples per pixel, as [`crate::GpuRenderer::start_at`].
    pub fn start_at(&mut self, frames: u32, samples: u32) {
        self.next_frame = frames;
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
