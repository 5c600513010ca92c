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

    /// NEE's control variate where the light's cone crosses a vertex's
    /// horizon: a large light beside the large sphere, whose tangent planes
    /// cut through the light over a wide band of its lit side, which fills
    /// the view. Direct light only (one bounce), 24x24 pixels, 64 spp, 10
    /// seeds with the control variate and 10 without: the image means
    /// agree, their difference within 5 standard errors of the seeds'
    /// spread (a control weight that left out part of the cone, or a
    /// signed integral that did not match the cone's, shows here).
    #[test]
    fn the_control_variate_is_unbiased_where_the_cone_crosses_the_horizon() {
        use pt_core::SphereLight;
        use pt_core::glam::Vec3;
        use pt_core::params::FLAG_NEE_CONTROL;
        let mut scene = Scene::default_scene();
        scene.light = SphereLight::new(Vec3::new(0.1, 0.9, -0.3), 0.3, Vec3::splat(8.0));
        scene.camera.position = Vec3::new(-0.45, 0.4, 0.9);
        scene.camera.look_at = Vec3::new(-0.45, 0.4, -0.3);
        scene.camera.vfov_degrees = 30.0;
        let settings = RenderSettings { width: 24, height: 24, spp: 0, max_bounces: 1, rr_start: 5 };
        let flags = crate::strategy::BASE_FLAGS;
        assert_ne!(flags & FLAG_NEE_CONTROL, 0);
        let seeds = 10u32;
        // The mean over seeds of the image's mean, and its standard error.
        let image_mean = |flags: u32| -> (f64, f64) {
            let means: Vec<f64> = (0..seeds)
                .map(|seed| {
                    let params = scene.frame_params_with_flags(&settings, 64, 40 + seed, flags);
                    let mut r = CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
                    r.render_frame(64);
                    let sum: f64 = r.accum().iter().map(|p| p.mean().element_sum() as f64).sum();
                    sum / r.accum().len() as f64
                })
                .collect();
            let n = seeds as f64;
            let m = means.iter().sum::<f64>() / n;
            (m, (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt())
        };
        let (with, without) = (image_mean(flags), image_mean(flags & !FLAG_NEE_CONTROL));
        let z = (with.0 - without.0) / (with.1 * with.1 + without.1 * without.1).sqrt();
        assert!(z.abs() < 5.0, "means {} and {} differ by {z} standard errors", with.0, without.0);
    }

    /// The light edge's control variate (`FLAG_LIGHT_EDGE`) on the pixels
    /// the light's silhouette crosses in the default scene at 64 x 64 (an
    /// image radius of 3.8 pixels), direct light only, 16 spp, 12 seeds
    /// with it and 12 without: the pixels' summed mean agrees (within 5
    /// standard errors of the seeds' spread), and their summed variance
    /// over the seeds falls at least a hundredfold (nothing hides the
    /// light there, so each sample's own light cancels and the pixel takes
    /// the exact share the light covers; 5,000-fold when written).
    #[test]
    fn the_light_edge_control_variate_is_unbiased_and_takes_the_edges_noise() {
        use pt_core::integrator::light_edge;
        use pt_core::params::FLAG_LIGHT_EDGE;
        let scene = Scene::default_scene();
        let settings = RenderSettings { width: 64, height: 64, spp: 0, max_bounces: 1, rr_start: 5 };
        let flags = crate::strategy::BASE_FLAGS;
        assert_ne!(flags & FLAG_LIGHT_EDGE, 0);
        let probe = scene.frame_params_with_flags(&settings, 16, 0, flags);
        let edge: Vec<usize> = (0..64 * 64)
            .filter(|&i| {
                let a = light_edge(i as u32 % 64, i as u32 / 64, &probe).share;
                a > 0.0 && a < 1.0
            })
            .collect();
        assert!(edge.len() >= 16, "{} pixels on the edge", edge.len());
        let seeds = 12u32;
        // Per seed, the edge pixels' mean radiance (channel sum).
        let renders = |flags: u32| -> Vec<Vec<f64>> {
            (0..seeds)
                .map(|seed| {
                    let params = scene.frame_params_with_flags(&settings, 16, 70 + seed, flags);
                    let mut r = CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
                    r.render_frame(16);
                    edge.iter().map(|&i| r.accum()[i].mean().element_sum() as f64).collect()
                })
                .collect()
        };
        let n = seeds as f64;
        // The summed mean and its standard error, and the summed variance.
        let stats = |images: &[Vec<f64>]| -> (f64, f64, f64) {
            let totals: Vec<f64> = images.iter().map(|px| px.iter().sum()).collect();
            let mean = totals.iter().sum::<f64>() / n;
            let se = (totals.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
            let variance: f64 = (0..edge.len())
                .map(|k| {
                    let m = images.iter().map(|px| px[k]).sum::<f64>() / n;
                    images.iter().map(|px| (px[k] - m).powi(2)).sum::<f64>() / (n - 1.0)
                })
                .sum();
            (mean, se, variance)
        };
        let (with, without) = (stats(&renders(flags)), stats(&renders(flags & !FLAG_LIGHT_EDGE)));
        let z = (with.0 - without.0) / (with.1 * with.1 + without.1 * without.1).sqrt();
        assert!(z.abs() < 5.0, "means {} and {} differ by {z} standard errors", with.0, without.0);
        assert!(with.2 * 100.0 < without.2, "variance {} with the control variate, {} without", with.2, without.2);
    }

    /// The lanes add the light edge's terms as the scalar loop does: a tile
    /// of the default scene at 128 x 128 over the light's image, whose
    /// silhouette crosses it, bit for bit.
    #[test]
    fn lanes_and_single_pixels_agree_across_the_lights_edge() {
        use pt_core::params::FLAG_LIGHT_EDGE;
        let scene = Scene::default_scene();
        let settings = RenderSettings { width: 128, height: 128, spp: 0, max_bounces: 5, rr_start: 5 };
        let mut params = scene.frame_params(&settings, 8, 3);
        assert_ne!(params.flags & FLAG_LIGHT_EDGE, 0);
        params.tile = Tile { x: 50, y: 16, width: 27, height: 24 };
        let new = || CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
        let (mut lanes, mut single) = (new(), new().one_pixel_at_a_time());
        for spp in [8, 3] {
            lanes.render_frame(spp);
            single.render_frame(spp);
        }
        assert_eq!(lanes.accum(), single.accum());
    }
}
