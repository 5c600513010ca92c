//! The rust-gpu build of the kernel crate. This file's contents are an input
//! of the committed module's hash: the options below shape the SPIR-V.

use std::path::Path;

use anyhow::Context;
use cargo_gpu_install::install::Install;
use cargo_gpu_install::spirv_builder::{ShaderPanicStrategy, SpirvMetadata};

use crate::inputs::{KERNEL_CRATES, KERNEL_PACKAGE, collect, combined_hash, locked_version, sha256_hex};
use crate::manifest::Manifest;

/// The SPIR-V target: Vulkan 1.2, which naga reads for every other backend.
pub const TARGET: &str = "spirv-unknown-vulkan1.2";

/// A freshly compiled module and its manifest.
pub struct Compiled {
    /// The SPIR-V module.
    pub module: Vec<u8>,
    /// What made it, and from what.
    pub manifest: Manifest,
}

/// Compiles the kernel crate under workspace root `root`.
///
/// On first use, `cargo-gpu-install` installs the nightly toolchain that
/// rust-gpu's codegen backend pins (through rustup, without a prompt) and
/// builds the backend into the user cache directory (`rust-gpu`): about ten
/// minutes on two cores; later builds take seconds. `in_build_script`
/// makes rust-gpu print cargo's `rerun-if-changed` lines and forward the
/// kernel's warnings as build-script warnings.
pub fn compile(root: &Path, in_build_script: bool) -> anyhow::Result<Compiled> {
    // Hashed before the build: a source edited during the build then shows
    // as stale instead of being recorded as built.
    let inputs = collect(root)?;
    let kernel_crate = root.join(KERNEL_CRATES[0]);
    let mut install = Install::from_shader_crate(kernel_crate.clone());
    if in_build_script {
        install = install.within_build_script();
    }
    let backend = install.run().context("installing rust-gpu's toolchain and codegen backend")?;
    let mut builder = backend.to_spirv_builder(&kernel_crate, TARGET);
    // A panic (an out-of-bounds index) ends the invocation instead of
    // hanging or trapping the device.
    builder.shader_panic_strategy = ShaderPanicStrategy::SilentExit;
    // Names of types and members stay in the module: the layout test reads
    // them back to check that host and kernel agree on every offset.
    builder.spirv_metadata = SpirvMetadata::NameVariables;
    // A warning inside a nested build is easy to miss: make it an error.
    builder.deny_warnings = true;
    let result = builder.build().with_context(|| format!("compiling {KERNEL_PACKAGE} with rust-gpu"))?;
    let path = result.module.unwrap_single();
    let module = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;

    let mut entry_points = result.entry_points.clone();
    entry_points.sort();
    let manifest = Manifest {
        module_sha256: sha256_hex(&module),
        module_bytes: module.len() as u64,
        rust_gpu: locked_version(root, "spirv-std")?,
        toolchain: backend.toolchain_channel.clone(),
        target: TARGET.to_string(),
        entry_points,
        source_sha256: combined_hash(&inputs),
        inputs,
    };
    Ok(Compiled { module, manifest })
}
