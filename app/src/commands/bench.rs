//! `pathtracer bench`: runs the benchmarks and writes the performance report.

use anyhow::{Context, Result};
use pt_render::{RenderSettings, Scene, output};

use super::{load_scene, machine_description, rayon_threads, spp_progress_bar};
use crate::bench::{
    self, BackendKind, defaults_section, gpu_machine_section, mitsuba_section, relative_to_report, web_section,
};
use crate::{BenchArgs, BenchWhat, SuiteBackends};

/// Runs the benchmarks asked for and writes the report when asked.
pub(crate) fn run(args: &BenchArgs) -> Result<()> {
    let ctx = match args.backend {
        // A report rebuilt from an earlier run's points renders nothing.
        _ if args.from_csv => None,
        SuiteBackends::Cpu => None,
        _ => Some(pt_render::GpuContext::new().context("the GPU benchmark needs a Vulkan adapter")?),
    };
    let gpu = ctx.as_ref();
    let cpu_too = !matches!(args.backend, SuiteBackends::Gpu);
    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("{}: cannot create", args.out_dir.display()))?;
    if args.suite {
        return super::suite::run(args, gpu, cpu_too);
    }
    let mut report = String::new();
    let default_scene = Scene::default_scene();

    if args.what != BenchWhat::Convergence {
        eprintln!("throughput: {} configurations x {} repetitions", bench::THROUGHPUT_CONFIGS.len(), args.reps);
        let mut rows = bench::throughput(gpu, args.reps as usize, &default_scene)?;
        if !cpu_too {
            rows.retain(|r| r.backend.kind != BackendKind::Cpu);
        }
        let table = bench::throughput_markdown(&rows);
        println!("{table}");
        report.push_str(&bench::throughput_section(args.reps, &table));
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
            points.retain(|p| p.backend.kind != BackendKind::Cpu);
        }
        let csv = args.out_dir.join("convergence.csv");
        bench::write_csv(&csv, &points)?;
        let mut extra = Vec::new();
        if let Some(m) = &args.mitsuba_csv {
            let sampler = bench::curve_sampler(m);
            extra.push((format!("Mitsuba 3 llvm_ad_rgb, path, {sampler}"), bench::read_curve(m)?));
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
        report.push_str(&bench::error_against_time_section(&bench::ErrorAgainstTime {
            scene: args.scene.as_ref().map_or("the built-in default scene".to_string(), |p| p.display().to_string()),
            width: args.width,
            height: args.height,
            max_bounces: settings.max_bounces,
            seeds: args.seeds,
            reference: reference_note,
            max_spp: args.max_spp,
            plot: relative_to_report(&png, args.report.as_deref()),
            csv: relative_to_report(&csv, args.report.as_deref()),
            table,
        }));
        if let Some(m) = &args.mitsuba_csv {
            report.push_str(&mitsuba_section(m, &points)?);
        }
        report.push_str(&defaults_section(&points));
        report.push_str(&gpu_machine_section(args.report.as_deref()));
        report.push_str(&web_section(args.report.as_deref()));
    }
    // The suite's section comes from its own run: keep it.
    if let Some(section) = args.report.as_deref().and_then(super::suite::existing_section) {
        report.push_str(&section);
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
