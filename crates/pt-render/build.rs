//! Compiles the rust-gpu kernel crate (`shaders-rs/pt-kernel`) to SPIR-V.
//!
//! `cargo-gpu-install` installs the pinned nightly toolchain and builds the
//! rust-gpu codegen backend on first use (cached in the user cache
//! directory), so a fresh machine needs no manual step. The path of the
//! resulting module reaches the crate as `PT_KERNEL_SPV`, and the module is
//! embedded with `include_bytes!`.

use std::path::PathBuf;

use cargo_gpu_install::install::Install;
use cargo_gpu_install::spirv_builder::{ShaderPanicStrategy, SpirvMetadata};

fn main() -> anyhow::Result<()> {
    // Read at run time, not baked in with `env!`: cargo shares one compiled
    // build script between checkouts that use the same target directory
    // (its hashes of workspace paths are relative), and a baked-in path
    // would build another checkout's kernel.
    let manifest_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR")?);
    let kernel_crate = manifest_dir.join("../../shaders-rs/pt-kernel");

    let install = Install::from_shader_crate(kernel_crate.clone()).run()?;
    let mut builder = install.to_spirv_builder(kernel_crate, "spirv-unknown-vulkan1.2");
    builder.build_script.defaults = true;
    // A panic (an out-of-bounds index) ends the invocation instead of
    // hanging or trapping the device.
    builder.shader_panic_strategy = ShaderPanicStrategy::SilentExit;
    // Names of types and members stay in the module: the layout test reads
    // them back to check that host and kernel agree on every offset.
    builder.spirv_metadata = SpirvMetadata::NameVariables;

    let result = builder.build()?;
    let spv = result.module.unwrap_single();
    println!("cargo::rustc-env=PT_KERNEL_SPV={}", spv.display());
    Ok(())
}
