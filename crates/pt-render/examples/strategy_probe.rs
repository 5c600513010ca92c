//! Compares sampling strategies on one scene by relMSE per sample and time
//! per sample, without the noise of a time-to-error curve: each strategy
//! renders `SPP` samples per pixel from scratch on `SEEDS` seeds, in turn,
//! and the report gives relMSE times spp (the variance per sample, which
//! is what the strategy changes) and milliseconds per spp; their product
//! over 1e-3 estimates the time to relMSE 1e-3. docs/ARCHITECTURE.md
//! ("Per-scene defaults") used it on the rooms of `scripts/random_rooms.py`.
//!
//! ```text
//! cargo run --release -p pt-render --example strategy_probe -- \
//!     SCENE.toml REFERENCE.exr SPP SEEDS cpu|gpu g0,g10,g25,c0,c10,c25
//! ```
//!
//! The reference sets the image size (`pathtracer render --width 128
//! --height 128 --spp 8192 --out REFERENCE.exr`). The strategies: the glow
//! lobe off, at a tenth or at a quarter (`g0`, `g10`, `g25`), each with
//! connections (`c0`, `c10`, `c25`), on top of the project's base flags
//! with the scene's own light-edge bit; `def` for the scene's default;
//! the bench's one-flag changes to the default (`mis` for NEE with MIS,
//! `cv`, `edge`, `sobol` and `proj` for NEE's control variate, the light
//! edge's, Sobol for every draw and NEE by projected solid angle, each
//! switched); or flags in hex. A `*` marks the strategy that is the scene's default.
//! The header gives the scene's features that the default rule reads and
//! the glow-lobe pilot's figures (`strategy::glow_pilot`).

use std::error::Error;
use std::path::Path;
use std::time::Instant;

use pt_core::params::{
    FLAG_CONNECT, FLAG_GLOW, FLAG_GLOW_SPARSE, FLAG_LIGHT_EDGE, FLAG_MIS, FLAG_NEE_CONTROL, FLAG_NEE_PROJECTED,
    FLAG_SOBOL_DEEP,
};
use pt_render::gpu::GpuContext;
use pt_render::strategy as st;
use pt_render::{Device, RenderSettings, Renderer, Scene, metrics, output};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, scene, reference, spp, seeds, backend, strategies] = args.as_slice() else {
        return Err("usage: strategy_probe SCENE.toml REFERENCE.exr SPP SEEDS cpu|gpu STRATEGY,...".into());
    };
    let scene = Scene::load(Path::new(scene))?;
    let (width, height, reference) = output::read_exr(Path::new(reference))?;
    let (spp, seeds): (u32, u32) = (spp.parse()?, seeds.parse()?);
    let settings = RenderSettings { width, height, ..scene.render };
    let ctx = if backend == "gpu" { Some(GpuContext::new()?) } else { None };
    let device = ctx.as_ref().map_or(Device::Cpu, Device::Gpu);
    let default = scene.default_flags();
    let base = (st::BASE_FLAGS & !FLAG_LIGHT_EDGE) | (default & FLAG_LIGHT_EDGE);
    let connected = FLAG_CONNECT | FLAG_SOBOL_DEEP;
    let flags = |name: &str| -> Result<u32, Box<dyn Error>> {
        Ok(match name {
            "def" => default,
            "g0" => base & !FLAG_GLOW,
            "g10" => base | FLAG_GLOW_SPARSE,
            "g25" => base,
            "c0" => (base & !FLAG_GLOW) | connected,
            "c10" => base | FLAG_GLOW_SPARSE | connected,
            "c25" => base | connected,
            "mis" => default | FLAG_MIS,
            "cv" => default ^ FLAG_NEE_CONTROL,
            "edge" => default ^ FLAG_LIGHT_EDGE,
            "sobol" => default ^ FLAG_SOBOL_DEEP,
            "proj" => default ^ FLAG_NEE_PROJECTED,
            hex => u32::from_str_radix(hex.trim_start_matches("0x"), 16)?,
        })
    };
    let same = |a: u32, b: u32| st::sample_flags(a) == st::sample_flags(b);
    println!(
        "default flags {default:#x} sphere_spot {:.1} wall_spot {:.1} corner {:.1} wall_share {:.3} extent {:.4} clearance {:.2}",
        st::sphere_hot_spot(&scene),
        st::hottest_wall_spot(&scene),
        st::corner_hot_spot(&scene),
        st::wall_share(&scene),
        st::light_extent(&scene),
        st::surface_clearance(&scene),
    );
    if let Some(p) = st::glow_pilot(&scene) {
        println!(
            "pilot relMSE*spp: no lobe {:.4}, a tenth {:.3}x and a quarter {:.3}x of it",
            p.none,
            p.tenth / p.none,
            p.quarter / p.none
        );
    }
    let beside = base | FLAG_CONNECT | FLAG_SOBOL_DEEP;
    if st::connections_apply(&scene)
        && let Some(r) = st::pilot_relmse(&scene, &[beside | FLAG_GLOW_SPARSE, beside])
    {
        println!("pilot beside connections: a tenth {:.4}, a quarter {:.3}x of it", r[0], r[1] / r[0]);
    }
    let names: Vec<&str> = strategies.split(',').collect();
    let all: Vec<u32> = names.iter().map(|n| flags(n)).collect::<Result<_, _>>()?;
    let (walls, spheres) = (scene.gpu_walls(), scene.gpu_spheres());
    let render = |f: u32, seed: u32, spp: u32| -> Result<(f64, f64), Box<dyn Error>> {
        let params = scene.frame_params_with_flags(&settings, 64, seed, f);
        let mut r = Renderer::new(device, params, &walls, &spheres)?;
        let start = Instant::now();
        let mut done = 0;
        while done < spp {
            let n = 64.min(spp - done);
            r.frame(n);
            done += n;
        }
        r.wait()?;
        let time = start.elapsed().as_secs_f64();
        let image = output::mean_radiance(&r.accum()?);
        Ok((metrics::rel_mse(&image, &reference), time))
    };
    // Untimed first: a driver may compile a pipeline at its first dispatch.
    for &f in &all {
        render(f, 99, 64.min(spp))?;
    }
    let mut sums = vec![(0.0, 0.0); all.len()];
    // Seeds outer, strategies inner: drift in the machine's speed falls on
    // every strategy alike.
    for seed in 0..seeds {
        for (sum, &f) in sums.iter_mut().zip(&all) {
            let (e, t) = render(f, 1000 + seed, spp)?;
            *sum = (sum.0 + e / seeds as f64, sum.1 + t / seeds as f64);
        }
    }
    for ((name, &f), (e, t)) in names.iter().zip(&all).zip(sums) {
        let (variance, per_spp) = (e * spp as f64, t / spp as f64);
        println!(
            "{name:>5}{} flags {f:#06x}: relMSE*spp {variance:.4}  ms/spp {:.3}  time to 1e-3 {:.3} s",
            if same(f, default) { "*" } else { " " },
            per_spp * 1e3,
            variance / 1e-3 * per_spp,
        );
    }
    Ok(())
}
