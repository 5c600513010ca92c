//! Error against time: convergence curves per strategy and seed, and the
//! times to a target error read off them.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use pt_core::AccumPixel;
use pt_render::gpu::GpuContext;
use pt_render::{CpuRenderer, RenderSettings, Scene, metrics, output};
use pt_render::{Device, Renderer};

use super::{BenchBackend, STRATEGIES, Strategy, StrategyId, median_min_max};

/// One point of a convergence curve.
#[derive(Clone, Debug)]
pub struct Point {
    /// Where it ran.
    pub backend: BenchBackend,
    /// Strategy label.
    pub strategy: String,
    /// Seed.
    pub seed: u32,
    /// Samples per pixel so far.
    pub spp: u32,
    /// Seconds of rendering so far (evaluation excluded).
    pub time: f64,
    /// relMSE against the reference.
    pub rel_mse: f64,
    /// MAPE.
    pub mape: f64,
    /// RMSE.
    pub rmse: f64,
}

pub(crate) fn means(accum: &[AccumPixel]) -> Vec<[f32; 3]> {
    accum.iter().map(|p| p.mean().to_array()).collect()
}

/// Renders the reference: `spp` samples per pixel on the CPU, telling
/// `progress` the samples per pixel done.
pub fn reference(
    scene: &Scene,
    settings: &RenderSettings,
    spp: u32,
    mut progress: impl FnMut(u32),
) -> Result<Vec<[f32; 3]>> {
    let params = scene.frame_params(settings, 64, REFERENCE_SEED);
    let mut r = CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres())?;
    let mut done = 0;
    while done < spp {
        let n = 64.min(spp - done);
        r.render_frame(n);
        done += n;
        progress(done);
    }
    Ok(means(r.accum()))
}

/// Seed of the reference render: distinct from every test seed.
const REFERENCE_SEED: u32 = 0x5eed_0001;

/// When a curve may stop before its largest sample count.
#[derive(Copy, Clone, Debug)]
pub struct Until {
    /// Stop after the first measurement below this relMSE.
    pub target: Option<f64>,
    /// Stop after the first measurement past this many seconds.
    pub time_limit: f64,
}

impl Until {
    /// Run to the largest sample count.
    pub const END: Self = Self { target: None, time_limit: f64::INFINITY };
}

/// Untimed renders before the timed curves, on seed 99: the default up to
/// 64 spp, since the first renders of a run were measured up to 30% slower
/// (driver and machine warming up), which would have penalised whichever
/// strategy came first; then 4 spp of every other strategy, since a GPU
/// driver may compile a pipeline at its first dispatch (lavapipe does),
/// which would count against whichever strategy first needs it.
pub(crate) fn warm_up(
    device: Device<'_>,
    scene: &Scene,
    settings: &RenderSettings,
    max_spp: u32,
    reference: &[[f32; 3]],
    backend: &BenchBackend,
    until: Until,
) -> Result<()> {
    for st in &STRATEGIES {
        let spp = if st.id == StrategyId::Default { 64 } else { 4 };
        curve(device, scene, settings, st, 99, max_spp.min(spp), reference, backend, until)?;
    }
    Ok(())
}

/// Renders `strategy` on one backend at every power-of-two sample count
/// from 4 up to `max_spp`, measuring the error of each, and stopping early
/// as `until` says. The default strategy takes the scene's own flags
/// ([`Scene::default_flags`]).
///
/// Each count is one render from scratch, in frames of the strategy's
/// samples per frame, timed by wall clock from its first frame until it
/// has finished: what `pathtracer render --spp N` spends rendering, and how
/// Mitsuba is timed (it has no progressive mode). The renderer's set-up,
/// readback and metric evaluation are outside the time. A seed's renders
/// at 2N and N spp share their first N samples, so the errors are those of
/// one progressive render; a progressive render's time would also count
/// the small frames and synchronisations before each measurement (4, 4, 8,
/// 16, 32 spp before 64), which a render to a sample count does not make.
#[allow(clippy::too_many_arguments)]
pub(crate) fn curve(
    device: Device<'_>,
    scene: &Scene,
    settings: &RenderSettings,
    strategy: &Strategy,
    seed: u32,
    max_spp: u32,
    reference: &[[f32; 3]],
    backend: &BenchBackend,
    until: Until,
) -> Result<Vec<Point>> {
    let mut params = scene.frame_params_with_flags(settings, strategy.spp_per_frame, seed, strategy.flags_for(scene));
    params.rr_start = strategy.rr_start;
    let (walls, spheres) = (scene.gpu_walls(), scene.gpu_spheres());
    let mut points = Vec::new();
    let mut spp = 4u32.min(max_spp);
    loop {
        let mut r = Renderer::new(device, params, &walls, &spheres)?;
        let start = Instant::now();
        let mut done = 0;
        while done < spp {
            let n = strategy.spp_per_frame.min(spp - done);
            r.frame(n);
            done += n;
        }
        r.wait()?;
        let time = start.elapsed().as_secs_f64();
        let accum = r.accum()?;
        let img = means(&accum);
        points.push(Point {
            backend: backend.clone(),
            strategy: strategy.name.to_string(),
            seed,
            spp,
            time,
            rel_mse: metrics::rel_mse(&img, reference),
            mape: metrics::mape(&img, reference),
            rmse: metrics::rmse(&img, reference),
        });
        let last = &points[points.len() - 1];
        if until.target.is_some_and(|t| last.rel_mse < t) || last.time > until.time_limit || spp == max_spp {
            break;
        }
        spp = (2 * spp).min(max_spp);
    }
    Ok(points)
}

/// Convergence curves of every strategy on each backend, `seeds` seeds each.
pub fn convergence(
    ctx: Option<&GpuContext>,
    scene: &Scene,
    settings: &RenderSettings,
    max_spp: u32,
    seeds: u32,
    reference: &[[f32; 3]],
    mut progress: impl FnMut(&str),
) -> Result<Vec<Point>> {
    let mut points = Vec::new();
    let mut backends: Vec<(Device<'_>, BenchBackend)> = Vec::new();
    if let Some(c) = ctx {
        backends.push((Device::Gpu(c), BenchBackend::gpu(&c.adapter_info.name)));
    }
    backends.push((Device::Cpu, BenchBackend::cpu()));
    for (device, name) in &backends {
        progress(&format!("{name}: warm-up"));
        warm_up(*device, scene, settings, max_spp, reference, name, Until::END)?;
        // Seeds outer, strategies inner: any drift of the machine's speed
        // during the run is spread over all strategies alike.
        for seed in 0..seeds {
            progress(&format!("{name}: seed {} of {seeds}, all strategies", seed + 1));
            for st in &STRATEGIES {
                points.extend(curve(*device, scene, settings, st, 100 + seed, max_spp, reference, name, Until::END)?);
            }
        }
    }
    Ok(points)
}

/// The backends of `points`, in the order they were measured.
pub fn backends_of(points: &[Point]) -> Vec<BenchBackend> {
    let mut backends: Vec<BenchBackend> = points.iter().map(|p| p.backend.clone()).collect();
    backends.dedup();
    backends
}

/// One sample count of a strategy's curve, over its seeds.
#[derive(Copy, Clone, Debug)]
pub struct CurvePoint {
    /// Median seconds: the machine is shared, and a single run can be
    /// slowed by half by other work; the median ignores such a spike.
    pub time: f64,
    /// Mean relMSE.
    pub rel_mse: f64,
    /// Smallest relMSE of a seed.
    pub rel_mse_min: f64,
    /// Largest relMSE of a seed.
    pub rel_mse_max: f64,
}

/// Median time, mean relMSE and its spread over seeds at each sample count
/// of a curve.
pub fn mean_curve(points: &[Point], backend: &BenchBackend, strategy: &str) -> Vec<CurvePoint> {
    let mut spps: Vec<u32> =
        points.iter().filter(|p| p.backend == *backend && p.strategy == strategy).map(|p| p.spp).collect();
    spps.sort_unstable();
    spps.dedup();
    spps.iter()
        .map(|&spp| {
            let sel: Vec<&Point> =
                points.iter().filter(|p| p.backend == *backend && p.strategy == strategy && p.spp == spp).collect();
            let n = sel.len() as f64;
            let (time, _, _) = median_min_max(sel.iter().map(|p| p.time).collect());
            CurvePoint {
                time,
                rel_mse: sel.iter().map(|p| p.rel_mse).sum::<f64>() / n,
                rel_mse_min: sel.iter().map(|p| p.rel_mse).fold(f64::MAX, f64::min),
                rel_mse_max: sel.iter().map(|p| p.rel_mse).fold(0.0, f64::max),
            }
        })
        .collect()
}

/// (time, relMSE) pairs of a mean curve.
pub fn time_error(curve: &[CurvePoint]) -> Vec<(f64, f64)> {
    curve.iter().map(|p| (p.time, p.rel_mse)).collect()
}

/// log-log interpolation of relMSE at time `t` along (time, relMSE) pairs.
pub(crate) fn rel_mse_at(curve: &[(f64, f64)], t: f64) -> Option<f64> {
    curve.windows(2).find(|w| w[0].0 <= t && t <= w[1].0).map(|w| {
        let f = (t.ln() - w[0].0.ln()) / (w[1].0.ln() - w[0].0.ln());
        (w[0].1.ln() + f * (w[1].1.ln() - w[0].1.ln())).exp()
    })
}

/// log-log interpolation of the time at which relMSE reaches `target`
/// along (time, relMSE) pairs.
pub fn time_to(curve: &[(f64, f64)], target: f64) -> Option<f64> {
    curve.windows(2).find(|w| w[0].1 >= target && w[1].1 <= target).map(|w| {
        let f = (target.ln() - w[0].1.ln()) / (w[1].1.ln() - w[0].1.ln());
        (w[0].0.ln() + f * (w[1].0.ln() - w[0].0.ln())).exp()
    })
}

/// The seeds a strategy was rendered with on `backend`, in order.
pub(crate) fn seeds(points: &[Point], backend: &BenchBackend, strategy: &str) -> Vec<u32> {
    let mut seeds: Vec<u32> =
        points.iter().filter(|p| p.backend == *backend && p.strategy == strategy).map(|p| p.seed).collect();
    seeds.sort_unstable();
    seeds.dedup();
    seeds
}

/// Each seed's time to relMSE `target` along its own curve, with the seed
/// (seeds that do not reach it are left out).
pub(crate) fn times_by_seed(points: &[Point], backend: &BenchBackend, strategy: &str, target: f64) -> Vec<(u32, f64)> {
    seeds(points, backend, strategy)
        .iter()
        .filter_map(|&seed| {
            let mut curve: Vec<&Point> =
                points.iter().filter(|p| p.backend == *backend && p.strategy == strategy && p.seed == seed).collect();
            curve.sort_by_key(|p| p.spp);
            time_to(&curve.iter().map(|p| (p.time, p.rel_mse)).collect::<Vec<_>>(), target).map(|t| (seed, t))
        })
        .collect()
}

/// Each seed's time to relMSE `target` along its own curve (seeds that do
/// not reach it are left out): the spread of a strategy's time.
pub fn seed_times_to(points: &[Point], backend: &BenchBackend, strategy: &str, target: f64) -> Vec<f64> {
    times_by_seed(points, backend, strategy, target).into_iter().map(|(_, t)| t).collect()
}

/// A strategy that reached relMSE `target` sooner than the default in
/// every seed, run for run.
#[derive(Clone, Debug, PartialEq)]
pub struct FasterThanDefault {
    /// The strategy's name.
    pub name: &'static str,
    /// Smallest and largest ratio of its time to the default's, over seeds.
    pub ratios: (f64, f64),
}

/// The strategies on `backend` that reached relMSE `target` sooner than
/// the default ([`StrategyId::Default`]) in every one of the default's seeds,
/// and the number of those seeds; `None` with fewer than two.
///
/// Each seed renders every strategy in turn, so a strategy's run and the
/// default's run of the same seed share the machine's state (a slow spell
/// of a shared machine spans both or neither), and their times pair. A
/// strategy exactly as fast as the default would still be the faster one
/// of a pair half of the time, and in all `n` pairs with probability 1/2^n
/// (a sign test): with 5 seeds, 0.031. The fastest median alone can be
/// such a strategy when two do the same work.
pub fn faster_than_default(
    points: &[Point],
    backend: &BenchBackend,
    target: f64,
) -> Option<(u32, Vec<FasterThanDefault>)> {
    let default = times_by_seed(points, backend, StrategyId::Default.name(), target);
    let n = seeds(points, backend, StrategyId::Default.name()).len();
    if n < 2 {
        return None;
    }
    let faster = STRATEGIES
        .iter()
        .filter(|st| st.id != StrategyId::Default)
        .filter_map(|st| {
            let times = times_by_seed(points, backend, st.name, target);
            let ratios: Vec<f64> = default
                .iter()
                .filter_map(|&(seed, d)| times.iter().find(|&&(s, _)| s == seed).map(|&(_, t)| t / d))
                .collect();
            (ratios.len() == n && ratios.iter().all(|&r| r < 1.0)).then(|| {
                let (_, lo, hi) = median_min_max(ratios);
                FasterThanDefault { name: st.name, ratios: (lo, hi) }
            })
        })
        .collect();
    Some((n as u32, faster))
}

/// Reads a reference EXR and checks its size.
pub fn load_reference(path: &Path, settings: &RenderSettings) -> Result<Vec<[f32; 3]>> {
    let (w, h, px) =
        output::read_exr(path).with_context(|| format!("{}: cannot read the reference", path.display()))?;
    if (w, h) != (settings.width, settings.height) {
        anyhow::bail!(
            "{}: the reference is {w}x{h}, the benchmark renders {}x{}",
            path.display(),
            settings.width,
            settings.height
        );
    }
    Ok(px)
}
