//! `pathtracer`: a progressive, physically based GPU path tracer.

mod bench;
mod commands;
mod viewer;

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

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
    /// Join the parts of a split render (`render --parts`) into its image.
    Merge(MergeArgs),
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
    /// Only render the reference (to OUT_DIR/reference.exr) and stop; with
    /// --suite, every scene's cached reference and OUT_DIR/suite.tsv.
    #[arg(long)]
    reference_only: bool,
    /// Convergence on every scene of --suite-dir: each strategy's time to
    /// relMSE 1e-3 and the default's gap to the fastest.
    #[arg(long)]
    suite: bool,
    /// The suite's scenes (every *.toml, each with a `# stresses:` line).
    #[arg(long, default_value = "scenes", requires = "suite")]
    suite_dir: PathBuf,
    /// Samples per pixel of each suite reference (cached under
    /// OUT_DIR/references by a hash of the scene and settings).
    #[arg(long, default_value_t = 16384, requires = "suite", value_parser = clap::value_parser!(u32).range(2..))]
    reference_spp: u32,
    /// Folder of `<scene>.csv` files from `compare.py --suite` to include.
    #[arg(long, requires = "suite")]
    mitsuba_dir: Option<PathBuf>,
    /// Measure nothing: rebuild the suite's tables, plot and report from
    /// the points of an earlier run (OUT_DIR/suite.csv; its seeds, not
    /// --seeds).
    #[arg(long, requires = "suite", conflicts_with = "reference_only")]
    from_csv: bool,
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
    /// Fail when a region's paired t statistic (mean pixel difference over
    /// its standard error) exceeds this: a test that both images estimate
    /// the same image from independent samples, e.g. 5.
    #[arg(long)]
    max_t: Option<f64>,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum BackendArg {
    /// The GPU when a hardware Vulkan adapter is present; else the CPU (with
    /// a notice), which also outruns a software adapter where it has AVX2.
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

impl TonemapArg {
    /// The kernel's `TONEMAP_*` value.
    fn code(self) -> u32 {
        match self {
            TonemapArg::Aces => pt_core::params::TONEMAP_ACES,
            TonemapArg::Clamp => pt_core::params::TONEMAP_CLAMP,
        }
    }
}

#[derive(Args)]
struct MergeArgs {
    /// The .ptpart files, in any order.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Output file: .png (exposure, tone map, sRGB) or .exr (linear mean radiance).
    #[arg(long)]
    out: PathBuf,
    /// Exposure in stops, PNG only.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Tone mapper, PNG only.
    #[arg(long, value_enum, default_value_t = TonemapArg::Aces)]
    tonemap: TonemapArg,
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
    /// Cut the render into this many parts by sample range and render one
    /// of them to a .ptpart file (`{part}` in --out becomes its index);
    /// `pathtracer merge` joins the parts.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    parts: Option<u32>,
    /// Which part to render, from 0 [default: JOB_COMPLETION_INDEX, else
    /// SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN].
    #[arg(long)]
    part: Option<u32>,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum SamplerArg {
    /// Sobol points, padded per dimension pair (the index Owen-scrambled,
    /// the values digitally shifted), for the first 5 draws of a path; a PCG
    /// stream for later draws.
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
    exit_quietly_on_closed_pipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::View(args)) => commands::view::run(&args),
        Some(Command::Render(args)) => commands::render::run(&args),
        Some(Command::Compare(args)) => commands::compare::run(&args),
        Some(Command::Merge(args)) => commands::merge::run(&args),
        Some(Command::Accuracy(args)) => commands::accuracy::run(&args),
        Some(Command::Bench(args)) => commands::bench::run(&args),
        None if viewer::display_available() => {
            commands::view::run(&ViewArgs { width: 1024, height: 768, ..Default::default() })
        }
        None => {
            eprintln!("no display available: rendering the default scene headless to render.png instead");
            commands::render::run(&RenderArgs::default())
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
/// `pathtracer compare ... | head` closes stdout early. Rust ignores
/// SIGPIPE, so the next `println!` would panic; a command-line tool should
/// stop quietly instead, as it does with the signal's default action.
fn exit_quietly_on_closed_pipe() {
    #[cfg(unix)]
    {
        unsafe extern "C" {
            fn signal(signum: i32, handler: usize) -> usize;
        }
        const SIGPIPE: i32 = 13;
        const SIG_DFL: usize = 0;
        // SAFETY: restores the default action of one signal, before any
        // other thread exists; `signal` is async-signal-safe to call here.
        unsafe { signal(SIGPIPE, SIG_DFL) };
    }
}

fn quiet_vulkan_device_select() {
    let unset = |name| std::env::var_os(name).is_none();
    if unset("XDG_RUNTIME_DIR") && unset("WAYLAND_DISPLAY") && unset("NODEVICE_SELECT") {
        // SAFETY: the first statement of `main`, before any other thread
        // exists that could read the environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}
