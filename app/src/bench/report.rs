//! The performance report's CSV, plot and markdown.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::convergence::*;
use super::{BenchBackend, STRATEGIES, StrategyId};

/// The convergence table in markdown, per backend, with the fastest
/// strategy to relMSE `target` named, those it does not beat by more than
/// the spread of its seeds (ties: their seeds' time ranges overlap), and
/// those faster than the default in every seed ([`faster_than_default`]).
pub fn convergence_markdown(points: &[Point], target: f64, max_spp: u32, pixels: u64) -> String {
    let mut s = String::new();
    let backends = backends_of(points);
    for b in &backends {
        // Each strategy's curve, and the range of its seeds' times to `target`.
        let range = |name: &str| {
            let times = seed_times_to(points, b, name, target);
            let lo = times.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = times.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (!times.is_empty()).then_some((lo, hi))
        };
        let curves: Vec<_> = STRATEGIES.iter().map(|st| (st, mean_curve(points, b, st.name), range(st.name))).collect();
        // Equal time: the shortest total time of any strategy.
        let t_eq = curves.iter().map(|(_, c, _)| c.last().map_or(f64::MAX, |l| l.time)).fold(f64::MAX, f64::min);
        let base_time = time_to(&time_error(&curves[0].1), target);
        let _ = writeln!(s, "\n### {b}\n");
        let _ = writeln!(
            s,
            "| strategy | samples/s | relMSE at {t_eq:.3} s | relMSE at {max_spp} spp (seed range) | relMSE x time at {max_spp} spp \
             | time to relMSE {target:.0e} (seed range) | speed-up vs default |\n|---|---|---|---|---|---|---|"
        );
        // Index in `curves` and time of the fastest strategy.
        let mut best: Option<(usize, f64)> = None;
        for (i, (st, c, seed_range)) in curves.iter().enumerate() {
            let Some(last) = c.last() else { continue };
            let te = time_error(c);
            let sps = pixels as f64 * max_spp as f64 / last.time;
            let at = rel_mse_at(&te, t_eq).or_else(|| (te[0].0 >= t_eq).then_some(te[0].1));
            let tt = time_to(&te, target);
            if let Some(t) = tt
                && best.is_none_or(|(_, bt)| t < bt)
            {
                best = Some((i, t));
            }
            let _ = writeln!(
                s,
                "| {} | {:.3e} | {} | {:.3e} ({:.2e}-{:.2e}) | {:.3e} | {} | {} |",
                st.name,
                sps,
                at.map_or("-".into(), |v| format!("{v:.3e}")),
                last.rel_mse,
                last.rel_mse_min,
                last.rel_mse_max,
                last.rel_mse * last.time,
                match (tt, seed_range) {
                    (Some(t), Some((lo, hi))) => format!("{t:.3} s ({lo:.2}-{hi:.2})"),
                    (Some(t), None) => format!("{t:.3} s"),
                    (None, _) => format!("> {:.2} s", last.time),
                },
                match (tt, base_time) {
                    (Some(t), Some(b)) => format!("{:.2}x", b / t),
                    _ => "-".into(),
                }
            );
        }
        if let Some((i, t)) = best {
            let (name, best_range) = (curves[i].0.name, curves[i].2);
            let _ = writeln!(s, "\nFastest to relMSE {target:.0e} on this backend: **{name}** ({t:.3} s).");
            if let Some((best_lo, best_hi)) = best_range {
                let tied: Vec<&str> = curves
                    .iter()
                    .filter(|(st, _, r)| st.name != name && r.is_some_and(|(lo, hi)| lo <= best_hi && best_lo <= hi))
                    .map(|(st, _, _)| st.name)
                    .collect();
                if !tied.is_empty() {
                    let _ = writeln!(
                        s,
                        "Tied with it (their seeds' times to relMSE {target:.0e} overlap its own): {}.",
                        tied.join("; ")
                    );
                }
            }
        }
        if let Some((n, faster)) = faster_than_default(points, b, target) {
            let list = if faster.is_empty() {
                "none".to_string()
            } else {
                faster
                    .iter()
                    .map(|f| format!("{} ({:.2}-{:.2}x the default's time)", f.name, f.ratios.0, f.ratios.1))
                    .collect::<Vec<_>>()
                    .join("; ")
            };
            let _ = writeln!(
                s,
                "Faster than the default in every seed, run for run (each seed renders every strategy in turn; a \
                 strategy only as fast would be so in all {n} seeds with probability 1/2^{n} = {:.3}): {list}.",
                0.5f64.powi(n as i32)
            );
        }
    }
    s
}

/// Writes all points as CSV.
pub fn write_csv(path: &Path, points: &[Point]) -> Result<()> {
    let mut s = String::from(
        "backend,strategy,seed,spp,time_s,rel_mse,mape,rmse
",
    );
    for p in points {
        let _ = writeln!(
            s,
            "\"{}\",\"{}\",{},{},{:.6},{:.6e},{:.6e},{:.6e}",
            p.backend, p.strategy, p.seed, p.spp, p.time, p.rel_mse, p.mape, p.rmse
        );
    }
    std::fs::write(path, s).with_context(|| format!("{}: cannot write the CSV", path.display()))
}

/// Draws relMSE against time, log-log, one line per backend and strategy
/// (mean over seeds), plus optional extra curves (e.g. Mitsuba).
pub fn plot(path: &Path, points: &[Point], extra: &[(String, Vec<(f64, f64)>)]) -> Result<()> {
    use plotters::prelude::*;
    plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT)
        .map_err(|_| anyhow::anyhow!("cannot load the plot font"))?;
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let backends = backends_of(points);
    for b in &backends {
        for st in &STRATEGIES {
            let c = mean_curve(points, b, st.name);
            let short = b.kind.label();
            series.push((format!("{short}: {}", st.name), time_error(&c)));
        }
    }
    series.extend(extra.iter().cloned());
    let all = series.iter().flat_map(|s| s.1.iter());
    let (t0, t1, e0, e1) = all
        .fold((f64::MAX, 0.0f64, f64::MAX, 0.0f64), |(a, b, c, d), p| (a.min(p.0), b.max(p.0), c.min(p.1), d.max(p.1)));
    let root = BitMapBackend::new(path, (1100, 750)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("relMSE against time (median time, mean relMSE of seeds), default scene", ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((t0 * 0.8..t1 * 1.25).log_scale(), (e0 * 0.8..e1 * 1.25).log_scale())?;
    chart.configure_mesh().x_desc("seconds").y_desc("relMSE").label_style(("sans-serif", 15)).draw()?;
    for (i, (name, pts)) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let style = if name.starts_with("CPU") { color.stroke_width(2) } else { color.stroke_width(3) };
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), style))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()?;
    root.present()?;
    Ok(())
}

/// Reads a CSV of `time_s,rel_mse` lines (with a header), as the Mitsuba
/// comparison script writes.
pub fn read_curve(path: &PathBuf) -> Result<Vec<(f64, f64)>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let mut f = line.split(',');
        let (Some(t), Some(e)) = (f.next(), f.next()) else {
            anyhow::bail!("{}:{}: expected time_s,rel_mse", path.display(), i + 1)
        };
        out.push((
            t.trim().parse().with_context(|| format!("{}:{}: time_s", path.display(), i + 1))?,
            e.trim().parse().with_context(|| format!("{}:{}: rel_mse", path.display(), i + 1))?,
        ));
    }
    Ok(out)
}

const MITSUBA_FAIRNESS: &str = "## Against Mitsuba 3\n\n\
Made by `scripts/performance_report.sh`: `scripts/mitsuba/compare.py` renders the same scene \
file with Mitsuba 3 (`llvm_ad_rgb`, `path` integrator, `max_depth` = max bounces + 1, box pixel \
filter, the light a black-BSDF sphere with an area emitter, walls two-sided diffuse) on the same \
machine, at the same resolution, against the same reference, with each of its `independent`, \
`multijitter`, `ldsampler` and `orthogonal` samplers, and keeps the one that reaches relMSE 1e-3 \
soonest (named below). Mitsuba's kernels are compiled before timing (each sample count is \
rendered once untimed, then timed); each of its points is one render from scratch at that sample \
count, with the median time and mean relMSE of its seeds. Ours are timed the same way: each point \
is one render from scratch at its sample count (the default strategy, above). Times to relMSE 1e-3 \
are interpolated log-log.\n\n";

/// The sampler named in the header of a curve from `compare.py` (its
/// fourth column); "independent" for curves written before it named one,
/// which all used Mitsuba's independent sampler.
pub fn curve_sampler(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let named = text.lines().next().and_then(|h| h.split(',').nth(3)).map(str::trim).filter(|s| !s.is_empty());
    named.unwrap_or("independent").to_string()
}

/// The defaults and the measurements behind each: how much longer (or
/// shorter) each alternative took to relMSE 1e-3 than the default, per
/// backend, from `points`.
pub(crate) fn defaults_section(points: &[Point]) -> String {
    let backends = backends_of(points);
    let time =
        |backend: &BenchBackend, strategy: &str| time_to(&time_error(&mean_curve(points, backend, strategy)), 1e-3);
    // "GPU ... 2.05x, CPU ... 1.91x": time of `a` over time of `b`.
    let ratio = |a: &str, b: &str| {
        backends
            .iter()
            .map(|backend| {
                let label = backend.kind.label();
                match (time(backend, a), time(backend, b)) {
                    (Some(x), Some(y)) => format!("{label} {:.2}x", x / y),
                    _ => format!("{label}: not reached within the budget"),
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let default = StrategyId::Default.name();
    let vs_default = |id: StrategyId| ratio(id.name(), default);
    // "GPU: none; CPU: none": the alternatives faster in every seed.
    let verdict = backends
        .iter()
        .filter_map(|backend| {
            let label = backend.kind.label();
            let (n, faster) = faster_than_default(points, backend, 1e-3)?;
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
         - Samples: randomised Sobol (the index Owen-scrambled, the values digitally shifted) for every draw of a path where connections are on; \
         elsewhere for the first 5 draws (pixel, then light and BSDF samples of two vertices), an independent \
         PCG stream for later ones. Independent PCG samples throughout: {}; Sobol draws switched: {}. Without \
         connections, deep in a path each Sobol pair is stratified alone, not jointly with the earlier ones, \
         and gains little, while a Sobol draw costs up to twice the integer multiplies of a PCG draw \
         (`SOBOL_DRAWS` in pt-core gives the choice of 5); a connection draws four more numbers per vertex, \
         and with it Sobol for every draw reached relMSE 1e-3 sooner on every scene of the suite.\n\
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
         (sin a = 0.09 from the floor): the cosine lobe rarely finds it and the glow lobe, where on, leaves its cone to \
         NEE, so MIS gives NEE nearly all the weight and both make the same image (the relMSE at 512 spp \
         above agrees to 3 digits). MIS then only adds work, a BSDF density and a weight per shadow ray, \
         and the two are a near tie that the cheaper one should win. MIS stays available (`FLAG_MIS`, the \
         viewer's checkbox) for large or near lights, whose cone reaches below a surface's horizon: cone \
         samples there are lost and BSDF samples find the visible part. At the last vertex no BSDF ray is \
         traced either way.\n\
         - NEE uniform in the light's cone. By projected solid angle where the cone lies wholly above a \
         vertex's horizon instead: {}. Projected, the cone's circle on the unit sphere, dropped onto the \
         tangent plane, is an ellipse; a point uniform in it, lifted back, has density proportional to the \
         cosine, so a shadow ray that reaches the light carries the exact unoccluded estimate \
         (`LightCone::sample_projected`) and only shadow edges are noisy. That leaves a little less noise per \
         sample, but it is a second sampling routine: where the scene is compiled into the kernel (lavapipe) \
         a render without it drops its code, and the CPU's eight lanes run both wherever their vertices \
         differ; uniform sampling reached relMSE 1e-3 sooner on most scenes of the suite.\n\
         - Connections through lit wall points (docs/ARCHITECTURE.md) around small lights where no wall can shadow the light: \
         each vertex also reaches the light through a wall point picked as the light would light it, weighed \
         by the power heuristic against the BSDF ray that could have found it. Connections off, with the glow \
         lobe in their place and Sobol for the first 5 draws: {}; the glow lobe beside them: {}. Nearly all of \
         the error left after NEE is indirect light, much of it from the bright patch of ceiling right above \
         the light, which the cosine lobe finds rarely and a connection finds by construction. Where they are \
         off (a wall that can shadow the light; large lights), BSDF sampling mixes the cosine lobe \
         with the glow lobe around the light (probability 0.25, reach 0.125 in 1 - cos past the light's cone, \
         density 1 / (1 - cos); `GLOW_PROBABILITY` and `GLOW_REACH` in pt-core; probability 0.1 around large \
         lights and in bright rooms, `FLAG_GLOW_SPARSE`), whose density falls as the inverse square of the \
         distance from the light, as the irradiance of surfaces around it does.\n\
         - Trace kernel: the small-scene kernel for scenes it holds (at most 8 walls and 16 spheres, and no \
         wall that can block a shadow ray: the default scene is one) on software adapters (lavapipe, \
         SwiftShader), with the scene compiled in for `render` and `bench` (the viewer, whose scene changes as \
         it is edited, reads it from buffers), and on NVIDIA GPUs; the general kernel for other scenes and \
         other GPUs, where it has not been measured. \
         The general and the small-scene kernel make the same image, bit for bit on lavapipe and on an NVIDIA \
         H200; with the scene compiled in, the driver folds and fuses differently (relMSE about 1e-11 between \
         the two). The throughput table times \
         both at 1920x1080, 64 spp/frame: lavapipe reads every uniform value of the general kernel as a \
         gather, lane by lane, and runs loop bodies that have nothing to do (docs/ARCHITECTURE.md); on an \
         NVIDIA H200 (PERFORMANCE-H200.md) and in a browser on SwiftShader the small-scene kernel ran ahead \
         too.\n\
         - Workgroup shape: 8x8 stays the default. The throughput table times 8x8, 16x4, 32x2 and 4x4 of the \
         general kernel (the only one that comes in every shape) on the \
         512x512 configuration; on lavapipe the shape only changes how invocations are batched into its \
         8-wide SIMD (4 wide rows leave half of each vector empty). On an H200 (PERFORMANCE-H200.md) 8x8, \
         16x4 and 32x2 are within 1% of each other and 4x4 runs at about half their speed: a 16-invocation \
         workgroup fills half of a 32-wide warp.\n",
        vs_default(StrategyId::Independent),
        vs_default(StrategyId::SobolSwitched),
        vs_default(StrategyId::RrFrom3),
        vs_default(StrategyId::RrFrom1),
        ratio(StrategyId::RrFrom3Luminance.name(), StrategyId::RrFrom3.name()),
        vs_default(StrategyId::Spp16),
        vs_default(StrategyId::Spp4),
        vs_default(StrategyId::NeeMis),
        vs_default(StrategyId::BsdfOnly),
        vs_default(StrategyId::NeeSwitched),
        vs_default(StrategyId::ConnectionsSwitched),
        vs_default(StrategyId::GlowShareSwitched),
    )
}

/// The report made on a lent GPU machine, kept beside the main one.
const GPU_MACHINE_REPORT: &str = "PERFORMANCE-H200.md";

/// Where the figures of a data-centre GPU are: the report of that name
/// beside `report` when there is one (this machine has no such GPU).
pub(crate) fn gpu_machine_section(report: Option<&Path>) -> String {
    let command = format!(
        "`pathtracer bench throughput --backend gpu --reps 10 --report docs/{GPU_MACHINE_REPORT}` (the kernel \
         is embedded in the release binary: copy it there with the Vulkan loader)"
    );
    let beside = report.and_then(Path::parent).map(|d| d.join(GPU_MACHINE_REPORT));
    if beside.is_some_and(|p| p.exists()) {
        format!(
            "\n## NVIDIA H200\n\nMeasured on a lent machine: [{GPU_MACHINE_REPORT}]({GPU_MACHINE_REPORT}), \
             made there by {command}. It names the GPU and its driver; its figures are those of the kernel as of the \
             commit that last changed it (`git log -1 docs/{GPU_MACHINE_REPORT}`). Rerun it there after a change \
             to the kernel.\n"
        )
    } else {
        format!(
            "\n## NVIDIA H200\n\nNot measured: no such GPU was at hand. To measure, run {command} on a \
             machine that has one, and keep the report beside this one.\n"
        )
    }
}

/// The browser viewer's speed table, written by `./scripts/web.sh test`.
const WEB_SPEED: &str = "web-speed.md";

/// The browser viewer's samples per second beside the native backends:
/// the table `./scripts/web.sh test` leaves beside `report`, measured in
/// one run of its own (a browser cannot run inside this bench).
pub(crate) fn web_section(report: Option<&Path>) -> String {
    let table = report.and_then(Path::parent).and_then(|d| std::fs::read_to_string(d.join(WEB_SPEED)).ok());
    match table {
        Some(table) => format!(
            "\n## In a browser\n\nThe viewer's page (`./scripts/web.sh`) traces with the same kernel, translated to \
             WGSL by naga in the page. From [{WEB_SPEED}]({WEB_SPEED}), which `./scripts/web.sh test` rewrites on \
             every run:\n\n{}",
            table.trim_end().to_owned() + "\n"
        ),
        None => "\n## In a browser\n\nNot measured here: `./scripts/web.sh test` writes the browser's figures to \
                 docs/web-speed.md.\n"
            .to_owned(),
    }
}

/// The Mitsuba comparison: time to relMSE 1e-3, ours against Mitsuba's.
pub(crate) fn mitsuba_section(csv: &PathBuf, points: &[Point]) -> Result<String> {
    let m = read_curve(csv)?;
    let tm = time_to(&m, 1e-3);
    let mut s =
        String::from(MITSUBA_FAIRNESS) + "| renderer | time to relMSE 1e-3 | ratio to Mitsuba |\n|---|---|---|\n";
    s.push_str(&format!(
        "| Mitsuba 3 llvm_ad_rgb, path, {} sampler (`{}`) | {} | 1 |\n",
        curve_sampler(csv),
        csv.display(),
        tm.map_or("not reached".into(), |t| format!("{t:.3} s"))
    ));
    let backends = backends_of(points);
    for b in backends {
        let t = time_to(&time_error(&mean_curve(points, &b, StrategyId::Default.name())), 1e-3);
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
pub(crate) fn relative_to_report(path: &std::path::Path, report: Option<&std::path::Path>) -> String {
    let dir = report.and_then(|r| r.parent()).filter(|d| !d.as_os_str().is_empty());
    match dir.and_then(|d| path.strip_prefix(d).ok()) {
        Some(rel) => rel.display().to_string(),
        None => path.display().to_string(),
    }
}

/// The throughput section: how rows were measured, then `table`.
pub(crate) fn throughput_section(reps: u32, table: &str) -> String {
    format!(
        "## Throughput\n\nDefault scene; warm-up frames for half a second (at least one), then {reps} timed frames per \
         configuration; median and \
         range of frames per second. Rays per sample (closest-hit plus shadow rays) are counted by the CPU's \
         instrumented trace of the same code over every 4th pixel in x and y, and multiply the samples per \
         second of both backends. The original OpenGL design reached 120 frames/s at 1920x1080, 4 spp/frame, \
         5 bounces on an RTX 3050: about 1.0e9 camera samples/s.\n\n{table}\n"
    )
}

/// What the error-against-time section states about its run.
pub(crate) struct ErrorAgainstTime {
    /// The scene file, or the built-in scene.
    pub scene: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Bounce limit.
    pub max_bounces: u32,
    /// Seeds per strategy.
    pub seeds: u32,
    /// What the errors are measured against.
    pub reference: String,
    /// The largest sample count of a run.
    pub max_spp: u32,
    /// The plot, relative to the report.
    pub plot: String,
    /// The CSV of all points, relative to the report.
    pub csv: String,
    /// The convergence table.
    pub table: String,
}

/// The error-against-time section: how the curves were measured, the plot,
/// the CSV and the table.
pub(crate) fn error_against_time_section(r: &ErrorAgainstTime) -> String {
    format!(
        "## Error against time\n\nScene: {}; {}x{} pixels, {} bounces; {} seeds per strategy; errors against {}. \
         Each strategy renders 4, 8, 16, ... up to {} spp, each count from scratch (as Mitsuba is timed, \
         and as `pathtracer render --spp N` renders), with the samples of one progressive render: \
         a seed's render at 2N spp begins with the N samples of its render at N spp. Time is wall clock from \
         a render's first frame until it has finished (set-up, readback and evaluation excluded). An untimed warm-up \
         render comes first, then every strategy once per seed in turn; each point takes the median time \
         and the mean relMSE of the seeds (the machine is shared: a single run can be slowed by half). \
         Equal time is the \
         shortest total time of any strategy; times to relMSE 1e-3 are interpolated log-log between \
         measurements.\n\n![relMSE against time]({})\n\nAll points: `{}`.\n{}\n",
        r.scene, r.width, r.height, r.max_bounces, r.seeds, r.reference, r.max_spp, r.plot, r.csv, r.table
    )
}
