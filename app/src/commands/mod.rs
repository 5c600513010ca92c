//! The implementations of `pathtracer`'s commands; the CLI that parses their
//! arguments and dispatches to them is in `main.rs`.

pub mod accuracy;
pub mod bench;
pub mod compare;
pub mod merge;
pub mod render;
pub mod suite;
pub mod view;

use std::path::PathBuf;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use pt_render::Scene;

/// The scene of `--scene`, else the built-in default scene.
pub(crate) fn load_scene(path: Option<&PathBuf>) -> Result<Scene> {
    Ok(match path {
        Some(p) => Scene::load(p)?,
        None => Scene::default_scene(),
    })
}

pub(crate) fn rayon_threads() -> usize {
    rayon::current_num_threads()
}

/// "model name, N cores" of this machine (from /proc/cpuinfo where present).
pub(crate) fn machine_description() -> String {
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

/// A progress bar over `spp` samples per pixel, with elapsed time and ETA.
pub(crate) fn spp_progress_bar(spp: u32) -> ProgressBar {
    let bar = ProgressBar::new(spp as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed_precise} (eta {eta})")
            .expect("valid progress template"),
    );
    bar
}
