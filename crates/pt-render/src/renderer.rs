//! One interface over the GPU and CPU backends, and the progressive render
//! loop that `pathtracer render` and the tests drive.

use std::time::{Duration, Instant};

use pt_core::{AccumPixel, FrameParams, Sphere, Wall};

use crate::cpu::CpuRenderer;
use crate::gpu::{GpuContext, GpuError, GpuRenderer};

/// Which renderer traces the paths.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The rust-gpu kernel through wgpu.
    Gpu,
    /// The same code on the CPU, parallel with rayon.
    Cpu,
}

/// A progressive renderer on either backend.
pub enum Renderer {
    /// GPU backend with its context.
    Gpu(Box<GpuContext>, Box<GpuRenderer>),
    /// CPU backend.
    Cpu(Box<CpuRenderer>),
}

impl Renderer {
    /// A renderer on `backend` with an empty accumulation.
    pub fn new(backend: Backend, params: FrameParams, walls: &[Wall], spheres: &[Sphere]) -> Result<Self, GpuError> {
        Ok(match backend {
            Backend::Gpu => {
                let ctx = GpuContext::new()?;
                let r = GpuRenderer::new(&ctx, params, walls, spheres)?;
                Renderer::Gpu(Box::new(ctx), Box::new(r))
            }
            Backend::Cpu => Renderer::Cpu(Box::new(CpuRenderer::new(params, walls, spheres)?)),
        })
    }

    /// What renders: the adapter for the GPU, the thread count for the CPU.
    pub fn description(&self) -> String {
        match self {
            Renderer::Gpu(ctx, _) => format!("GPU: {}", ctx.adapter_description()),
            Renderer::Cpu(_) => format!("CPU: {} threads", rayon::current_num_threads()),
        }
    }

    /// The parameters in use.
    pub fn params(&self) -> &FrameParams {
        match self {
            Renderer::Gpu(_, r) => r.params(),
            Renderer::Cpu(r) => r.params(),
        }
    }

    /// Adds one frame of `samples` samples per pixel. On the GPU it is only
    /// submitted; [`Renderer::wait`] waits for it.
    pub fn frame(&mut self, samples: u32) {
        match self {
            Renderer::Gpu(_, r) => r.submit_frame(samples),
            Renderer::Cpu(r) => r.render_frame(samples),
        }
    }

    /// Waits for submitted work; reports a lost device.
    pub fn wait(&self) -> Result<(), GpuError> {
        match self {
            Renderer::Gpu(ctx, _) => ctx.wait(),
            Renderer::Cpu(_) => Ok(()),
        }
    }

    /// The accumulation buffer.
    pub fn accum(&self) -> Result<Vec<AccumPixel>, GpuError> {
        match self {
            Renderer::Gpu(ctx, r) => r.read_accum(ctx),
            Renderer::Cpu(r) => Ok(r.accum().to_vec()),
        }
    }

    /// The display pass's output: RGBA8 per pixel, row 0 at the top.
    pub fn display(&mut self, exposure: f32, tonemap: u32) -> Result<Vec<u32>, GpuError> {
        match self {
            Renderer::Gpu(ctx, r) => {
                r.submit_display(exposure, tonemap);
                r.read_display(ctx)
            }
            Renderer::Cpu(r) => Ok(r.display(exposure, tonemap)),
        }
    }
}

/// Figures of a finished render.
#[derive(Copy, Clone, Debug)]
pub struct RenderStats {
    /// Wall-clock time of the sampling, synchronised at the end.
    pub elapsed: Duration,
    /// Camera samples traced (pixels x spp).
    pub samples: u64,
    /// Samples discarded as NaN or infinite.
    pub non_finite: u64,
}

impl RenderStats {
    /// Camera samples per second.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// Renders `spp` samples per pixel in frames of at most `per_frame`,
/// calling `progress(samples done)` after each synchronised batch. Returns
/// the accumulation and the figures.
pub fn render_progressive(
    renderer: &mut Renderer,
    spp: u32,
    per_frame: u32,
    mut progress: impl FnMut(u32),
) -> Result<(Vec<AccumPixel>, RenderStats), GpuError> {
    let per_frame = per_frame.max(1);
    let start = Instant::now();
    let mut done = 0;
    let mut last_sync = Instant::now();
    while done < spp {
        let n = per_frame.min(spp - done);
        renderer.frame(n);
        done += n;
        // Synchronise a few times a second: often enough for the progress
        // bar, rarely enough to keep the GPU queue full.
        if done == spp || last_sync.elapsed() > Duration::from_millis(250) {
            renderer.wait()?;
            last_sync = Instant::now();
            progress(done);
        }
    }
    renderer.wait()?;
    let elapsed = start.elapsed();
    let accum = renderer.accum()?;
    let p = renderer.params();
    let stats = RenderStats {
        elapsed,
        samples: p.width as u64 * p.height as u64 * spp as u64,
        non_finite: accum.iter().map(|a| a.non_finite as u64).sum(),
    };
    Ok((accum, stats))
}

/// Renders `spp` samples per pixel in frames of at most `per_frame`, on
/// the GPU of `ctx` or, without one, on the CPU, and returns the
/// accumulation: a whole render for tests and the accuracy suite, on a
/// context they share (pipelines are compiled once per context).
pub fn render_accum(
    ctx: Option<&GpuContext>,
    params: FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    spp: u32,
    per_frame: u32,
) -> Result<Vec<AccumPixel>, GpuError> {
    let per_frame = per_frame.max(1);
    let frames = (0..spp).step_by(per_frame as usize).map(|done| per_frame.min(spp - done));
    match ctx {
        Some(ctx) => {
            let mut r = GpuRenderer::new(ctx, params, walls, spheres)?;
            frames.for_each(|n| r.submit_frame(n));
            ctx.wait()?;
            r.read_accum(ctx)
        }
        None => {
            let mut r = CpuRenderer::new(params, walls, spheres)?;
            frames.for_each(|n| r.render_frame(n));
            Ok(r.accum().to_vec())
        }
    }
}
