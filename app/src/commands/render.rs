//! `pathtracer render`: a scene to a PNG or EXR file, with a progress bar.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use pt_render::GpuRenderer;
use pt_render::output::{self, OutputFormat};
use pt_render::parts;
use pt_render::renderer::{TiledRender, device_tiles, render_tiled};
use pt_render::{Device, GpuContext, RenderSettings};

use super::{load_scene, spp_progress_bar};
use crate::{BackendArg, RenderArgs, SamplerArg};

/// Renders the scene to the output file.
pub(crate) fn run(args: &RenderArgs) -> Result<()> {
    if !args.exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    // Everything the user gave is checked before any work starts, and the
    // output's folder must take a file: a bad argument never costs a render.
    let split = match args.parts {
        Some(parts) => Some((part_index(args.part, parts)?, parts)),
        None if args.part.is_some() => anyhow::bail!("--part needs --parts: how many parts the render is cut into"),
        None => None,
    };
    let out = match split {
        Some((part, _)) => PathBuf::from(args.out.to_string_lossy().replace("{part}", &part.to_string())),
        None => args.out.clone(),
    };
    let format = output::check_writable(&out)?;
    if split.is_some() != (format == OutputFormat::Part) {
        anyhow::bail!(
            "{}: a split render (--parts) writes a .{} file, and only a split render does",
            out.display(),
            parts::EXTENSION
        );
    }
    let scene = load_scene(args.scene.as_ref())?;
    let settings = RenderSettings {
        width: args.width.unwrap_or(scene.render.width),
        height: args.height.unwrap_or(scene.render.height),
        spp: args.spp.unwrap_or(scene.render.spp),
        max_bounces: args.max_bounces.unwrap_or(scene.render.max_bounces),
        rr_start: scene.render.rr_start,
    };
    let tonemap = args.tonemap.code();
    let mut params = scene.frame_params(&settings, args.spp_per_frame, args.seed);
    let (walls, spheres) = (scene.gpu_walls(), scene.gpu_spheres());
    let samples = match split {
        Some((part, parts)) => parts::part_samples(settings.spp, args.spp_per_frame, part, parts),
        None => 0..settings.spp,
    };
    // The context outlives the renderer made on it.
    let ctx = match args.backend {
        BackendArg::Gpu => Some(GpuContext::new().context("cannot start the GPU renderer")?),
        BackendArg::Cpu => None,
        BackendArg::Auto => match GpuContext::new() {
            // A software adapter (lavapipe) runs on the same cores as the
            // CPU renderer, which is faster there when it runs eight
            // pixels at a time (docs/PERFORMANCE.md, the scene suite).
            Ok(ctx) if ctx.is_software() && pt_render::cpu::lanes_available() => {
                eprintln!("the Vulkan adapter is a software one; rendering on the CPU, which is faster here");
                None
            }
            Ok(ctx) => Some(ctx),
            Err(e) => {
                eprintln!("GPU unavailable ({e}); rendering on the CPU");
                None
            }
        },
    };
    let device = ctx.as_ref().map_or(Device::Cpu, Device::Gpu);
    // `params` has the scene's default strategy, the same on every backend,
    // so the parts of a split render, on whatever machines they run, render
    // alike.
    match args.sampler {
        SamplerArg::Sobol => params.flags |= pt_core::params::FLAG_SOBOL,
        SamplerArg::Independent => params.flags &= !pt_core::params::FLAG_SOBOL,
    }
    let display = (format == OutputFormat::Png).then_some((args.exposure, tonemap));
    let render = |device: Device<'_>| -> Result<TiledRender> {
        let tiles = device_tiles(device, settings.width, settings.height);
        eprintln!("{}", device.description());
        if let Device::Gpu(ctx) = device
            && let Some(notice) = GpuRenderer::general_kernel_notice(&scene, GpuRenderer::default_trace_kernel(ctx))
        {
            eprintln!("{notice}");
        }
        eprintln!(
            "rendering {}x{}, {} spp, max {} bounces, seed {}{}{}",
            settings.width,
            settings.height,
            settings.spp,
            settings.max_bounces,
            args.seed,
            match split {
                Some((part, parts)) => format!(", part {part} of {parts}: samples {}..{}", samples.start, samples.end),
                None => String::new(),
            },
            if tiles.len() > 1 { format!(", in {} tiles of rows", tiles.len()) } else { String::new() }
        );
        let spp = samples.len() as u64;
        let bar = spp_progress_bar((spp as u32).saturating_mul(tiles.len() as u32));
        bar.enable_steady_tick(Duration::from_millis(200));
        let result = render_tiled(
            device,
            params,
            &walls,
            &spheres,
            samples.clone(),
            args.spp_per_frame,
            &tiles,
            display,
            |tile, done| bar.set_position(tile as u64 * spp + done as u64),
        );
        bar.finish_and_clear();
        Ok(result?)
    };
    let (device, image) = match (args.backend, render(device)) {
        (_, Ok(image)) => (device, image),
        (BackendArg::Auto, Err(e)) if ctx.is_some() => {
            eprintln!("GPU render failed ({e:#}); rendering on the CPU");
            (Device::Cpu, render(Device::Cpu)?)
        }
        (_, Err(e)) => return Err(e).context("rendering failed"),
    };
    let stats = image.stats;

    match (format, image.display, split) {
        (OutputFormat::Png, Some(rgba), _) => output::write_png(&out, settings.width, settings.height, &rgba)?,
        (OutputFormat::Part, _, Some((part, parts))) => {
            let header = parts::PartHeader {
                render: parts::render_hash(&scene, &settings, args.seed, args.spp_per_frame, params.flags),
                width: settings.width,
                height: settings.height,
                spp: settings.spp,
                first_sample: samples.start,
                end_sample: samples.end,
                part,
                parts,
            };
            parts::write_part(&out, &header, &image.accum)?;
        }
        _ => output::write_exr(&out, settings.width, settings.height, &output::mean_radiance(&image.accum))?,
    }
    println!("adapter: {}", device.description());
    println!("time: {:.3} s", stats.elapsed.as_secs_f64());
    println!("samples per second: {:.3e}", stats.samples_per_second());
    println!("non-finite samples: {}", stats.non_finite);
    println!("wrote {}", out.display());
    Ok(())
}

/// The index of this process's part of a render cut into `parts`: `--part`,
/// else the index its cluster engine gives the task, `JOB_COMPLETION_INDEX`
/// (Kubernetes Indexed Jobs, from 0) or `SLURM_ARRAY_TASK_ID` (Slurm job
/// arrays, counted from `SLURM_ARRAY_TASK_MIN`).
fn part_index(part: Option<u32>, parts: u32) -> Result<u32> {
    let from_env = |name: &str| -> Result<Option<u32>> {
        std::env::var(name)
            .ok()
            .map(|v| v.trim().parse::<u32>().with_context(|| format!("{name}={v:?} is not a part index")))
            .transpose()
    };
    let index = match part {
        Some(k) => k,
        None => match (from_env("JOB_COMPLETION_INDEX")?, from_env("SLURM_ARRAY_TASK_ID")?) {
            (Some(k), _) => k,
            (None, Some(id)) => id
                .checked_sub(from_env("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0))
                .with_context(|| format!("SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN"))?,
            (None, None) => anyhow::bail!(
                "--parts {parts} needs this part's index: --part K, or JOB_COMPLETION_INDEX (Kubernetes Indexed Job) \
                 or SLURM_ARRAY_TASK_ID (Slurm job array) in the environment"
            ),
        },
    };
    if index >= parts {
        anyhow::bail!("part {index} does not exist in a render cut into {parts} parts (indices 0 to {})", parts - 1);
    }
    Ok(index)
}
