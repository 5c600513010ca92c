//! The path tracer's GPU kernel as a committed artefact.
//!
//! `shaders-rs/pt-kernel` compiles to SPIR-V only with rust-gpu's codegen
//! backend, which needs a pinned nightly toolchain and about ten minutes to
//! build. Users of the renderer never change the kernel, so its module is
//! committed at [`MODULE_PATH`] and the app embeds that file: building,
//! running and testing the app takes stable Rust alone.
//!
//! Beside the module, [`MANIFEST_PATH`] records what made it (rust-gpu
//! version, toolchain, target, entry points) and a SHA-256 of every input
//! that goes into it ([`inputs`]). A test recomputes those hashes, so a
//! change to the kernel or to pt-core without a rebuild fails the test
//! suite and names [`REBUILD_COMMAND`].
//!
//! - [`inputs`]: which files and lock entries the module depends on.
//! - [`manifest`]: the manifest file, written byte for byte the same for the
//!   same inputs.
//! - [`compile`]: the rust-gpu build itself (installs the pinned toolchain
//!   and the codegen backend on first use).

pub mod compile;
pub mod inputs;
pub mod manifest;

use std::path::{Path, PathBuf};

/// The committed SPIR-V module, relative to the workspace root.
pub const MODULE_PATH: &str = "shaders-rs/compiled/pt_kernel.spv";

/// The committed manifest, relative to the workspace root.
pub const MANIFEST_PATH: &str = "shaders-rs/compiled/manifest.toml";

/// The one command that rebuilds the committed module and manifest.
pub const REBUILD_COMMAND: &str = "cargo run -p shader-build";

/// The workspace root: the nearest directory above `CARGO_MANIFEST_DIR`
/// that holds `Cargo.lock` and the kernel crate. Read at run time (cargo
/// sets the variable for `cargo run`, `cargo test` and build scripts): a
/// path baked in at compile time would point at another checkout when two
/// share one target directory.
pub fn workspace_root() -> anyhow::Result<PathBuf> {
    let dir = std::env::var_os("CARGO_MANIFEST_DIR")
        .ok_or_else(|| anyhow::anyhow!("CARGO_MANIFEST_DIR is not set: run this through cargo ({REBUILD_COMMAND})"))?;
    Path::new(&dir)
        .ancestors()
        .find(|d| d.join("Cargo.lock").is_file() && d.join(inputs::KERNEL_CRATES[0]).is_dir())
        .map(Path::to_path_buf)
        .ok_or_else(|| {
            anyhow::anyhow!(
                "no workspace root with Cargo.lock and the kernel crate above {}",
                Path::new(&dir).display()
            )
        })
}
