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

/// "model name (family F, model M; vector ISA), N logical cores, OS" of
/// this machine (from /proc/cpuinfo where present).
pub(crate) fn machine_description() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo").map_or_else(|_| "unknown CPU".into(), |s| cpu_description(&s));
    format!("{cpu}, {} logical cores, {}", rayon_threads(), std::env::consts::OS)
}

/// The first processor of a /proc/cpuinfo text: its model name, family and
/// model numbers, and its widest vector extension. A shared machine's
/// model name can be as bare as "AMD EPYC", and a renderer that vectorises
/// for the widest one it finds (Mitsuba's Dr.Jit takes AVX-512 where
/// present; lavapipe stays at 256 bits) runs at another speed beside ours
/// on another generation, so comparisons must name it.
pub(crate) fn cpu_description(cpuinfo: &str) -> String {
    let field = |key: &str| {
        cpuinfo
            .lines()
            .find(|l| l.split(':').next().is_some_and(|k| k.trim() == key))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let name = field("model name").unwrap_or_else(|| "unknown CPU".into());
    let flags = field("flags").unwrap_or_default();
    let has = |f: &str| flags.split_whitespace().any(|x| x == f);
    let isa = if has("avx512f") {
        "AVX-512"
    } else if has("avx2") {
        "AVX2, no AVX-512"
    } else if has("avx") {
        "AVX, no AVX2"
    } else {
        "no AVX"
    };
    match (field("cpu family"), field("model")) {
        (Some(f), Some(m)) => format!("{name} (family {f}, model {m}; {isa})"),
        _ if flags.is_empty() => name,
        _ => format!("{name} ({isa})"),
    }
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

#[cfg(test)]
mod tests {
    use super::cpu_description;

    #[test]
    fn the_cpu_description_names_family_model_and_widest_vector_extension() {
        let zen3 = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 1\n\
                    model name\t: AMD EPYC\nflags\t\t: fpu sse2 avx fma avx2 sha_ni\n\nprocessor\t: 1\n";
        assert_eq!(cpu_description(zen3), "AMD EPYC (family 25, model 1; AVX2, no AVX-512)");
        let zen4 = zen3.replace("model\t\t: 1", "model\t\t: 17").replace("avx2", "avx2 avx512f avx512bw");
        assert_eq!(cpu_description(&zen4), "AMD EPYC (family 25, model 17; AVX-512)");
        // "model name" must not be read as "model".
        let old = "model name\t: Old CPU\nflags\t\t: fpu sse2\n";
        assert_eq!(cpu_description(old), "Old CPU (no AVX)");
        assert_eq!(cpu_description(""), "unknown CPU");
    }
}
