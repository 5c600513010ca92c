//! Throughput: frames, camera samples and rays per second.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::Result;
use pt_core::{FrameParams, instrument};
use pt_render::gpu::{GpuContext, GpuRenderer, GpuTimer, TraceKernel, WORKGROUP_SHAPES};
use pt_render::scene::DEFAULT_RR_START;
use pt_render::{CpuRenderer, RenderSettings, Scene};
use rayon::prelude::*;

use super::{BenchBackend, median_min_max};

/// A throughput configuration.
pub struct ThroughputConfig {
    /// Label in the report.
    pub name: &'static str,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel per frame.
    pub spp: u32,
    /// Max bounces.
    pub bounces: u32,
    /// Whether the GPU times every workgroup shape here, not only the
    /// default one (with the general kernel, the only one they come in).
    pub all_shapes: bool,
    /// Whether the GPU times both forms of the trace kernel here, not only
    /// the adapter's default.
    pub both_kernels: bool,
}

/// The configurations measured; the first is the original OpenGL design's.
pub const THROUGHPUT_CONFIGS: [ThroughputConfig; 6] = [
    ThroughputConfig {
        name: "original design: 1920x1080, 4 spp/frame, 5 bounces",
        width: 1920,
        height: 1080,
        spp: 4,
        bounces: 5,
        all_shapes: false,
        both_kernels: false,
    },
    ThroughputConfig {
        name: "1920x1080, 16 spp/frame, 5 bounces",
        width: 1920,
        height: 1080,
        spp: 16,
        bounces: 5,
        all_shapes: false,
        both_kernels: false,
    },
    ThroughputConfig {
        name: "1920x1080, 64 spp/frame (render's default), 5 bounces",
        width: 1920,
        height: 1080,
        spp: 64,
        bounces: 5,
        all_shapes: false,
        both_kernels: true,
    },
    ThroughputConfig {
        name: "512x512, 4 spp/frame, 5 bounces",
        width: 512,
        height: 512,
        spp: 4,
        bounces: 5,
        all_shapes: true,
        both_kernels: false,
    },
    ThroughputConfig {
        name: "512x512, 64 spp/frame, 5 bounces",
        width: 512,
        height: 512,
        spp: 64,
        bounces: 5,
        all_shapes: false,
        both_kernels: false,
    },
    ThroughputConfig {
        name: "512x512, 4 spp/frame, 1 bounce",
        width: 512,
        height: 512,
        spp: 4,
        bounces: 1,
        all_shapes: false,
        both_kernels: false,
    },
];

/// One measured row.
pub struct ThroughputRow {
    /// Configuration label.
    pub config: String,
    /// Where it ran.
    pub backend: BenchBackend,
    /// Median frames per second, with min and max over repetitions.
    pub fps: (f64, f64, f64),
    /// Camera samples per second at the median.
    pub samples_per_second: f64,
    /// Rays (closest-hit and shadow) per second at the median.
    pub rays_per_second: f64,
    /// Rays per camera sample (counted on the CPU over a pixel subset).
    pub rays_per_sample: f64,
    /// How frames were timed.
    pub timing: &'static str,
}

/// Rays per camera sample of a configuration: the CPU's instrumented trace
/// over every 4th pixel in x and y (same code, same distribution as the GPU).
fn rays_per_sample(params: &FrameParams, scene: &Scene) -> Result<f64> {
    let geometry = scene.geometry()?;
    let rows: Vec<u32> = (0..params.height).step_by(4).collect();
    let (rays, samples) = rows
        .par_iter()
        .map(|&y| {
            let mut r = 0u64;
            let mut n = 0u64;
            for x in (0..params.width).step_by(4) {
                r += instrument::count_pixel_rays(x, y, params, &geometry);
                n += params.samples_per_frame as u64;
            }
            (r, n)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    Ok(rays as f64 / samples as f64)
}

/// Measures every configuration on the GPU (when `ctx` is given) and the
/// CPU: one warm-up frame, then `reps` timed frames.
pub fn throughput(ctx: Option<&GpuContext>, reps: usize, scene: &Scene) -> Result<Vec<ThroughputRow>> {
    let mut rows = Vec::new();
    for cfg in &THROUGHPUT_CONFIGS {
        let settings = RenderSettings {
            width: cfg.width,
            height: cfg.height,
            spp: cfg.spp,
            max_bounces: cfg.bounces,
            rr_start: DEFAULT_RR_START,
        };
        let params = scene.frame_params(&settings, cfg.spp, 1);
        let rps = rays_per_sample(&params, scene)?;
        let samples = cfg.width as f64 * cfg.height as f64 * cfg.spp as f64;
        if let Some(ctx) = ctx {
            // The adapter's default kernel and shape; the other kernel and
            // the other shapes where the configuration asks for them.
            let mut setups = vec![GpuSetup::Default];
            if cfg.both_kernels {
                let default = GpuRenderer::default_trace_kernel(ctx);
                setups.extend(TraceKernel::ALL.into_iter().filter(|&k| k != default).map(GpuSetup::Kernel));
            }
            if cfg.all_shapes {
                // Shapes are compared on the general kernel, the only one that
                // comes in every shape; its 8x8 row is the default's where the
                // adapter's default is the general kernel.
                let first = if GpuRenderer::default_trace_kernel(ctx) == TraceKernel::General { 1 } else { 0 };
                setups.extend((first..WORKGROUP_SHAPES.len()).map(GpuSetup::Shape));
            }
            for setup in setups {
                let (times, timestamps, label) = time_gpu(ctx, params, scene, cfg.spp, reps, setup)?;
                let backend = BenchBackend::gpu(format!("{}, {label}", ctx.adapter_info.name));
                rows.push(row(cfg, backend, times, samples, rps, timestamps));
            }
        }
        let mut cpu = CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres())?;
        cpu.render_frame(cfg.spp);
        let mut times = Vec::new();
        for _ in 0..reps {
            let start = Instant::now();
            cpu.render_frame(cfg.spp);
            times.push(start.elapsed().as_secs_f64());
        }
        rows.push(row(cfg, BenchBackend::cpu(), times, samples, rps, false));
    }
    Ok(rows)
}

/// Least time the GPU works before a throughput configuration is timed.
const WARM_UP_SECONDS: f64 = 0.5;

/// Which trace kernel a GPU throughput row times.
#[derive(Copy, Clone)]
enum GpuSetup {
    /// The renderer's own choice for the adapter, in the default shape.
    Default,
    /// Another form of the trace kernel, in the default shape.
    Kernel(TraceKernel),
    /// The general kernel in `WORKGROUP_SHAPES[i]`.
    Shape(usize),
}

/// Seconds of `reps` frames on the GPU after the warm-up, with the kernel
/// `setup` picks; whether they come from timestamps; and the kernel and
/// shape that ran, for the report.
fn time_gpu(
    ctx: &GpuContext,
    params: FrameParams,
    scene: &Scene,
    spp: u32,
    reps: usize,
    setup: GpuSetup,
) -> Result<(Vec<f64>, bool, String)> {
    let mut r = GpuRenderer::new(ctx, params, &scene.gpu_walls(), &scene.gpu_spheres())?;
    let mut shape = 0;
    match setup {
        GpuSetup::Default => {}
        GpuSetup::Kernel(kernel) => r.set_trace_kernel(ctx, kernel),
        GpuSetup::Shape(i) => {
            r.set_workgroup_shape(ctx, i);
            shape = i;
        }
    }
    let (_, w, h) = WORKGROUP_SHAPES[shape];
    let label = format!("workgroup {w}x{h}, {}", r.trace_kernel().name());
    let timer = if ctx.is_software() { None } else { GpuTimer::new(ctx) };
    // Warm-up: frames until half a second has passed (at least one). A GPU
    // left idle while the CPU counted rays runs its first frames at idle
    // clocks: an H100 measured at 20 frames/s, then at 117, with one
    // warm-up frame.
    let warm_up = Instant::now();
    loop {
        r.submit_frame(spp);
        ctx.wait()?;
        if warm_up.elapsed().as_secs_f64() >= WARM_UP_SECONDS {
            break;
        }
    }
    let mut times = Vec::new();
    for _ in 0..reps {
        let start = Instant::now();
        r.submit_frame_timed(spp, timer.as_ref());
        ctx.wait()?;
        let wall = start.elapsed().as_secs_f64();
        times.push(match &timer {
            Some(t) => t.read_ms(ctx)? * 1e-3,
            None => wall,
        });
    }
    Ok((times, timer.is_some(), label))
}

fn row(
    cfg: &ThroughputConfig,
    backend: BenchBackend,
    times: Vec<f64>,
    samples: f64,
    rps: f64,
    timestamps: bool,
) -> ThroughputRow {
    let fps: Vec<f64> = times.iter().map(|t| 1.0 / t).collect();
    let (med, lo, hi) = median_min_max(fps);
    ThroughputRow {
        config: cfg.name.to_string(),
        backend,
        fps: (med, lo, hi),
        samples_per_second: med * samples,
        rays_per_second: med * samples * rps,
        rays_per_sample: rps,
        timing: if timestamps { "GPU timestamps" } else { "wall clock, synchronised" },
    }
}

/// The throughput table in markdown.
pub fn throughput_markdown(rows: &[ThroughputRow]) -> String {
    let mut s = String::from(
        "| configuration | backend | frames/s (median) | min-max | camera samples/s | rays/sample | rays/s | timing |\n|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {:.3}-{:.3} | {:.3e} | {:.2} | {:.3e} | {} |",
            r.config,
            r.backend,
            r.fps.0,
            r.fps.1,
            r.fps.2,
            r.samples_per_second,
            r.rays_per_sample,
            r.rays_per_second,
            r.timing
        );
    }
    s
}
