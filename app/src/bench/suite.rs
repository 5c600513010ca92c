//! `pathtracer bench convergence --suite`: every scene of a folder, each
//! strategy's time to a target relMSE on each backend, the default's gap to
//! the fastest, and Mitsuba 3's samplers beside them.
//!
//! References are rendered once per scene and kept under the output folder,
//! named by a hash of what makes them (the scene as the program reads it,
//! the image size, the bounce limit and the sample count): a rerun, or a
//! Mitsuba run between two bench runs, reads the same file.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use pt_render::gpu::GpuContext;
use pt_render::{CpuRenderer, Device, RenderSettings, Scene, metrics, output};

use super::convergence::{Point, Until, curve, means, seeds as seeds_of, time_to, times_by_seed, warm_up};
use super::{BackendKind, BenchBackend, STRATEGIES, StrategyId, median_min_max};

/// One scene of the suite.
pub struct SuiteScene {
    /// The file's stem, e.g. `light-large`.
    pub name: String,
    /// The file.
    pub path: PathBuf,
    /// What the scene stresses: the text after `# stresses:` in its file.
    pub stresses: String,
    /// The scene.
    pub scene: Scene,
}

/// Marks the line of a suite scene that says what it stresses.
const STRESSES: &str = "# stresses:";

/// What a scene without a `# stresses:` line is said to stress in the
/// tables: its light and spheres, so that a folder of new scenes runs as
/// it is.
fn what_it_holds(scene: &Scene) -> String {
    let (c, r) = (scene.light.center, scene.light.radius);
    let spheres = match scene.spheres.len() {
        1 => "1 sphere".to_string(),
        n => format!("{n} spheres"),
    };
    format!(
        "(no `{STRESSES}` line) a light of radius {r} at ({}, {}, {}), {spheres}, {} walls.",
        c.x,
        c.y,
        c.z,
        scene.walls.len()
    )
}

/// The scenes of `dir` (every `*.toml`, by name), each with its
/// `# stresses:` line, or where it has none, a line naming its light and
/// spheres ([`what_it_holds`]).
pub fn load_suite(dir: &Path) -> Result<Vec<SuiteScene>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read the suite folder", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        bail!("{}: no scene files (*.toml) in the suite folder", dir.display());
    }
    paths
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).with_context(|| format!("{}: cannot read", path.display()))?;
            let scene = Scene::from_toml(&text, &path)?;
            let stresses = match text.lines().find_map(|l| l.strip_prefix(STRESSES)) {
                Some(line) => line.trim().to_string(),
                None => what_it_holds(&scene),
            };
            let name = path.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            Ok(SuiteScene { name, path, stresses, scene })
        })
        .collect()
}

/// 64-bit FNV-1a: a stable hash (std's `DefaultHasher` may change between
/// Rust releases, which would orphan every cached reference).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// The hash that names a reference: the scene as read (comments and
/// spacing do not count), the settings that change its pixels and the
/// sample count.
pub fn reference_hash(scene: &Scene, settings: &RenderSettings, spp: u32) -> u64 {
    let key = format!(
        "{}\nwidth {} height {} max_bounces {} spp {spp} seed {REFERENCE_SEED}",
        scene.to_toml(),
        settings.width,
        settings.height,
        settings.max_bounces
    );
    fnv1a(key.as_bytes())
}

/// Seed of the references: distinct from every bench and test seed.
const REFERENCE_SEED: u32 = 0x5eed_0002;

/// A reference and its own error.
pub struct Reference {
    /// Mean radiance per pixel.
    pub pixels: Vec<[f32; 3]>,
    /// Its file.
    pub path: PathBuf,
    /// Its own relMSE, estimated from its two independent halves A and B:
    /// E[relMSE(A, B)] = 2 var(half) and var(mean) = var(half) / 2, so a
    /// quarter of relMSE(A, B). It adds to every relMSE measured against it.
    pub rel_mse: f64,
    /// Whether it was read from the cache.
    pub cached: bool,
}

/// The reference of `scene` in `dir`: read when cached, else rendered on
/// the CPU as two independent halves of `spp / 2` samples per pixel and
/// written (the mean as `<name>-<hash>.exr`, its own relMSE beside it).
pub fn cached_reference(
    dir: &Path,
    s: &SuiteScene,
    settings: &RenderSettings,
    spp: u32,
    mut progress: impl FnMut(u32),
) -> Result<Reference> {
    let stem = format!("{}-{:016x}", s.name, reference_hash(&s.scene, settings, spp));
    let path = dir.join(format!("{stem}.exr"));
    let noise_path = dir.join(format!("{stem}.relmse"));
    if path.exists() && noise_path.exists() {
        let pixels = super::load_reference(&path, settings)?;
        let text =
            std::fs::read_to_string(&noise_path).with_context(|| format!("{}: cannot read", noise_path.display()))?;
        let rel_mse = text.trim().parse().with_context(|| format!("{}: not a number", noise_path.display()))?;
        return Ok(Reference { pixels, path, rel_mse, cached: true });
    }
    let half = (spp / 2).max(1);
    let mut halves = Vec::new();
    for h in 0..2u32 {
        let params = s.scene.frame_params(settings, 64, REFERENCE_SEED + h);
        let mut r = CpuRenderer::new(params, &s.scene.gpu_walls(), &s.scene.gpu_spheres())?;
        let mut done = 0;
        while done < half {
            let n = 64.min(half - done);
            r.render_frame(n);
            done += n;
            progress(h * half + done);
        }
        halves.push(means(r.accum()));
    }
    let pixels: Vec<[f32; 3]> =
        halves[0].iter().zip(&halves[1]).map(|(a, b)| std::array::from_fn(|c| 0.5 * (a[c] + b[c]))).collect();
    let rel_mse = metrics::rel_mse(&halves[0], &halves[1]) / 4.0;
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    // The number first: a reference without it is rendered again.
    std::fs::write(&noise_path, format!("{rel_mse:e}\n"))
        .with_context(|| format!("{}: cannot write", noise_path.display()))?;
    output::write_exr(&path, settings.width, settings.height, &pixels)?;
    Ok(Reference { pixels, path, rel_mse, cached: false })
}

/// The settings of a suite scene: its own bounce limit and Russian roulette
/// start, the suite's image size.
pub fn suite_settings(s: &SuiteScene, width: u32, height: u32) -> RenderSettings {
    RenderSettings { width, height, ..s.scene.render }
}

/// A curve is cut off once it has taken this many times the default's time
/// to the target in the same seed: the strategy is then far from the
/// fastest, and finishing it would cost more than the rest of the scene.
const CUT_OFF: f64 = 2.0;

/// Seeds from here on belong to the confirmation round; the screening round
/// uses 100, 101, ...
///
/// Why a second round: the screening picks the fastest of a dozen
/// strategies by their medians, and where several are within the timing
/// noise of each other (those that render the very same samples on another
/// schedule, for one), the lowest of a dozen noisy medians is lower than
/// that strategy's true time. The default's gap to it, read from the same
/// runs, is then too large by that luck (the winner's curse). Measured again
/// on fresh seeds, default against the screening's fastest other strategy,
/// the gap has no such bias.
pub const CONFIRM_SEED: u32 = 200;

/// Every strategy on each backend for one scene, `seeds` seeds, each curve
/// stopped once below `target` (or at `max_spp`, or past [`CUT_OFF`] times
/// the default's time of its seed). The reference's own relMSE is taken off
/// every measurement ([`without_reference_noise`]).
#[allow(clippy::too_many_arguments)]
pub fn scene_curves(
    ctx: Option<&GpuContext>,
    cpu: bool,
    scene: &Scene,
    settings: &RenderSettings,
    max_spp: u32,
    seeds: u32,
    target: f64,
    reference: &Reference,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Point>> {
    let noise = reference.rel_mse;
    let reference = &reference.pixels;
    let mut backends: Vec<(Device<'_>, BenchBackend)> = Vec::new();
    if let Some(c) = ctx {
        backends.push((Device::Gpu(c), BenchBackend::gpu(&c.adapter_info.name)));
    }
    if cpu {
        backends.push((Device::Cpu, BenchBackend::cpu()));
    }
    let mut points = Vec::new();
    for (device, name) in &backends {
        let default = StrategyId::Default.strategy();
        let until = Until { target: Some(target + noise), time_limit: f64::INFINITY };
        warm_up(*device, scene, settings, max_spp, reference, name, until)?;
        for seed in 0..seeds {
            progress(&format!("{name}: seed {} of {seeds}", seed + 1));
            let seed = 100 + seed;
            let mut d = curve(*device, scene, settings, default, seed, max_spp, reference, name, until)?;
            without_reference_noise(&mut d, noise);
            let curve_of = |pts: &[Point]| pts.iter().map(|p| (p.time, p.rel_mse)).collect::<Vec<_>>();
            let limit = time_to(&curve_of(&d), target).map_or(f64::INFINITY, |t| CUT_OFF * t);
            points.extend(d);
            for st in STRATEGIES.iter().filter(|st| st.id != StrategyId::Default && !st.same_as_default_on(scene)) {
                let until = Until { target: Some(target + noise), time_limit: limit };
                let mut c = curve(*device, scene, settings, st, seed, max_spp, reference, name, until)?;
                without_reference_noise(&mut c, noise);
                points.extend(c);
            }
        }
        // The confirmation round (see `CONFIRM_SEED`): the default and the
        // screening's fastest other strategy, in turn, on fresh seeds.
        let Some(rival) = scene_result(&points, name, seeds, target).rival else { continue };
        for seed in (0..seeds).map(|k| CONFIRM_SEED + k) {
            progress(&format!(
                "{name}: confirming against {}, seed {} of {seeds}",
                STRATEGIES[rival].name,
                seed - CONFIRM_SEED + 1
            ));
            let unbounded = Until { target: Some(target + noise), time_limit: f64::INFINITY };
            for st in [default, &STRATEGIES[rival]] {
                let mut c = curve(*device, scene, settings, st, seed, max_spp, reference, name, unbounded)?;
                without_reference_noise(&mut c, noise);
                points.extend(c);
            }
        }
    }
    Ok(points)
}

/// Takes the reference's own relMSE `noise` off each measurement. An image
/// and the reference err independently, so the relMSE between them is
/// (nearly: the weights use the reference) the sum of their own; without
/// the correction a noisier reference would slow every curve alike, ours
/// and Mitsuba's, by a different amount per scene.
pub fn without_reference_noise(points: &mut [Point], noise: f64) {
    for p in points {
        p.rel_mse = (p.rel_mse - noise).max(f64::MIN_POSITIVE);
    }
}

/// A time to the target per seed, by seed.
type SeedTimes = Vec<(u32, f64)>;

/// Median of the seeds' times, `None` unless every seed reached the target.
fn median_time(times: &SeedTimes, seeds: usize) -> Option<f64> {
    (times.len() == seeds && seeds > 0).then(|| median_min_max(times.iter().map(|t| t.1).collect()).0)
}

/// One strategy's standing on one scene and backend.
#[derive(Clone, Debug)]
pub struct Standing {
    /// Median time to the target over seeds; `None` when a seed did not
    /// reach it (cut off or out of samples).
    pub median: Option<f64>,
    /// Its seeds' times.
    pub times: SeedTimes,
}

/// What one scene and backend came to.
#[derive(Clone, Debug)]
pub struct SceneResult {
    /// Every strategy, in [`STRATEGIES`] order (the default first), in the
    /// screening round.
    pub standings: Vec<Standing>,
    /// Index of the fastest strategy by median time in the screening round.
    pub best: Option<usize>,
    /// The default's time over the fastest's, seed for seed, in the
    /// screening round: median, lowest and highest over seeds (1 when the
    /// default is the fastest).
    pub gap: Option<(f64, f64, f64)>,
    /// Index of the fastest strategy other than the default by median time
    /// in the screening round: the one the confirmation round measures.
    pub rival: Option<usize>,
    /// The default's time over the rival's, seed for seed, in the
    /// confirmation round: median, lowest and highest over its seeds.
    pub confirmed: Option<(f64, f64, f64)>,
    /// The default's median time over every seed of both rounds (twice as
    /// many renders as the screening's median): the figure compared with
    /// Mitsuba. `None` unless every one of them reached the target.
    pub default_time: Option<f64>,
}

/// The default's time over `other`'s, seed for seed: median, lowest and
/// highest; `None` unless both reached the target in all `seeds` seeds.
fn paired_ratio(default: &SeedTimes, other: &SeedTimes, seeds: u32) -> Option<(f64, f64, f64)> {
    let ratios: Vec<f64> =
        default.iter().filter_map(|&(seed, t)| other.iter().find(|x| x.0 == seed).map(|x| t / x.1)).collect();
    (ratios.len() == seeds as usize && !ratios.is_empty()).then(|| median_min_max(ratios))
}

/// The standings of every strategy on `backend` in the screening round, the
/// fastest, and the default's gap to it seed for seed; then the
/// confirmation round's gap to the fastest other strategy.
pub fn scene_result(points: &[Point], backend: &BenchBackend, seeds: u32, target: f64) -> SceneResult {
    let (screening, confirmation): (Vec<Point>, Vec<Point>) =
        points.iter().filter(|p| p.backend == *backend).cloned().partition(|p| p.seed < CONFIRM_SEED);
    let standings: Vec<Standing> = STRATEGIES
        .iter()
        .map(|st| {
            let times = times_by_seed(&screening, backend, st.name, target);
            Standing { median: median_time(&times, seeds as usize), times }
        })
        .collect();
    let fastest = |skip_default: bool| {
        standings
            .iter()
            .enumerate()
            .skip(usize::from(skip_default))
            .filter_map(|(i, s)| s.median.map(|m| (i, m)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };
    let (best, rival) = (fastest(false), fastest(true));
    let gap = best.and_then(|b| paired_ratio(&standings[0].times, &standings[b].times, seeds));
    let confirmed = rival.and_then(|r| {
        let times = |name| times_by_seed(&confirmation, backend, name, target);
        paired_ratio(&times(STRATEGIES[0].name), &times(STRATEGIES[r].name), seeds)
    });
    // Screening and confirmation seeds render the default alike; a shared
    // machine's timing noise (one run can be 20% off) moves a median of
    // twice as many renders less.
    let confirming = times_by_seed(&confirmation, backend, STRATEGIES[0].name, target);
    let rendered = seeds_of(&confirmation, backend, STRATEGIES[0].name).len();
    let default_time = standings[0].median.filter(|_| confirming.len() == rendered).map(|_| {
        let all = standings[0].times.iter().chain(&confirming).map(|t| t.1).collect();
        median_min_max(all).0
    });
    SceneResult { standings, best, gap, rival, confirmed, default_time }
}

/// Mitsuba's curves of one scene: per sampler, (seed, spp, time, relMSE).
pub type MitsubaRuns = Vec<(String, u32, u32, f64, f64)>;

/// Reads `<dir>/<scene>.csv` as `compare.py --suite` writes it:
/// `sampler,seed,spp,time_s,rel_mse`, with the reference's own relMSE
/// `noise` taken off, as off ours.
pub fn read_mitsuba(path: &Path, noise: f64) -> Result<MitsubaRuns> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let at = || format!("{}:{}", path.display(), i + 1);
        if f.len() != 5 {
            bail!("{}: expected sampler,seed,spp,time_s,rel_mse", at());
        }
        out.push((
            f[0].to_string(),
            f[1].parse().with_context(|| format!("{}: seed", at()))?,
            f[2].parse().with_context(|| format!("{}: spp", at()))?,
            f[3].parse().with_context(|| format!("{}: time_s", at()))?,
            f[4].parse::<f64>().with_context(|| format!("{}: rel_mse", at()))?.max(noise) - noise,
        ));
    }
    Ok(out)
}

/// Each Mitsuba sampler's median time to `target` over its seeds (read
/// along each seed's own curve, as ours), in the order of the file; `None`
/// for a sampler whose seeds did not all reach it.
pub fn mitsuba_times(runs: &MitsubaRuns, target: f64) -> Vec<(String, Option<f64>)> {
    let mut samplers: Vec<&str> = Vec::new();
    for r in runs {
        if !samplers.contains(&r.0.as_str()) {
            samplers.push(&r.0);
        }
    }
    samplers
        .into_iter()
        .map(|name| {
            let mut seeds: Vec<u32> = runs.iter().filter(|r| r.0 == name).map(|r| r.1).collect();
            seeds.sort_unstable();
            seeds.dedup();
            let times: Vec<f64> = seeds
                .iter()
                .filter_map(|&seed| {
                    let mut c: Vec<_> = runs.iter().filter(|r| r.0 == name && r.1 == seed).collect();
                    c.sort_by_key(|r| r.2);
                    time_to(&c.iter().map(|r| (r.3, r.4)).collect::<Vec<_>>(), target)
                })
                .collect();
            let median = (times.len() == seeds.len() && !times.is_empty()).then(|| median_min_max(times).0);
            (name.to_string(), median)
        })
        .collect()
}

/// Mitsuba's fastest sampler to the target and its time.
pub fn mitsuba_best(times: &[(String, Option<f64>)]) -> Option<(&str, f64)> {
    times.iter().filter_map(|(n, t)| t.map(|t| (n.as_str(), t))).min_by(|a, b| a.1.total_cmp(&b.1))
}

/// "0.123 s" or "-".
fn secs(t: Option<f64>) -> String {
    t.map_or("-".into(), |t| format!("{t:.3} s"))
}

/// One scene's table: each strategy's median time (seed range) per backend.
pub fn scene_markdown(points: &[Point], backends: &[BenchBackend], seeds: u32, target: f64) -> String {
    let results: Vec<SceneResult> = backends.iter().map(|b| scene_result(points, b, seeds, target)).collect();
    let mut s = String::from("| strategy |");
    for b in backends {
        let _ = write!(s, " {} |", b.kind.label());
    }
    s.push_str("\n|---|");
    s.push_str(&"---|".repeat(backends.len()));
    s.push('\n');
    for (i, st) in STRATEGIES.iter().enumerate() {
        let _ = write!(s, "| {} |", st.name);
        for (k, r) in results.iter().enumerate() {
            let x = &r.standings[i];
            let ran = points.iter().any(|p| p.strategy == st.name && p.backend == backends[k]);
            let cell = match x.median {
                Some(m) => {
                    let (_, lo, hi) = median_min_max(x.times.iter().map(|t| t.1).collect());
                    format!("{m:.3} s ({lo:.3}-{hi:.3})")
                }
                // `scene_curves` skips a strategy that is the default here.
                None if !ran => "the default here".into(),
                None => "not reached".into(),
            };
            let bold = r.best == Some(i);
            let _ = write!(s, " {} |", if bold { format!("**{cell}**") } else { cell });
        }
        s.push('\n');
    }
    for (b, r) in backends.iter().zip(&results) {
        let _ = writeln!(s, "\n{}, confirmation round: the default's gap {}.", b.kind.label(), confirmed_text(r));
    }
    s
}

/// The default's gap in the screening round as "1.04x (0.98-1.10)", or "-".
pub fn gap_text(r: &SceneResult) -> String {
    ratio_text(r.gap)
}

/// The default's gap in the confirmation round, with the strategy it was
/// measured against: "1.04x (0.98-1.10) against NEE with MIS", or "-".
pub fn confirmed_text(r: &SceneResult) -> String {
    match (r.confirmed, r.rival) {
        (Some(g), Some(i)) => format!("{} against {}", ratio_text(Some(g)), STRATEGIES[i].name),
        _ => "-".into(),
    }
}

fn ratio_text(g: Option<(f64, f64, f64)>) -> String {
    g.map_or("-".into(), |(m, lo, hi)| format!("{m:.2}x ({lo:.2}-{hi:.2})"))
}

/// A scene's measurements, as the report shows them.
pub struct SceneRun<'a> {
    /// The scene.
    pub scene: &'a SuiteScene,
    /// Its settings.
    pub settings: RenderSettings,
    /// Its reference's own relMSE.
    pub reference_rel_mse: f64,
    /// Every curve point.
    pub points: Vec<Point>,
    /// Mitsuba's runs, when given.
    pub mitsuba: Option<MitsubaRuns>,
}

/// (median time, mean relMSE) at each sample count that every seed
/// measured, from (seed, spp, time, relMSE) rows.
fn median_curve(rows: &[(u32, u32, f64, f64)]) -> Vec<(f64, f64)> {
    let mut seeds: Vec<u32> = rows.iter().map(|r| r.0).collect();
    seeds.sort_unstable();
    seeds.dedup();
    let mut spps: Vec<u32> = rows.iter().map(|r| r.1).collect();
    spps.sort_unstable();
    spps.dedup();
    spps.into_iter()
        .filter_map(|spp| {
            let at: Vec<_> = rows.iter().filter(|r| r.1 == spp).collect();
            (at.len() == seeds.len()).then(|| {
                let (t, _, _) = median_min_max(at.iter().map(|r| r.2).collect());
                (t, at.iter().map(|r| r.3).sum::<f64>() / at.len() as f64)
            })
        })
        .collect()
}

/// [`median_curve`] of `strategy` on `backend`.
fn common_curve(points: &[Point], backend: &BenchBackend, strategy: &str) -> Vec<(f64, f64)> {
    let rows: Vec<_> = points
        .iter()
        .filter(|p| p.backend == *backend && p.strategy == strategy && p.seed < CONFIRM_SEED)
        .map(|p| (p.seed, p.spp, p.time, p.rel_mse))
        .collect();
    median_curve(&rows)
}

/// [`median_curve`] of Mitsuba's `sampler`.
fn mitsuba_curve(runs: &MitsubaRuns, sampler: &str) -> Vec<(f64, f64)> {
    let rows: Vec<_> = runs.iter().filter(|r| r.0 == sampler).map(|r| (r.1, r.2, r.3, r.4)).collect();
    median_curve(&rows)
}

/// A plotted line: its label, (time, relMSE) points and colour.
type Series = (String, Vec<(f64, f64)>, plotters::style::RGBAColor);

/// Small multiples: one log-log panel of relMSE against time per scene,
/// with the default on each backend, the fastest other strategy on the
/// first backend, and Mitsuba's fastest sampler.
pub fn plot_suite(
    path: &Path,
    runs: &[SceneRun<'_>],
    backends: &[BenchBackend],
    seeds: u32,
    target: f64,
) -> Result<()> {
    use plotters::prelude::*;
    plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT)
        .map_err(|_| anyhow::anyhow!("cannot load the plot font"))?;
    let cols = 3;
    let rows = runs.len().div_ceil(cols).max(1);
    let root = BitMapBackend::new(path, (1500, 420 * rows as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((rows, cols));
    for (run, area) in runs.iter().zip(panels.iter()) {
        let mut series: Vec<Series> = Vec::new();
        let default = StrategyId::Default.name();
        for (k, b) in backends.iter().enumerate() {
            let color = if k == 0 { RED.to_rgba() } else { BLUE.to_rgba() };
            series.push((format!("{} default", b.kind.label()), common_curve(&run.points, b, default), color));
        }
        if let Some(b) = backends.first() {
            let r = scene_result(&run.points, b, seeds, target);
            if let Some(i) = r.best.filter(|&i| i != 0) {
                let name = STRATEGIES[i].name;
                series.push((
                    format!("{}: {name}", b.kind.label()),
                    common_curve(&run.points, b, name),
                    MAGENTA.to_rgba(),
                ));
            }
        }
        if let Some(m) = &run.mitsuba
            && let Some((name, _)) = mitsuba_best(&mitsuba_times(m, target))
        {
            series.push((format!("Mitsuba 3, {name}"), mitsuba_curve(m, name), BLACK.to_rgba()));
        }
        let all = series.iter().flat_map(|s| s.1.iter());
        let (t0, t1, e0, e1) = all.fold((f64::MAX, 0.0f64, f64::MAX, 0.0f64), |(a, b, c, d), p| {
            (a.min(p.0), b.max(p.0), c.min(p.1), d.max(p.1))
        });
        if t1 <= 0.0 {
            continue;
        }
        let (e0, e1) = (e0.min(target), e1.max(target));
        let mut chart = ChartBuilder::on(area)
            .caption(&run.scene.name, ("sans-serif", 20))
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(55)
            .build_cartesian_2d((t0 * 0.8..t1 * 1.25).log_scale(), (e0 * 0.8..e1 * 1.25).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("seconds")
            .y_desc("relMSE")
            .x_label_formatter(&|x| format!("{x:.2}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            // On a log axis of under two decades plotters labels every
            // tenth of a decade, with light lines between: a grey band.
            .x_labels(5)
            .y_labels(5)
            .x_max_light_lines(1)
            .y_max_light_lines(1)
            .label_style(("sans-serif", 12))
            .draw()?;
        chart.draw_series(LineSeries::new([(t0 * 0.8, target), (t1 * 1.25, target)], BLACK.mix(0.3)))?;
        for (name, pts, color) in &series {
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 11))
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// The suite's section of the report: the summary table, the plot, and
/// each scene's table of strategies (the scenes of folder `dir`).
pub fn suite_markdown(
    runs: &[SceneRun<'_>],
    backends: &[BenchBackend],
    seeds: u32,
    target: f64,
    dir: &str,
    plot: &str,
    csv: &str,
) -> String {
    let mut s = String::new();
    let (w, h) = runs.first().map_or((0, 0), |r| (r.settings.width, r.settings.height));
    let both = 2 * seeds;
    let _ = writeln!(
        s,
        "Every scene of `{dir}/` at {w}x{h} pixels with its own bounce limit, {seeds} seeds per strategy and backend. \
         Each seed renders the default first, then every other strategy (but one that renders the scene just as \
         the default does: \"the default here\"), at 4, 8, 16, ... spp, each count from scratch and timed \
         from its first frame until it has finished, as Mitsuba is timed, measuring relMSE \
         against the scene's cached reference, and stops a curve at the first measurement below \
         {target:.0e} (or past {CUT_OFF}x the default's time of that seed: \"not reached\"). Times are read \
         log-log between measurements, per seed; the tables give the median and the seeds' range. The default's \
         gap is its time over the fastest strategy's (by median), seed for seed: median and range of the seeds' \
         ratios. That is the screening round. Picking the lowest of a dozen noisy medians favours whichever \
         strategy had the luckiest runs, so the screening's gap is biased against the default where strategies \
         tie; a confirmation round then renders the default and the fastest other strategy again, in turn, on \
         {seeds} fresh seeds (seeds {CONFIRM_SEED} and up in the CSV), and its gap is the one the goal is judged \
         by. The summary's time of the default, and its ratio to Mitsuba, is the median over its renders in \
         both rounds ({both} seeds); the scenes' own tables give the screening's. Mitsuba 3 (`llvm_ad_rgb`, \
         `path`) renders the same scene, size and bounce limit from scratch at each sample count with each of \
         its `independent`, `multijitter`, `ldsampler` and `orthogonal` samplers ({seeds} seeds, kernels \
         compiled untimed first), against the same reference; its fastest sampler per scene is the one \
         compared.\n"
    );
    s.push_str("| scene | what it stresses | reference relMSE |");
    for b in backends {
        let l = b.kind.label();
        let _ =
            write!(s, " {l}: default | {l}: fastest strategy | {l}: default's gap | {l}: default's gap, confirmed |");
    }
    s.push_str(" Mitsuba's fastest sampler |");
    for b in backends {
        let _ = write!(s, " {}: ratio to Mitsuba |", b.kind.label());
    }
    s.push_str("\n|---|---|---|");
    s.push_str(&"---|---|---|---|".repeat(backends.len()));
    s.push_str("---|");
    s.push_str(&"---|".repeat(backends.len()));
    s.push('\n');
    for run in runs {
        let results: Vec<SceneResult> = backends.iter().map(|b| scene_result(&run.points, b, seeds, target)).collect();
        let mitsuba = run.mitsuba.as_ref().map(|m| mitsuba_times(m, target));
        let best_m = mitsuba.as_deref().and_then(mitsuba_best);
        let _ = write!(s, "| {} | {} | {:.1e} |", run.scene.name, run.scene.stresses, run.reference_rel_mse);
        for r in &results {
            let fastest = r.best.map_or("-".into(), |i| {
                let name = if i == 0 { "the default" } else { STRATEGIES[i].name };
                format!("{name}, {}", secs(r.standings[i].median))
            });
            let _ = write!(s, " {} | {fastest} | {} | {} |", secs(r.default_time), gap_text(r), confirmed_text(r));
        }
        let _ = write!(s, " {} |", best_m.map_or("-".into(), |(n, t)| format!("{n}, {t:.3} s")));
        for r in &results {
            let ratio = match (r.default_time, best_m) {
                (Some(a), Some((_, b))) => format!("{:.2}x", a / b),
                _ => "-".into(),
            };
            let _ = write!(s, " {ratio} |");
        }
        s.push('\n');
    }
    let _ = writeln!(s, "\n![relMSE against time, one panel per scene]({plot})\n\nAll points: `{csv}`.");
    for run in runs {
        let _ = writeln!(s, "\n#### {}\n\n{}\n", run.scene.name, run.scene.stresses);
        s.push_str(&scene_markdown(&run.points, backends, seeds, target));
        if let Some(m) = &run.mitsuba {
            let times = mitsuba_times(m, target);
            let list: Vec<String> = times.iter().map(|(n, t)| format!("{n} {}", secs(*t))).collect();
            let _ = writeln!(s, "\nMitsuba 3, median time to {target:.0e}: {}.", list.join(", "));
        }
    }
    s
}

/// Writes every point of the suite as CSV, with its scene.
pub fn write_suite_csv(path: &Path, runs: &[SceneRun<'_>]) -> Result<()> {
    let mut s = String::from("scene,backend,strategy,seed,spp,time_s,rel_mse\n");
    for run in runs {
        for p in &run.points {
            let _ = writeln!(
                s,
                "{},\"{}\",\"{}\",{},{},{:.6},{:.6e}",
                run.scene.name, p.backend, p.strategy, p.seed, p.spp, p.time, p.rel_mse
            );
        }
    }
    std::fs::write(path, s).with_context(|| format!("{}: cannot write the CSV", path.display()))
}

/// Reads a CSV that [`write_suite_csv`] wrote: every point, by scene, in
/// the file's order. MAPE and RMSE are not in the file and read as 0; the
/// suite's tables use neither.
pub fn read_suite_csv(path: &Path) -> Result<Vec<(String, Point)>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let at = || format!("{}:{}", path.display(), i + 1);
        let f = csv_fields(line);
        if f.len() != 7 {
            bail!("{}: expected scene,backend,strategy,seed,spp,time_s,rel_mse", at());
        }
        let backend = match f[1].split_once(": ") {
            Some(("GPU", d)) => BenchBackend::gpu(d),
            Some(("CPU", d)) => BenchBackend { kind: BackendKind::Cpu, detail: d.to_string() },
            _ => bail!("{}: backend {:?} is neither \"GPU: ...\" nor \"CPU: ...\"", at(), f[1]),
        };
        let point = Point {
            backend,
            strategy: f[2].clone(),
            seed: f[3].parse().with_context(|| format!("{}: seed", at()))?,
            spp: f[4].parse().with_context(|| format!("{}: spp", at()))?,
            time: f[5].parse().with_context(|| format!("{}: time_s", at()))?,
            rel_mse: f[6].parse().with_context(|| format!("{}: rel_mse", at()))?,
            mape: 0.0,
            rmse: 0.0,
        };
        out.push((f[0].clone(), point));
    }
    Ok(out)
}

/// How many screening seeds (below [`CONFIRM_SEED`]) `points` hold.
pub fn screening_seeds<'a>(points: impl Iterator<Item = &'a Point>) -> u32 {
    let mut seeds: Vec<u32> = points.map(|p| p.seed).filter(|&s| s < CONFIRM_SEED).collect();
    seeds.sort_unstable();
    seeds.dedup();
    seeds.len() as u32
}

/// The fields of one CSV line: commas inside double quotes do not split,
/// and the quotes are dropped (the strategies' names hold commas but no
/// quotes).
fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(String::new()),
            c => fields.last_mut().expect("never empty").push(c),
        }
    }
    fields
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `write_suite_csv` writes, `read_suite_csv` reads back: every
    /// field, a strategy name with commas and a colon in it included.
    #[test]
    fn the_suite_csv_reads_back_what_was_written() {
        let scenes = load_suite(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes"))).unwrap();
        let gpu = BenchBackend::gpu("llvmpipe (LLVM 15.0.6, 256 bits)");
        let cpu = BenchBackend { kind: BackendKind::Cpu, detail: "2 threads".into() };
        let points = vec![
            point(STRATEGIES[0].name, &gpu, 100, 64, 0.084092, 9.315918e-4),
            point(STRATEGIES[5].name, &cpu, 201, 4, 0.007018, 2.873919e-2),
        ];
        let run = SceneRun {
            scene: &scenes[0],
            settings: suite_settings(&scenes[0], 128, 128),
            reference_rel_mse: 0.0,
            points: points.clone(),
            mitsuba: None,
        };
        let dir = std::env::temp_dir().join(format!("pt-suite-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("suite.csv");
        write_suite_csv(&path, &[run]).unwrap();
        let back = read_suite_csv(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(STRATEGIES[0].name.contains(", ") && STRATEGIES[0].name.contains(": "));
        assert_eq!(back.len(), 2);
        // Seed 100 screens, 201 confirms.
        assert_eq!(screening_seeds(back.iter().map(|(_, p)| p)), 1);
        for ((scene, p), q) in back.iter().zip(&points) {
            assert_eq!(scene, &scenes[0].name);
            assert_eq!((&p.backend, &p.strategy, p.seed, p.spp), (&q.backend, &q.strategy, q.seed, q.spp));
            assert_eq!((p.time, p.rel_mse), (q.time, q.rel_mse));
        }
    }

    fn point(strategy: &str, backend: &BenchBackend, seed: u32, spp: u32, time: f64, rel_mse: f64) -> Point {
        Point { backend: backend.clone(), strategy: strategy.into(), seed, spp, time, rel_mse, mape: 0.0, rmse: 0.0 }
    }

    #[test]
    fn fnv1a_matches_its_published_vectors() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn the_reference_hash_follows_the_scene_and_settings_not_the_comments() {
        let a = Scene::default_scene();
        let text = format!("# another comment\n{}", a.to_toml());
        let b = Scene::from_toml(&text, Path::new("b.toml")).unwrap();
        let st = RenderSettings { width: 64, height: 64, ..a.render };
        assert_eq!(reference_hash(&a, &st, 1024), reference_hash(&b, &st, 1024));
        assert_ne!(reference_hash(&a, &st, 1024), reference_hash(&a, &st, 2048));
        assert_ne!(reference_hash(&a, &st, 1024), reference_hash(&a, &RenderSettings { width: 65, ..st }, 1024));
        let mut c = a.clone();
        c.light.radius *= 1.5;
        assert_ne!(reference_hash(&a, &st, 1024), reference_hash(&c, &st, 1024));
    }

    #[test]
    fn the_gap_pairs_each_seed_with_the_fastest_strategys_same_seed() {
        // Each run reaches 1e-3 at 2 t (halving log error from (t, 2e-3) to
        // (4 t, 5e-4)). The default: 2.0 and 3.0 s; MIS: 1.8 and 2.5 s, the
        // fastest by median (2.15 s against 2.5 s). Seed for seed: 2.0 / 1.8
        // and 3.0 / 2.5.
        let b = BenchBackend::gpu("b");
        let mut pts = Vec::new();
        for (k, reach) in [(0, [2.0, 3.0]), (5, [1.8, 2.5]), (1, [4.0, 4.0])] {
            for (seed, r) in reach.into_iter().enumerate() {
                pts.push(point(STRATEGIES[k].name, &b, seed as u32, 4, r / 2.0, 2e-3));
                pts.push(point(STRATEGIES[k].name, &b, seed as u32, 8, r * 2.0, 5e-4));
            }
        }
        let r = scene_result(&pts, &b, 2, 1e-3);
        assert_eq!(r.best, Some(5));
        let (m, lo, hi) = r.gap.unwrap();
        assert!((lo - 2.0 / 1.8).abs() < 1e-9 && (hi - 1.2).abs() < 1e-9 && m == hi, "{:?}", r.gap);
        assert_eq!(gap_text(&r), "1.20x (1.11-1.20)");
        // A strategy that a seed did not bring to the target has no median.
        pts.retain(|p| !(p.strategy == STRATEGIES[5].name && p.seed == 1 && p.spp == 8));
        let r = scene_result(&pts, &b, 2, 1e-3);
        assert!(r.standings[5].median.is_none());
        assert_eq!(r.best, Some(0));
        assert_eq!(r.gap.map(|g| g.0), Some(1.0));
    }

    #[test]
    fn the_confirmation_round_measures_the_default_against_the_fastest_other_strategy_on_its_own_seeds() {
        // Screening (seeds 0, 1): the default reaches 1e-3 at 2.0 and 3.0 s,
        // MIS (5) at 1.8 and 2.5 s, PCG (1) at 4.0 s: MIS is the fastest,
        // gap 1.2x. Confirmation (seeds CONFIRM_SEED, +1): the default at 2.0
        // and 2.2 s, MIS at 2.0 and 2.0 s: 1.0x and 1.1x. The screening's
        // figures must not move with the confirmation's points.
        let b = BenchBackend::gpu("b");
        let mut pts = Vec::new();
        let add = |pts: &mut Vec<Point>, k: usize, seed: u32, reach: f64| {
            pts.push(point(STRATEGIES[k].name, &b, seed, 4, reach / 2.0, 2e-3));
            pts.push(point(STRATEGIES[k].name, &b, seed, 8, reach * 2.0, 5e-4));
        };
        for (k, reach) in [(0, [2.0, 3.0]), (5, [1.8, 2.5]), (1, [4.0, 4.0])] {
            for (seed, r) in reach.into_iter().enumerate() {
                add(&mut pts, k, seed as u32, r);
            }
        }
        let screened = scene_result(&pts, &b, 2, 1e-3);
        assert_eq!((screened.best, screened.rival, screened.confirmed), (Some(5), Some(5), None));
        // Before the confirmation the default's time is the screening's
        // median (the upper of 2.0 and 3.0).
        assert!(screened.default_time.is_some_and(|t| (t - 3.0).abs() < 1e-9), "{:?}", screened.default_time);
        for (k, reach) in [(0, [2.0, 2.2]), (5, [2.0, 2.0])] {
            for (seed, r) in reach.into_iter().enumerate() {
                add(&mut pts, k, CONFIRM_SEED + seed as u32, r);
            }
        }
        let r = scene_result(&pts, &b, 2, 1e-3);
        assert_eq!((r.best, r.rival), (Some(5), Some(5)));
        assert_eq!(r.gap, screened.gap);
        assert_eq!(r.standings[0].times, screened.standings[0].times);
        let (m, lo, hi) = r.confirmed.unwrap();
        assert!((lo - 1.0).abs() < 1e-9 && (hi - 1.1).abs() < 1e-9 && m == hi, "{:?}", r.confirmed);
        assert_eq!(confirmed_text(&r), format!("1.10x (1.00-1.10) against {}", STRATEGIES[5].name));
        // The default's time compared with Mitsuba is the median of all
        // four of its renders, 2.0, 3.0, 2.0 and 2.2 (the upper middle one).
        assert!(r.default_time.is_some_and(|t| (t - 2.2).abs() < 1e-9), "{:?}", r.default_time);
        // Where the default is the screening's fastest, the rival is the
        // next one, and a confirmation seed short of the target leaves no
        // confirmed gap.
        pts.retain(|p| !(p.strategy == STRATEGIES[5].name && p.seed < CONFIRM_SEED));
        add(&mut pts, 1, CONFIRM_SEED, 4.0);
        add(&mut pts, 1, CONFIRM_SEED + 1, 4.0);
        let r = scene_result(&pts, &b, 2, 1e-3);
        assert_eq!((r.best, r.rival), (Some(0), Some(1)));
        assert!(r.confirmed.is_some_and(|g| (g.0 - 2.2 / 4.0).abs() < 1e-9), "{:?}", r.confirmed);
        pts.retain(|p| !(p.strategy == STRATEGIES[0].name && p.seed == CONFIRM_SEED + 1 && p.spp == 8));
        let r = scene_result(&pts, &b, 2, 1e-3);
        assert_eq!(r.confirmed, None);
        // A render of the default short of the target leaves no time.
        assert_eq!(r.default_time, None);
        assert_eq!(confirmed_text(&r), "-");
    }

    #[test]
    fn mitsubas_best_sampler_is_the_lowest_median_of_its_seeds() {
        // independent reaches 1e-3 at 2 s and 4 s (median of two: the
        // upper), multijitter at 1 s in both seeds; orthogonal never.
        let mut runs: MitsubaRuns = Vec::new();
        for (name, reach) in [("independent", [2.0, 4.0]), ("multijitter", [1.0, 1.0])] {
            for (seed, r) in reach.into_iter().enumerate() {
                runs.push((name.into(), seed as u32, 4, r / 2.0, 2e-3));
                runs.push((name.into(), seed as u32, 8, r * 2.0, 5e-4));
            }
        }
        runs.push(("orthogonal".into(), 0, 4, 1.0, 5e-3));
        runs.push(("orthogonal".into(), 0, 8, 2.0, 2e-3));
        let t = mitsuba_times(&runs, 1e-3);
        assert_eq!(t.iter().map(|x| x.0.as_str()).collect::<Vec<_>>(), ["independent", "multijitter", "orthogonal"]);
        assert!((t[0].1.unwrap() - 4.0).abs() < 1e-9 && (t[1].1.unwrap() - 1.0).abs() < 1e-9 && t[2].1.is_none());
        let (name, time) = mitsuba_best(&t).unwrap();
        assert_eq!(name, "multijitter");
        assert!((time - 1.0).abs() < 1e-9);
    }

    /// The suite's cached references, as `scripts/performance_report.sh`
    /// makes them: 128x128, 8192 spp.
    fn committed_reference(s: &SuiteScene) -> Reference {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/bench/references");
        let settings = suite_settings(s, 128, 128);
        let stem = format!("{}-{:016x}", s.name, reference_hash(&s.scene, &settings, 8192));
        assert!(dir.join(format!("{stem}.exr")).exists(), "{stem}.exr is not in docs/bench/references");
        cached_reference(&dir, s, &settings, 8192, |_| {}).unwrap()
    }

    #[test]
    fn every_scene_renders_the_same_image_as_its_reference_with_its_default_strategy() {
        // The references were rendered with the glow lobe on everywhere;
        // each scene's own default renders here, and so does the default
        // with the connections switched (on around the large lights, off
        // around the small ones), on the CPU at 64 spp, independent seed.
        // A paired t test per 16x16 region and channel: 11 scenes x 2
        // strategies x 64 regions x 3 channels = 4224 statistics; |t| > 5 by chance has
        // probability about 4e-3 in all (Student's t with 255 degrees of
        // freedom).
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut worst = (0.0f64, String::new());
        let mut connected = 0;
        for s in load_suite(&dir).unwrap() {
            let reference = committed_reference(&s);
            let settings = suite_settings(&s, 128, 128);
            let mut params = s.scene.frame_params(&settings, 64, 4242);
            let default = s.scene.default_flags();
            assert_eq!(params.flags, default);
            for st in [StrategyId::Default, StrategyId::ConnectionsSwitched] {
                params.flags = (st.strategy().flags)(default);
                connected += (params.flags & pt_core::params::FLAG_CONNECT != 0) as u32;
                let mut r = CpuRenderer::new(params, &s.scene.gpu_walls(), &s.scene.gpu_spheres()).unwrap();
                r.render_frame(64);
                let img = means(r.accum());
                let t = metrics::region_t_statistics(&img, &reference.pixels, 128, 128, 16);
                let m = t.iter().flat_map(|r| r.iter().map(|x| x.abs())).fold(0.0, f64::max);
                if m > worst.0 {
                    worst = (m, format!("{} ({})", s.name, st.name()));
                }
            }
        }
        // One of the two has connections on every scene.
        assert_eq!(connected, 11, "{connected} renders with connections");
        assert!(worst.0 < 5.0, "{}: largest |t| {:.2}", worst.1, worst.0);
    }

    /// A folder of new scenes runs as it is: a scene without the line is
    /// named by its light and spheres, and one with it keeps its words.
    #[test]
    fn a_scene_without_a_stresses_line_is_named_by_its_light() {
        let dir = std::env::temp_dir().join(format!("pt-suite-stresses-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plain = Scene::default_scene().to_toml();
        std::fs::write(dir.join("a.toml"), &plain).unwrap();
        std::fs::write(dir.join("b.toml"), format!("# stresses: the default room again.\n{plain}")).unwrap();
        let suite = load_suite(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        let suite = suite.unwrap();
        assert_eq!(suite.len(), 2);
        assert_eq!(
            suite[0].stresses,
            "(no `# stresses:` line) a light of radius 0.15 at (0, 1.7, 0), 2 spheres, 5 walls."
        );
        assert_eq!(suite[1].stresses, "the default room again.");
        assert!(suite[0].scene == suite[1].scene);
    }

    #[test]
    fn every_scene_of_the_suite_says_what_it_stresses_and_loads() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let suite = load_suite(&dir).unwrap();
        assert!(suite.len() >= 8, "{} scenes", suite.len());
        assert!(suite.iter().any(|s| s.name == "default" && s.scene == Scene::default_scene()));
        assert!(
            suite.iter().all(|s| s.stresses.len() > 20 && !s.stresses.starts_with("(no ")),
            "every scene says what it stresses"
        );
        let radii: Vec<f32> = suite.iter().map(|s| s.scene.light.radius).collect();
        let (lo, hi) = radii.iter().fold((f32::MAX, 0.0f32), |(a, b), &r| (a.min(r), b.max(r)));
        assert!(lo <= 0.025 && hi >= 0.45, "light radii {lo} to {hi}");
        assert!(suite.iter().any(|s| s.scene.render.max_bounces >= 16));
    }
}
