//! `cargo run -p shader-build [-- --check]`: rebuilds the kernel's committed
//! SPIR-V module and manifest (`shaders-rs/compiled/`), or with `--check`
//! rebuilds it and fails on any difference from the committed files,
//! writing nothing.

use std::fs;
use std::process::ExitCode;

use anyhow::Context;
use shader_build::compile::compile;
use shader_build::{MANIFEST_PATH, MODULE_PATH, workspace_root};

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<ExitCode> {
    let check = match std::env::args().skip(1).collect::<Vec<_>>().as_slice() {
        [] => false,
        [flag] if flag == "--check" => true,
        _ => {
            eprintln!("usage: cargo run -p shader-build [-- --check]");
            return Ok(ExitCode::from(2));
        }
    };
    let root = workspace_root()?;
    eprintln!("compiling the kernel with rust-gpu (the first run installs its toolchain and backend: minutes)");
    let compiled = compile(&root, false)?;
    let manifest_text = compiled.manifest.to_toml();
    let (module_path, manifest_path) = (root.join(MODULE_PATH), root.join(MANIFEST_PATH));
    let same_module = fs::read(&module_path).ok().as_deref() == Some(compiled.module.as_slice());
    let same_manifest = fs::read_to_string(&manifest_path).ok().as_deref() == Some(manifest_text.as_str());
    let summary = format!(
        "{} bytes, {} entry points, rust-gpu {} on {}",
        compiled.module.len(),
        compiled.manifest.entry_points.len(),
        compiled.manifest.rust_gpu,
        compiled.manifest.toolchain
    );

    if check {
        if same_module && same_manifest {
            println!("{MODULE_PATH} and {MANIFEST_PATH} match a rebuild from source ({summary})");
            return Ok(ExitCode::SUCCESS);
        }
        for (same, path) in [(same_module, MODULE_PATH), (same_manifest, MANIFEST_PATH)] {
            if !same {
                eprintln!("differs from a rebuild from source: {path}");
            }
        }
        if !same_manifest && let Ok(old) = shader_build::manifest::Manifest::read(&manifest_path) {
            for line in old.stale_inputs(&compiled.manifest.inputs) {
                eprintln!("  {line}");
            }
        }
        eprintln!("rebuild with `{}` and commit both files", shader_build::REBUILD_COMMAND);
        return Ok(ExitCode::FAILURE);
    }

    if let Some(dir) = module_path.parent() {
        fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    // Module first: a manifest never describes a module that is not there.
    fs::write(&module_path, &compiled.module).with_context(|| format!("writing {}", module_path.display()))?;
    fs::write(&manifest_path, manifest_text).with_context(|| format!("writing {}", manifest_path.display()))?;
    let what = if same_module && same_manifest { "unchanged" } else { "written" };
    println!("{MODULE_PATH} and {MANIFEST_PATH} {what} ({summary})");
    Ok(ExitCode::SUCCESS)
}
