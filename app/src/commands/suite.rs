//! `pathtracer bench convergence --suite`: the scene suite's run.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};
use pt_render::gpu::GpuContext;

use super::{machine_description, spp_progress_bar};
use crate::BenchArgs;
use crate::bench::relative_to_report;
use crate::bench::suite::{
    SceneRun, cached_reference, load_suite, plot_suite, read_mitsuba, read_suite_csv, scene_curves, scene_markdown,
    screening_seeds, suite_markdown, suite_settings, write_suite_csv,
};
use crate::bench::{BackendKind, BenchBackend, backends_of};

/// The target relMSE of the suite.
const TARGET: f64 = 1e-3;

/// Where the suite's section starts and ends in a report, so that a
/// report made by another command keeps it.
const BEGIN: &str = "<!-- suite: made by `pathtracer bench convergence --suite` -->";
const END: &str = "<!-- end of suite -->";

/// The suite's section of the report at `path`, markers included.
pub(crate) fn existing_section(path: &Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    let start = text.find(BEGIN)?;
    let end = text[start..].find(END)? + start + END.len();
    Some(format!("\n{}\n", &text[start..end]))
}

/// Runs the suite: references, then every scene's curves, then the tables,
/// the plot and the report's section.
pub(crate) fn run(args: &BenchArgs, gpu: Option<&GpuContext>, cpu: bool) -> Result<()> {
    let suite = load_suite(&args.suite_dir)?;
    let refs_dir = args.out_dir.join("references");
    let mut manifest = String::from("scene\tfile\treference\twidth\theight\tmax_bounces\treference_rel_mse\n");
    let mut references = Vec::new();
    for s in &suite {
        let settings = suite_settings(s, args.width, args.height);
        eprintln!("{}: reference, {} spp at {}x{} on the CPU", s.name, args.reference_spp, args.width, args.height);
        let bar = spp_progress_bar(args.reference_spp);
        let r = cached_reference(&refs_dir, s, &settings, args.reference_spp, |d| bar.set_position(d as u64))?;
        bar.finish_and_clear();
        eprintln!(
            "{}: {} {} (its own relMSE {:.1e})",
            s.name,
            if r.cached { "cached" } else { "wrote" },
            r.path.display(),
            r.rel_mse
        );
        let _ = writeln!(
            manifest,
            "{}\t{}\t{}\t{}\t{}\t{}\t{:e}",
            s.name,
            s.path.display(),
            r.path.display(),
            settings.width,
            settings.height,
            settings.max_bounces,
            r.rel_mse
        );
        references.push((settings, r));
    }
    let tsv = args.out_dir.join("suite.tsv");
    std::fs::write(&tsv, manifest).with_context(|| format!("{}: cannot write", tsv.display()))?;
    if args.reference_only {
        println!("wrote {}", tsv.display());
        return Ok(());
    }

    let csv = args.out_dir.join("suite.csv");
    let earlier = if args.from_csv { Some(read_suite_csv(&csv)?) } else { None };
    // A report rebuilt from a run has that run's seeds, whatever --seeds says.
    let seeds = earlier.as_ref().map_or(args.seeds, |all| screening_seeds(all.iter().map(|(_, p)| p)));
    let mut runs = Vec::new();
    for (s, (settings, r)) in suite.iter().zip(references) {
        let points = match &earlier {
            Some(all) => {
                let mine: Vec<_> = all.iter().filter(|(name, _)| *name == s.name).map(|(_, p)| p.clone()).collect();
                if mine.is_empty() {
                    bail!("{}: no points of scene {}", csv.display(), s.name);
                }
                mine
            }
            None => scene_curves(gpu, cpu, &s.scene, &settings, args.max_spp, seeds, TARGET, &r, |m| {
                eprintln!("{}: {m}", s.name)
            })?,
        };
        let mitsuba = match &args.mitsuba_dir {
            Some(d) => Some(read_mitsuba(&d.join(format!("{}.csv", s.name)), r.rel_mse)?),
            None => None,
        };
        let backends = backends_of(&points);
        println!("\n{} ({})\n{}", s.name, s.stresses, scene_markdown(&points, &backends, seeds, TARGET));
        runs.push(SceneRun { scene: s, settings, reference_rel_mse: r.rel_mse, points, mitsuba });
    }
    let backends: Vec<BenchBackend> = {
        let mut b: Vec<BenchBackend> = runs.iter().flat_map(|r| backends_of(&r.points)).collect();
        b.sort_by_key(|x| x.kind == BackendKind::Cpu);
        b.dedup();
        b
    };
    if backends.is_empty() {
        bail!("no backend measured");
    }
    // The machine that measured the points: this one, or for a report
    // rebuilt from them, the one its run recorded.
    let machine_file = args.out_dir.join("suite.machine");
    let machine = if args.from_csv {
        std::fs::read_to_string(&machine_file).map_or_else(|_| "not recorded".into(), |s| s.trim().to_string())
    } else {
        write_suite_csv(&csv, &runs)?;
        let m = machine_description();
        std::fs::write(&machine_file, format!("{m}\n"))
            .with_context(|| format!("{}: cannot write", machine_file.display()))?;
        m
    };
    let png = args.out_dir.join("suite.png");
    plot_suite(&png, &runs, &backends, seeds, TARGET)?;
    let body = format!(
        "Machine: {machine}.\n\n{}",
        suite_markdown(
            &runs,
            &backends,
            seeds,
            TARGET,
            args.suite_dir.to_string_lossy().trim_end_matches('/'),
            &relative_to_report(&png, args.report.as_deref()),
            &relative_to_report(&csv, args.report.as_deref()),
        )
    );
    println!("{body}");
    if let Some(path) = &args.report {
        let section = format!("{BEGIN}\n## The scene suite\n\n{body}\n{END}");
        let text = std::fs::read_to_string(path).unwrap_or_default();
        let text = match (text.find(BEGIN), text.find(END)) {
            (Some(a), Some(b)) if b > a => format!("{}{section}{}", &text[..a], &text[b + END.len()..]),
            _ => format!("{}\n{section}\n", text.trim_end()),
        };
        std::fs::write(path, text).with_context(|| format!("{}: cannot write the report", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
