//! `pathtracer`: a progressive, physically based GPU path tracer.

mod bench;
mod viewer;

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use pt_core::params::{TONEMAP_ACES, TONEMAP_CLAMP};
use pt_render::metrics;
use pt_render::output::{self, OutputFormat};
use pt_render::renderer::render_progressive;
use pt_render::{Backend, RenderSettings, Renderer, Scene};

#[derive(Parser)]
#[command(name = "pathtracer", version, about = "A progressive, physically based GPU path tracer")]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the interactive viewer (the default when a display is available).
    View(ViewArgs),
    /// Render a scene to a PNG (tone-mapped sRGB) or EXR (linear radiance) file.
    Render(RenderArgs),
    /// Run the accuracy suite: analytic scenes, hard cases, sampling tests.
    Accuracy(AccuracyArgs),
    /// Benchmarks: throughput, and error against time (speed against error).
    Bench(BenchArgs),
    /// Compare an EXR with a reference EXR: MSE, RMSE, relMSE, MAPE, and region means.
    Compare(CompareArgs),
}

#[derive(Args, Clone, Default)]
struct ViewArgs {
    /// Scene file (TOML); the built-in default scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Window width in pixels.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: u32,
    /// Window height in pixels.
    #[arg(long, default_value_t = 768, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: u32,
    /// Stop tracing at this many samples per pixel (0: never).
    #[arg(long, default_value_t = 0)]
    spp: u32,
    /// Maximum scattering events per path [default: the scene's, else 5].
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=64))]
    max_bounces: Option<u32>,
    /// Run this many frames, then exit (with --screenshot: the hook for tests).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// Save what the window shows, panel included, as PNG after the last frame.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
}

#[derive(Args)]
struct BenchArgs {
    /// What to measure.
    #[arg(value_enum, default_value_t = BenchWhat::All)]
    what: BenchWhat,
    /// Scene for the convergence runs (default: the built-in scene).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Reference EXR for the convergence runs; rendered on the CPU at
    /// 100x --max-spp when absent.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Image width of the convergence runs.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=4096))]
    width: u32,
    /// Image height of the convergence runs.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=4096))]
    height: u32,
    /// Largest sample count of a convergence run (a power of two).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(4..=1_048_576))]
    max_spp: u32,
    /// Independent seeds per convergence configuration.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(2..=100))]
    seeds: u32,
    /// Timed repetitions per throughput configuration.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    reps: u32,
    /// Backends to measure.
    #[arg(long, value_enum, default_value_t = SuiteBackends::Both)]
    backend: SuiteBackends,
    /// Folder for the CSV, the plot and the rendered reference.
    #[arg(long, default_value = "bench-out")]
    out_dir: PathBuf,
    /// Write the report (markdown) here, e.g. docs/PERFORMANCE.md.
    #[arg(long)]
    report: Option<PathBuf>,
    /// A `time_s,rel_mse` CSV from scripts/mitsuba/compare.py to include.
    #[arg(long)]
    mitsuba_csv: Option<PathBuf>,
    /// Only render the reference (to OUT_DIR/reference.exr) and stop.
    #[arg(long)]
    reference_only: bool,
}

#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
enum BenchWhat {
    /// Frames, camera samples and rays per second.
    Throughput,
    /// relMSE, MAPE and RMSE against time per strategy.
    Convergence,
    /// Both.
    All,
}

#[derive(Args)]
struct AccuracyArgs {
    /// Which renderers the scene cases run on.
    #[arg(long, value_enum, default_value_t = SuiteBackends::Both)]
    backend: SuiteBackends,
    /// The full counts (1e6 hit points, 1e7 rays, 2^25 spp) instead of CI's.
    #[arg(long)]
    full: bool,
    /// Also write the report as markdown to this file.
    #[arg(long)]
    report: Option<PathBuf>,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum SuiteBackends {
    /// CPU and GPU.
    Both,
    /// CPU only.
    Cpu,
    /// GPU only.
    Gpu,
}

#[derive(Args)]
struct CompareArgs {
    /// The image to judge (EXR, linear radiance).
    image: PathBuf,
    /// The reference (EXR, linear radiance), of the same size.
    #[arg(long)]
    reference: PathBuf,
    /// Side of the square regions whose means are compared, in pixels.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    block: u32,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum BackendArg {
    /// The GPU when a Vulkan adapter is present, else the CPU (with a notice).
    Auto,
    /// The rust-gpu kernel on the best Vulkan adapter (a real GPU, else lavapipe).
    Gpu,
    /// The same code on all CPU cores.
    Cpu,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum TonemapArg {
    /// ACES filmic curve (Narkowicz fit).
    Aces,
    /// Clamp to [0, 1].
    Clamp,
}

#[derive(Args, Clone)]
struct RenderArgs {
    /// Scene file (TOML); the built-in default scene when absent.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Image width in pixels [default: the scene's, else 512].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's, else 512].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Samples per pixel [default: the scene's, else 256].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Maximum scattering events per path; 1 is direct light only [default: the scene's, else 5].
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1_000_000))]
    max_bounces: Option<u32>,
    /// Random seed: renders with different seeds are independent.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Which renderer traces the paths.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// Output file: .png (exposure, tone map, sRGB) or .exr (linear mean radiance).
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    /// Samples per pixel per frame (one GPU dispatch each); 64 was fastest
    /// to a given error in `pathtracer bench` (docs/PERFORMANCE.md).
    #[arg(long, default_value_t = bench::DEFAULT_SPP_PER_FRAME, value_parser = clap::value_parser!(u32).range(1..))]
    spp_per_frame: u32,
    /// Exposure in stops, PNG only.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Tone mapper, PNG only.
    #[arg(long, value_enum, default_value_t = TonemapArg::Aces)]
    tonemap: TonemapArg,
    /// Where the random numbers come from.
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    sampler: SamplerArg,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum SamplerArg {
    /// Owen-scrambled Sobol points (Burley 2020), padded per dimension pair,
    /// for the first 5 draws of a path; a PCG stream for later draws.
    Sobol,
    /// Independent PCG streams.
    Independent,
}

impl Default for RenderArgs {
    /// The arguments of a bare `pathtracer render`.
    fn default() -> Self {
        match Cli::parse_from(["pathtracer", "render"]).command {
            Some(Command::Render(args)) => args,
            _ => unreachable!("`pathtracer render` parses as the render command"),
        }
    }
}

fn main() {
    quiet_vulkan_device_select();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::View(args)) => view(&args),
        Some(Command::Render(args)) => render(&args),
        Some(Command::Compare(args)) => compare(&args),
        Some(Command::Accuracy(args)) => accuracy(&args),
        Some(Command::Bench(args)) => bench_command(&args),
        None if viewer::display_available() => view(&ViewArgs { width: 1024, height: 768, ..Default::default() }),
        None => {
            eprintln!("no display available: rendering the default scene headless to render.png instead");
            render(&RenderArgs::default())
        }
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

/// Mesa's Vulkan device-select layer asks the Wayland compositor which GPU
/// is the default one, and libwayland prints "error: XDG_RUNTIME_DIR is
/// invalid or not set in the environment." at every Vulkan instance when
/// there is no session to ask: a headless machine, a container, CI. There
/// the layer has nothing to choose by (a desktop session always sets
/// `XDG_RUNTIME_DIR`), so it is switched off through its own variable,
/// `NODEVICE_SELECT`, which the Vulkan loader reads; wgpu still picks the
/// adapter by power preference. A user's own setting of either variable
/// wins.
fn quiet_vulkan_device_select() {
    let unset = |name| std::env::var_os(name).is_none();
    if unset("XDG_RUNTIME_DIR") && unset("WAYLAND_DISPLAY") && unset("NODEVICE_SELECT") {
        // SAFETY: the first statement of `main`, before any other thread
        // exists that could read the environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

fn view(args: &ViewArgs) -> Result<()> {
    if let Some(shot) = &args.screenshot {
        output::check_writable(shot)?;
    }
    let scene = load_scene(args.scene.as_ref())?;
    viewer::run(viewer::ViewArgs {
        scene,
        scene_path: args.scene.clone(),
        width: args.width,
        height: args.height,
        target_spp: args.spp,
        max_bounces: args.max_bounces,
        frames: args.frames,
        screenshot: args.screenshot.clone(),
    })
}

fn load_scene(path: Option<&PathBuf>) -> Result<Scene> {
    Ok(match path {
        Some(p) => Scene::load(p)?,
        None => Scene::default_scene(),
    })
}

fn render(args: &RenderArgs) -> Result<()> {
    if !args.exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    // Everything the user gave is checked before any work starts, and the
    // output's folder must take a file: a bad argument never costs a render.
    let format = output::check_writable(&args.out)?;
    let scene = load_scene(args.scene.as_ref())?;
    let settings = RenderSettings {
        width: args.width.unwrap_or(scene.render.width),
        height: args.height.unwrap_or(scene.render.height),
        spp: args.spp.unwrap_or(scene.render.spp),
        max_bounces: args.max_bounces.unwrap_or(scene.render.max_bounces),
        rr_start: scene.render.rr_start,
    };
    let tonemap = match args.tonemap {
        TonemapArg::Aces => TONEMAP_ACES,
        TonemapArg::Clamp => TONEMAP_CLAMP,
    };
    let mut params = scene.frame_params(&settings, args.spp_per_frame, args.seed);
    match args.sampler {
        SamplerArg::Sobol => params.flags |= pt_core::params::FLAG_SOBOL,
        SamplerArg::Independent => params.flags &= !pt_core::params::FLAG_SOBOL,
    }
    let (walls, spheres) = (scene.gpu_walls(), scene.gpu_spheres());
    let mut renderer = match args.backend {
        BackendArg::Gpu => {
            Renderer::new(Backend::Gpu, params, &walls, &spheres).context("cannot start the GPU renderer")?
        }
        BackendArg::Cpu => Renderer::new(Backend::Cpu, params, &walls, &spheres)?,
        BackendArg::Auto => Renderer::new(Backend::Gpu, params, &walls, &spheres).or_else(|e| {
            eprintln!("GPU unavailable ({e}); rendering on the CPU");
            Renderer::new(Backend::Cpu, params, &walls, &spheres)
        })?,
    };
    eprintln!("{}", renderer.description());
    eprintln!(
        "rendering {}x{}, {} spp, max {} bounces, seed {}",
        settings.width, settings.height, settings.spp, settings.max_bounces, args.seed
    );

    let bar = spp_progress_bar(settings.spp);
    bar.enable_steady_tick(Duration::from_millis(200));
    let (accum, stats) =
        render_progressive(&mut renderer, settings.spp, args.spp_per_frame, |done| bar.set_position(done as u64))
            .context("rendering failed")?;
    bar.finish_and_clear();

    match format {
        OutputFormat::Png => {
            let rgba = renderer.display(args.exposure, tonemap).context("display pass failed")?;
            output::write_png(&args.out, settings.width, settings.height, &rgba)?;
        }
        OutputFormat::Exr => {
            output::write_exr(&args.out, settings.width, settings.height, &output::mean_radiance(&accum))?
        }
    }
    println!("adapter: {}", renderer.description());
    println!("time: {:.3} s", stats.elapsed.as_secs_f64());
    println!("samples per second: {:.3e}", stats.samples_per_second());
    println!("non-finite samples: {}", stats.non_finite);
    println!("wrote {}", args.out.display());
    Ok(())
}

fn compare(args: &CompareArgs) -> Result<()> {
    let read = |p: &PathBuf| output::read_exr(p).with_context(|| format!("{}: cannot read the EXR", p.display()));
    let (w, h, image) = read(&args.image)?;
    let (rw, rh, reference) = read(&args.reference)?;
    if (w, h) != (rw, rh) {
        anyhow::bail!(
            "{} is {w}x{h} but the reference {} is {rw}x{rh}",
            args.image.display(),
            args.reference.display()
        );
    }
    println!("MSE     {:.6e}", metrics::mse(&image, &reference));
    println!("RMSE    {:.6e}", metrics::rmse(&image, &reference));
    println!("relMSE  {:.6e}", metrics::rel_mse(&image, &reference));
    println!("MAPE    {:.6e}", metrics::mape(&image, &reference));
    // Region means: bias shows as a region that differs beyond the noise.
    let a = metrics::region_means(&image, w, h, args.block);
    let b = metrics::region_means(&reference, w, h, args.block);
    let mut worst = (0.0f64, 0usize, 0usize);
    let mut sum_rel = 0.0;
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        for c in 0..3 {
            let rel = (x[c] - y[c]) / (y[c].abs() + 0.01);
            sum_rel += rel;
            if rel.abs() > worst.0.abs() {
                worst = (rel, i, c);
            }
        }
    }
    let regions_x = w.div_ceil(args.block) as usize;
    println!(
        "regions of {0}x{0}: mean relative difference {1:+.4e}, largest {2:+.4e} (region x {3}, y {4}, channel {5})",
        args.block,
        sum_rel / (3 * a.len()) as f64,
        worst.0,
        worst.1 % regions_x,
        worst.1 / regions_x,
        ["r", "g", "b"][worst.2]
    );
    Ok(())
}

fn accuracy(args: &AccuracyArgs) -> Result<()> {
    use pt_render::accuracy::{self, Size, Target};
    let size = if args.full { Size::Full } else { Size::Quick };
    let ctx = match args.backend {
        SuiteBackends::Cpu => None,
        _ => Some(pt_render::GpuContext::new().context("the GPU cases need a Vulkan adapter")?),
    };
    let mut targets = Vec::new();
    if !matches!(args.backend, SuiteBackends::Gpu) {
        targets.push(Target::Cpu);
    }
    if let Some(c) = &ctx {
        targets.push(Target::Gpu(c));
    }
    let start = std::time::Instant::now();
    let results = accuracy::run(&targets, size)?;
    let elapsed = start.elapsed().as_secs_f64();
    let table = accuracy::markdown_table(&results);
    println!("{table}");
    let failed = results.iter().filter(|r| !r.pass).count();
    println!("{} cases, {failed} failed, {elapsed:.1} s", results.len());
    if let Some(path) = &args.report {
        let machine = machine_description();
        let adapter = ctx.as_ref().map_or("none (CPU only)".to_string(), |c| c.adapter_description());
        let cmd = format!(
            "pathtracer accuracy{}{} --report {}",
            if args.full { " --full" } else { "" },
            match args.backend {
                SuiteBackends::Both => "",
                SuiteBackends::Cpu => " --backend cpu",
                SuiteBackends::Gpu => " --backend gpu",
            },
            path.display()
        );
        let text = format!(
            "# Accuracy report\n\nGenerated by `{cmd}` ({} cases, {failed} failed, {elapsed:.1} s).\n\n\
             - Machine: {machine}\n- GPU adapter: {adapter}\n- CPU backend: {} rayon threads\n\n\
             {}\n\n## Cases\n\n{table}",
            results.len(),
            rayon_threads(),
            ACCURACY_METHOD,
        );
        std::fs::write(path, text).with_context(|| format!("{}: cannot write the report", path.display()))?;
        println!("wrote {}", path.display());
    }
    if failed > 0 {
        anyhow::bail!("{failed} accuracy cases failed");
    }
    Ok(())
}

const ACCURACY_METHOD: &str = "## Method\n\n\
Monte Carlo cases render 16 independent images (distinct seeds). The spread of their \
means gives the standard error, and a case passes when |measured - expected| is within \
5.5 standard errors (t with 15 degrees of freedom: probability 1e-4 each, under 1% over a \
run). Image comparisons (equal expectations, metamorphic) take the largest per-region |z| \
over 8x8-pixel regions and channels of two sets of 16 seeds and accept up to 6 (family-wise \
about 1%). Geometric checks count failures and accept none. Sampling tests are binned \
chi-square tests (as Mitsuba 3's chi2.py: cells under 5 expected samples pooled), \
Sidak-corrected to 1% over the five tests: cosine sampling over 20 x 40 equal-area cells of \
the sphere with expected counts integrated from the pdf; light-cone sampling over 20 x 40 \
equal-area cells of the cap in its own frame (exact expected counts; a sample outside the \
cap fails the case). Expected values: \
spherical room rho L s^2 / (1 - rho (1 - s^2)) (and its N-bounce partial sum); albedo times \
background for a sphere under a uniform sky; the sphere-light irradiance of Snyder (1996) \
with horizon clipping (checked against quadrature in a unit test); 1 - (R/D)^3 for a floor \
point next to a black sphere resting on it under a uniform sky.\n\n\
Every rendered case also counts non-finite samples; a single one fails the case.\n\n\
## What the suite found\n\n\
- The GPU's compensated (Kahan) accumulation was silently a plain sum on lavapipe: the \
driver's compiler reassociates SPIR-V float arithmetic (no NoContraction decoration) and \
folds `(t - sum) - y` to zero. After 2^24 samples the mean was off by 4.6e-5. The sum now \
passes `t` through a select on a uniform the compiler cannot know (`kahan_add`), and the \
error is below 1e-6 on both backends.\n\
- The per-frame sum of a pixel's samples was a plain f32 sum: 65536 samples of 0.1 in one \
frame drifted by 6e-4. It is compensated too.";

fn rayon_threads() -> usize {
    rayon::current_num_threads()
}

/// "model name, N cores" of this machine (from /proc/cpuinfo where present).
fn machine_description() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    format!("{cpu}, {} logical cores, {}", rayon_threads(), std::env::consts::OS)
}

fn bench_command(args: &BenchArgs) -> Result<()> {
    let ctx = match args.backend {
        SuiteBackends::Cpu => None,
        _ => Some(pt_render::GpuContext::new().context("the GPU benchmark needs a Vulkan adapter")?),
    };
    let gpu = ctx.as_ref();
    let cpu_too = !matches!(args.backend, SuiteBackends::Gpu);
    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("{}: cannot create", args.out_dir.display()))?;
    let mut report = String::new();
    let default_scene = Scene::default_scene();

    if args.what != BenchWhat::Convergence {
        eprintln!("throughput: {} configurations x {} repetitions", bench::THROUGHPUT_CONFIGS.len(), args.reps);
        let mut rows = bench::throughput(gpu, args.reps as usize, &default_scene)?;
        if !cpu_too {
            rows.retain(|r| !r.backend.starts_with("CPU"));
        }
        let table = bench::throughput_markdown(&rows);
        println!("{table}");
        report.push_str(&format!(
            "## Throughput\n\nDefault scene; warm-up frames for half a second (at least one), then {} timed frames per \
             configuration; median and \
             range of frames per second. Rays per sample (closest-hit plus shadow rays) are counted by the CPU's \
             instrumented trace of the same code over every 4th pixel in x and y, and multiply the samples per \
             second of both backends. The original OpenGL design reached 120 frames/s at 1920x1080, 4 spp/frame, \
             5 bounces on an RTX 3050: about 1.0e9 camera samples/s.\n\n{table}\n",
            args.reps
        ));
    }

    if args.what != BenchWhat::Throughput {
        let scene = load_scene(args.scene.as_ref())?;
        let settings = RenderSettings { width: args.width, height: args.height, spp: args.max_spp, ..scene.render };
        let ref_spp = args.max_spp.saturating_mul(100);
        let reference = match &args.reference {
            Some(p) => bench::load_reference(p, &settings)?,
            None => {
                eprintln!(
                    "rendering the reference: {ref_spp} spp at {}x{} on the CPU (100x the largest budget)",
                    args.width, args.height
                );
                let bar = spp_progress_bar(ref_spp);
                let r = bench::reference(&scene, &settings, ref_spp, |done| bar.set_position(done as u64))?;
                bar.finish_and_clear();
                output::write_exr(&args.out_dir.join("reference.exr"), args.width, args.height, &r)?;
                r
            }
        };
        if args.reference_only {
            println!("wrote {}", args.out_dir.join("reference.exr").display());
            return Ok(());
        }
        let mut points = bench::convergence(gpu, &scene, &settings, args.max_spp, args.seeds, &reference, |s| {
            eprintln!("convergence: {s}")
        })?;
        if !cpu_too {
            points.retain(|p| !p.backend.starts_with("CPU"));
        }
        let csv = args.out_dir.join("convergence.csv");
        bench::write_csv(&csv, &points)?;
        let mut extra = Vec::new();
        if let Some(m) = &args.mitsuba_csv {
            extra.push(("Mitsuba 3 llvm_ad_rgb, path".to_string(), bench::read_curve(m)?));
        }
        let png = args.out_dir.join("convergence.png");
        bench::plot(&png, &points, &extra)?;
        let pixels = args.width as u64 * args.height as u64;
        let table = bench::convergence_markdown(&points, 1e-3, args.max_spp, pixels);
        println!("{table}");
        let reference_note = match &args.reference {
            Some(p) => format!("the reference `{}`", p.display()),
            None => format!(
                "a reference of {ref_spp} spp rendered on the CPU (100x the largest budget, {} spp)",
                args.max_spp
            ),
        };
        report.push_str(&format!(
            "## Error against time\n\nScene: {}; {}x{} pixels, {} bounces; {} seeds per strategy; errors against {}. \
             Each strategy renders progressively to {} spp; errors are measured at 4, 8, 16, ... spp (no frame \
             spans a measurement), with time counted around synchronised frames only (readback and evaluation excluded). An untimed warm-up \
             render comes first, then every strategy once per seed in turn; each point takes the median time \
             and the mean relMSE of the seeds (the machine is shared: a single run can be slowed by half). \
             Equal time is the \
             shortest total time of any strategy; times to relMSE 1e-3 are interpolated log-log between \
             measurements.\n\n![relMSE against time]({})\n\nAll points: `{}`.\n{table}\n",
            args.scene.as_ref().map_or("the built-in default scene".to_string(), |p| p.display().to_string()),
            args.width,
            args.height,
            settings.max_bounces,
            args.seeds,
            reference_note,
            args.max_spp,
            relative_to_report(&png, args.report.as_deref()),
            relative_to_report(&csv, args.report.as_deref()),
        ));
        if let Some(m) = &args.mitsuba_csv {
            report.push_str(&mitsuba_section(m, &points)?);
        }
        report.push_str(&defaults_section(&points));
        report.push_str(&gpu_machine_section(args.report.as_deref()));
    }

    if let Some(path) = &args.report {
        let adapter = ctx.as_ref().map_or("none".to_string(), |c| c.adapter_description());
        let mut cmd = std::env::args().collect::<Vec<_>>();
        cmd[0] = "pathtracer".into();
        let text = format!(
            "# Performance report\n\nGenerated by `{}`.\n\n- Machine: {}\n- GPU adapter: {adapter}\n- CPU backend: {} rayon threads\n\n{report}",
            cmd.join(" "),
            machine_description(),
            rayon_threads(),
        );
        std::fs::write(path, text).with_context(|| format!("{}: cannot write the report", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

const MITSUBA_FAIRNESS: &str = "## Against Mitsuba 3\n\n\
Made by `scripts/performance_report.sh`: `scripts/mitsuba/compare.py` renders the same scene \
file with Mitsuba 3 (`llvm_ad_rgb`, `path` integrator, `max_depth` = max bounces + 1, \
independent sampler, box pixel filter, the light a black-BSDF sphere with an area emitter, \
walls two-sided diffuse) on the same machine, at the same resolution, against the same \
reference. Mitsuba's kernels are compiled before timing (each sample count is rendered once \
untimed, then timed); each of its points is one render from scratch at that sample count, \
with the median time and mean relMSE of its seeds, as ours. Our points are the progressive renders above (default strategy). Times to \
relMSE 1e-3 are interpolated log-log.\n\n";

/// The defaults and the measurements behind each: how much longer (or
/// shorter) each alternative took to relMSE 1e-3 than the default, per
/// backend, from `points`.
fn defaults_section(points: &[bench::Point]) -> String {
    let mut backends: Vec<String> = points.iter().map(|p| p.backend.clone()).collect();
    backends.dedup();
    let time = |backend: &str, strategy: &str| {
        bench::time_to(&bench::time_error(&bench::mean_curve(points, backend, strategy)), 1e-3)
    };
    // "GPU ... 2.05x, CPU ... 1.91x": time of `a` over time of `b`.
    let ratio = |a: &str, b: &str| {
        backends
            .iter()
            .map(|backend| {
                let label = backend.split(':').next().unwrap_or(backend);
                match (time(backend, a), time(backend, b)) {
                    (Some(x), Some(y)) => format!("{label} {:.2}x", x / y),
                    _ => format!("{label}: not reached within the budget"),
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let default = bench::STRATEGIES[0].name;
    let vs_default = |i: usize| ratio(bench::STRATEGIES[i].name, default);
    // "GPU: none; CPU: none": the alternatives faster in every seed.
    let verdict = backends
        .iter()
        .filter_map(|backend| {
            let label = backend.split(':').next().unwrap_or(backend);
            let (n, faster) = bench::faster_than_default(points, backend, 1e-3)?;
            let names: Vec<&str> = faster.iter().map(|f| f.name).collect();
            Some(format!(
                "{label} ({n} seeds): {}",
                if names.is_empty() { "none".to_string() } else { names.join(", ") }
            ))
        })
        .collect::<Vec<_>>()
        .join("; ");
    format!(
        "\n## Defaults chosen from these measurements\n\n\
         Each figure is the time an alternative took to reach relMSE 1e-3, as a multiple of the default's \
         time on the same backend (above 1: the default is faster). Alternatives that do the same work as \
         the default and make nearly the same image (MIS here, other samples per frame on the CPU) come within \
         the machine's noise of it, and the lowest median can be either; the test that separates a real \
         difference from noise is run for run: alternatives faster than the default in every seed, {verdict}.\n\n\
         - Samples: Owen-scrambled Sobol (Burley 2020) for the first 5 draws of a path (pixel, then light \
         and BSDF samples of two vertices), an independent PCG stream for later ones. Independent PCG \
         samples throughout: {}; Sobol for every draw: {}. Deep in a path each Sobol pair is stratified alone, \
         not jointly with the earlier ones, and gains little, while a Sobol draw costs four times the integer \
         multiplies of a PCG draw (`SOBOL_DRAWS` in pt-core gives the choice of 5).\n\
         - Russian roulette from bounce 5, i.e. none within the default 5 bounces. From bounce 3: {}; from \
         bounce 1: {}. Its random cut-offs undo part of Sobol's stratification; it stays for deeper bounce \
         limits, where it bounds path length.\n\
         - Survival rule: the throughput's largest component, clamped to [0.05, 1]. Following luminance \
         instead, both from bounce 3, took {} the time of the largest-component rule (after the red and green \
         walls luminance ends more paths: shorter paths, more colour noise there).\n\
         - 64 samples per pixel per frame for `render`. 16 per frame: {}; 4 per frame: {}. An invocation \
         traces its pixel's samples of the frame one after another, and a SIMD group (8 lanes on lavapipe, 32 \
         on NVIDIA) runs until its busiest lane is done: the more samples per frame, the smaller the spread of \
         the lanes' summed path lengths against their mean, and the fewer dispatches (each with a fixed cost). \
         Since no frame spans a measurement, every count from 64 up renders the same frames to 128 spp here; \
         the throughput table compares 16 and 64 at 1920x1080. The viewer adapts its count to a frame \
         budget.\n\
         - NEE without MIS: after a bounce, light is gathered by shadow rays only, and a BSDF ray that \
         hits the light adds nothing. NEE with MIS: {}; BSDF sampling alone: {}. The light is small here \
         (sin a = 0.09 from the floor): the cosine lobe rarely finds it and the glow lobe leaves its cone to \
         NEE, so MIS gives NEE nearly all the weight and both make the same image (the relMSE at 512 spp \
         above agrees to 3 digits). MIS then only adds work, a BSDF density and a weight per shadow ray, \
         and the two are a near tie that the cheaper one should win. MIS stays available (`FLAG_MIS`, the \
         viewer's checkbox) for large or near lights, whose cone reaches below a surface's horizon: cone \
         samples there are lost and BSDF samples find the visible part. At the last vertex no BSDF ray is \
         traced either way.\n\
         - BSDF sampling: the cosine lobe mixed with the glow lobe around the light (probability 0.25, reach \
         0.125 in 1 - cos past the light's cone, density 1 / (1 - cos); `GLOW_PROBABILITY` and `GLOW_REACH` \
         in pt-core). Cosine lobe \
         alone: {}. Nearly all of the remaining error is indirect light, and much of it comes from the bright ceiling \
         right above the light, which the cosine lobe finds rarely. The glow lobe's density falls as the \
         inverse square of the distance from the light, as the irradiance of surfaces around it does. (Not \
         measured by this bench: on the CPU at 256x256 and 64 spp, direct light alone, `render --max-bounces 1`, \
         has relMSE 3.5e-5 against an 8192-spp render of its own, and all 5 bounces 1.6e-3 against the \
         reference above; `pathtracer compare` gives both.)\n\
         - Trace kernel: the small-scene kernel on CPU adapters (lavapipe), for scenes it holds (at most 8 \
         walls and 4 spheres, and no wall that can block a shadow ray: the default scene is one); the general \
         kernel on GPUs and for other scenes. Both make the same image, bit for bit on lavapipe. The throughput \
         table times both at 1920x1080, 64 spp/frame: lavapipe reads every uniform value of the general kernel \
         as a gather, lane by lane, and runs loop bodies that have nothing to do (docs/ARCHITECTURE.md). GPUs \
         keep the general kernel, with which the H100 figures were measured, until a run there shows the other \
         ahead.\n\
         - Workgroup shape: 8x8 stays the default. The throughput table times 8x8, 16x4, 32x2 and 4x4 of the \
         general kernel (the only one that comes in every shape) on the \
         512x512 configuration; on lavapipe the shape only changes how invocations are batched into its \
         8-wide SIMD (4 wide rows leave half of each vector empty). On an H100 (PERFORMANCE-H100.md) 8x8, \
         16x4 and 32x2 are within 1% of each other and 4x4 runs at about half their speed: a 16-invocation \
         workgroup fills half of a 32-wide warp.\n",
        vs_default(1),
        vs_default(10),
        vs_default(2),
        vs_default(4),
        ratio(bench::STRATEGIES[3].name, bench::STRATEGIES[2].name),
        vs_default(8),
        vs_default(9),
        vs_default(5),
        vs_default(6),
        vs_default(7),
    )
}

/// The report made on a lent GPU machine, kept beside the main one.
const GPU_MACHINE_REPORT: &str = "PERFORMANCE-H100.md";

/// Where the figures of a data-centre GPU are: the report of that name
/// beside `report` when there is one (this machine has no such GPU).
fn gpu_machine_section(report: Option<&Path>) -> String {
    let command = format!(
        "`pathtracer bench throughput --backend gpu --reps 10 --report docs/{GPU_MACHINE_REPORT}` (the kernel \
         is embedded in the release binary: copy it there with the Vulkan loader)"
    );
    let beside = report.and_then(Path::parent).map(|d| d.join(GPU_MACHINE_REPORT));
    if beside.is_some_and(|p| p.exists()) {
        format!(
            "\n## NVIDIA H100 / H200\n\nMeasured on a lent machine: [{GPU_MACHINE_REPORT}]({GPU_MACHINE_REPORT}), \
             made there by {command}. It names the GPU and its driver; its figures are those of the kernel as of the \
             commit that last changed it (`git log -1 docs/{GPU_MACHINE_REPORT}`). Rerun it there after a change \
             to the kernel.\n"
        )
    } else {
        format!(
            "\n## NVIDIA H100 / H200\n\nNot measured: no such GPU was at hand. To measure, run {command} on a \
             machine that has one, and keep the report beside this one.\n"
        )
    }
}

/// A progress bar over `spp` samples per pixel, with elapsed time and ETA.
fn spp_progress_bar(spp: u32) -> ProgressBar {
    let bar = ProgressBar::new(spp as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed_precise} (eta {eta})")
            .expect("valid progress template"),
    );
    bar
}

/// The Mitsuba comparison: time to relMSE 1e-3, ours against Mitsuba's.
fn mitsuba_section(csv: &PathBuf, points: &[bench::Point]) -> Result<String> {
    let m = bench::read_curve(csv)?;
    let tm = bench::time_to(&m, 1e-3);
    let mut s =
        String::from(MITSUBA_FAIRNESS) + "| renderer | time to relMSE 1e-3 | ratio to Mitsuba |\n|---|---|---|\n";
    s.push_str(&format!(
        "| Mitsuba 3 llvm_ad_rgb, path (`{}`) | {} | 1 |\n",
        csv.display(),
        tm.map_or("not reached".into(), |t| format!("{t:.3} s"))
    ));
    let mut backends: Vec<String> = points.iter().map(|p| p.backend.clone()).collect();
    backends.dedup();
    for b in backends {
        let t = bench::time_to(&bench::time_error(&bench::mean_curve(points, &b, bench::STRATEGIES[0].name)), 1e-3);
        s.push_str(&format!(
            "| pathtracer {b}, default strategy | {} | {} |\n",
            t.map_or("not reached".into(), |t| format!("{t:.3} s")),
            match (t, tm) {
                (Some(a), Some(b)) => format!("{:.2}", a / b),
                _ => "-".into(),
            }
        ));
    }
    Ok(s)
}

/// `path` as seen from the folder of the report (for links in markdown).
fn relative_to_report(path: &std::path::Path, report: Option<&std::path::Path>) -> String {
    let dir = report.and_then(|r| r.parent()).filter(|d| !d.as_os_str().is_empty());
    match dir.and_then(|d| path.strip_prefix(d).ok()) {
        Some(rel) => rel.display().to_string(),
        None => path.display().to_string(),
    }
}
