//! One interface over the GPU and CPU backends, and the progressive render
//! loop that `pathtracer render` and the tests drive.

use std::ops::Range;
use std::time::{Duration, Instant};

use pt_core::{AccumPixel, FrameParams, Sphere, Tile, Wall};

use crate::cpu::CpuRenderer;
use crate::gpu::renderer::max_image_bytes;
use crate::gpu::{GpuContext, GpuError, GpuRenderer};

/// The frame index `frame` wrapped into the indices a renderer may write:
/// every `u32` but `u32::MAX`, which would turn off the kernel's Kahan
/// compensation (`FrameParams::keeps_sums`). Both renderers number their
/// frames through it, so they keep drawing the same samples.
pub(crate) fn frame_index(frame: u32) -> u32 {
    frame % u32::MAX
}

/// Where paths are traced: the rust-gpu kernel on a GPU context (shared by
/// every renderer made on it: the kernel is compiled once per context), or
/// the same code on the CPU. Every command, the viewer's tests, the
/// accuracy suite and the benchmarks choose their backend with this.
#[derive(Copy, Clone)]
pub enum Device<'a> {
    /// The rust-gpu kernel through wgpu, on this context.
    Gpu(&'a GpuContext),
    /// The same code on the CPU, parallel with rayon.
    Cpu,
}

impl Device<'_> {
    /// "gpu" or "cpu", for case names and file names.
    pub fn name(&self) -> &'static str {
        match self {
            Device::Gpu(_) => "gpu",
            Device::Cpu => "cpu",
        }
    }

    /// What renders: the adapter for the GPU, the thread count for the CPU.
    pub fn description(&self) -> String {
        match self {
            Device::Gpu(ctx) => format!("GPU: {}", ctx.adapter_description()),
            Device::Cpu => format!("CPU: {} threads", rayon::current_num_threads()),
        }
    }
}

/// A progressive renderer on either backend.
pub enum Renderer<'a> {
    /// GPU backend on a shared context.
    Gpu(&'a GpuContext, Box<GpuRenderer>),
    /// CPU backend.
    Cpu(Box<CpuRenderer>),
}

impl<'a> Renderer<'a> {
    /// A renderer on `device` with an empty accumulation.
    pub fn new(device: Device<'a>, params: FrameParams, walls: &[Wall], spheres: &[Sphere]) -> Result<Self, GpuError> {
        Ok(match device {
            Device::Gpu(ctx) => Renderer::Gpu(ctx, Box::new(GpuRenderer::new(ctx, params, walls, spheres)?)),
            Device::Cpu => Renderer::Cpu(Box::new(CpuRenderer::new(params, walls, spheres)?)),
        })
    }

    /// The device it renders on.
    pub fn device(&self) -> Device<'a> {
        match self {
            Renderer::Gpu(ctx, _) => Device::Gpu(ctx),
            Renderer::Cpu(_) => Device::Cpu,
        }
    }

    /// What renders: the adapter for the GPU, the thread count for the CPU.
    pub fn description(&self) -> String {
        self.device().description()
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

    /// Continues a render that stopped after `frames` frames and `samples`
    /// samples per pixel: the next frames are those of the whole render.
    pub fn start_at(&mut self, frames: u32, samples: u32) {
        match self {
            Renderer::Gpu(_, r) => r.start_at(frames, samples),
            Renderer::Cpu(r) => r.start_at(frames, samples),
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
    renderer: &mut Renderer<'_>,
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
        samples: p.tile.pixels() * spp as u64,
        non_finite: accum.iter().map(|a| a.non_finite as u64).sum(),
    };
    Ok((accum, stats))
}

/// Renders `spp` samples per pixel in frames of at most `per_frame` on
/// `device` and returns the accumulation: [`render_progressive`] without
/// progress, a whole render for tests and the accuracy suite.
pub fn render_accum(
    device: Device<'_>,
    params: FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    spp: u32,
    per_frame: u32,
) -> Result<Vec<AccumPixel>, GpuError> {
    let mut renderer = Renderer::new(device, params, walls, spheres)?;
    Ok(render_progressive(&mut renderer, spp, per_frame, |_| {})?.0)
}

/// The tiles of a `width` x `height` image: bands of whole rows, each of at
/// most `max_pixels` pixels (at least one row), top to bottom. Bands keep
/// each tile's rows contiguous in the image, so tiles join by appending.
pub fn row_bands(width: u32, height: u32, max_pixels: u64) -> Vec<Tile> {
    let rows = (max_pixels / width.max(1) as u64).clamp(1, height.max(1) as u64) as u32;
    (0..height).step_by(rows as usize).map(|y| Tile { x: 0, y, width, height: rows.min(height - y) }).collect()
}

/// The tiles `device` renders a `width` x `height` image in: the whole
/// image where its accumulation fits one buffer of the adapter, else bands
/// of rows that each fit. GPU memory then stays within one tile's buffers
/// (at most [`max_image_bytes`], 128 MiB on lavapipe, plus an eighth for
/// the display), whatever the image size. The CPU renders the whole image.
pub fn device_tiles(device: Device<'_>, width: u32, height: u32) -> Vec<Tile> {
    match device {
        Device::Gpu(ctx) => row_bands(width, height, max_image_bytes(&ctx.device) / size_of::<AccumPixel>() as u64),
        Device::Cpu => vec![Tile::whole(width, height)],
    }
}

/// A whole image rendered tile by tile.
pub struct TiledRender {
    /// The accumulation of the whole image, row 0 at the top.
    pub accum: Vec<AccumPixel>,
    /// The display pass's RGBA8 output, when asked for.
    pub display: Option<Vec<u32>>,
    /// Figures summed over the tiles.
    pub stats: RenderStats,
}

/// Renders the image of `params` (whose tile is ignored) in `tiles`, bands
/// of whole rows from [`row_bands`] or [`device_tiles`], one renderer at a
/// time: the samples per pixel `samples` of the whole render (all of them
/// from 0, or a part from [`crate::parts::part_samples`], which starts on a
/// frame boundary) in frames of at most `per_frame`, and the display pass
/// with `display` = (exposure, tone mapper) when given. `progress(tile,
/// samples done in it)` follows [`render_progressive`]. Pixels keep their
/// image coordinates and frames their indices, so the result is the one a
/// single tile would give.
#[allow(clippy::too_many_arguments)]
pub fn render_tiled(
    device: Device<'_>,
    params: FrameParams,
    walls: &[Wall],
    spheres: &[Sphere],
    samples: Range<u32>,
    per_frame: u32,
    tiles: &[Tile],
    display: Option<(f32, u32)>,
    mut progress: impl FnMut(usize, u32),
) -> Result<TiledRender, GpuError> {
    let per_frame = per_frame.max(1);
    let mut out = TiledRender {
        accum: Vec::with_capacity(params.width as usize * params.height as usize),
        display: display.map(|_| Vec::new()),
        stats: RenderStats { elapsed: Duration::ZERO, samples: 0, non_finite: 0 },
    };
    for (i, &tile) in tiles.iter().enumerate() {
        let mut renderer = Renderer::new(device, FrameParams { tile, ..params }, walls, spheres)?;
        renderer.start_at(samples.start / per_frame, samples.start);
        let spp = samples.end.saturating_sub(samples.start);
        let (accum, stats) = render_progressive(&mut renderer, spp, per_frame, |done| progress(i, done))?;
        out.accum.extend_from_slice(&accum);
        if let (Some((exposure, tonemap)), Some(rgba)) = (display, out.display.as_mut()) {
            rgba.extend(renderer.display(exposure, tonemap)?);
        }
        out.stats.elapsed += stats.elapsed;
        out.stats.samples += stats.samples;
        out.stats.non_finite += stats.non_finite;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::frame_index;

    #[test]
    fn frame_indices_never_reach_u32_max() {
        assert_eq!(frame_index(7), 7);
        assert_eq!(frame_index(u32::MAX - 1), u32::MAX - 1);
        // The frame after the last allowed index, and a restored count of
        // u32::MAX, start again at 0.
        assert_eq!(frame_index((u32::MAX - 1).wrapping_add(1)), 0);
        assert_eq!(frame_index(u32::MAX.wrapping_add(1)), 0);
    }
}
