//! `pathtracer render`: a scene to a PNG or EXR file, with a progress bar.

use std::time::Duration;

use anyhow::{Context, Result};
use pt_core::params::{TONEMAP_ACES, TONEMAP_CLAMP};
use pt_render::output::{self, OutputFormat};
use pt_render::renderer::{TiledRender, device_tiles, render_tiled};
use pt_render::{Device, GpuContext, RenderSettings};

use super::{load_scene, spp_progress_bar};
use crate::{BackendArg, RenderArgs, SamplerArg, TonemapArg};

/// Renders the scene to the output file.
pub(crate) fn run(args: &RenderArgs) -> Result<()> {
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
    // The context outlives the renderer made on it.
    let ctx = match args.backend {
        BackendArg::Gpu => Some(GpuContext::new().context("cannot start the GPU renderer")?),
        BackendArg::Cpu => None,
        BackendArg::Auto => {
            GpuContext::new().inspect_err(|e| eprintln!("GPU unavailable ({e}); rendering on the CPU")).ok()
        }
    };
    let device = ctx.as_ref().map_or(Device::Cpu, Device::Gpu);
    let display = (format == OutputFormat::Png).then_some((args.exposure, tonemap));
    let render = |device: Device<'_>| -> Result<TiledRender> {
        let tiles = device_tiles(device, settings.width, settings.height);
        eprintln!("{}", device.description());
        eprintln!(
            "rendering {}x{}, {} spp, max {} bounces, seed {}{}",
            settings.width,
            settings.height,
            settings.spp,
            settings.max_bounces,
            args.seed,
            if tiles.len() > 1 { format!(", in {} tiles of rows", tiles.len()) } else { String::new() }
        );
        let spp = settings.spp as u64;
        let bar = spp_progress_bar(settings.spp.saturating_mul(tiles.len() as u32));
        bar.enable_steady_tick(Duration::from_millis(200));
        let result = render_tiled(
            device,
            params,
            &walls,
            &spheres,
            settings.spp,
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

    match (format, image.display) {
        (OutputFormat::Png, Some(rgba)) => output::write_png(&args.out, settings.width, settings.height, &rgba)?,
        _ => output::write_exr(&args.out, settings.width, settings.height, &output::mean_radiance(&image.accum))?,
    }
    println!("adapter: {}", device.description());
    println!("time: {:.3} s", stats.elapsed.as_secs_f64());
    println!("samples per second: {:.3e}", stats.samples_per_second());
    println!("non-finite samples: {}", stats.non_finite);
    println!("wrote {}", args.out.display());
    Ok(())
}
