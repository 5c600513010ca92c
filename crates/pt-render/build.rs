//! Chooses the SPIR-V kernel module that pt-render embeds:
//! - by default the committed module, `shaders-rs/compiled/pt_kernel.spv`,
//!   so that building the renderer needs stable Rust alone;
//! - `PT_KERNEL_SPV=/path/to/module.spv`: a module built elsewhere (for
//!   packagers; a relative path is read from the workspace root);
//! - the `build-kernel` feature: the kernel compiled from source now, with
//!   rust-gpu (for kernel authors: edit pt-core, run the viewer).
//!
//! The chosen path reaches the crate as `PT_KERNEL_MODULE`.

use std::path::{Path, PathBuf};

/// The committed module, relative to the workspace root (shader-build's
/// `MODULE_PATH`; a test checks that they agree).
const COMMITTED_MODULE: &str = "shaders-rs/compiled/pt_kernel.spv";

/// The first word of every SPIR-V module, as stored little-endian.
const SPIRV_MAGIC: [u8; 4] = [0x03, 0x02, 0x23, 0x07];

fn main() {
    // Read at run time, not baked in with `env!`: cargo shares one compiled
    // build script between checkouts that use the same target directory.
    let manifest_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let root = manifest_dir.join("../..");
    println!("cargo::rerun-if-env-changed=PT_KERNEL_SPV");

    let module = if let Some(path) = std::env::var_os("PT_KERNEL_SPV") {
        root.join(path)
    } else if cfg!(feature = "build-kernel") {
        build_from_source(&root)
    } else {
        root.join(COMMITTED_MODULE)
    };
    match std::fs::read(&module) {
        Ok(bytes) if bytes.starts_with(&SPIRV_MAGIC) => {}
        Ok(_) => fail(&format!("{} is not a SPIR-V module (wrong magic number)", module.display())),
        Err(e) => fail(&format!("cannot read the kernel module {}: {e}", module.display())),
    }
    println!("cargo::rerun-if-changed={}", module.display());
    println!("cargo::rustc-env=PT_KERNEL_MODULE={}", module.display());
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}

#[cfg(not(feature = "build-kernel"))]
fn build_from_source(_root: &Path) -> PathBuf {
    unreachable!("only called with the build-kernel feature")
}

/// Compiles the kernel with rust-gpu into `OUT_DIR`, and warns when the
/// result differs from the committed module (which the stale-kernel test
/// will then report until `cargo run -p shader-build` updates it).
#[cfg(feature = "build-kernel")]
fn build_from_source(root: &Path) -> PathBuf {
    let compiled = shader_build::compile::compile(root, true).unwrap_or_else(|e| fail(&format!("{e:#}")));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("pt_kernel.spv");
    std::fs::write(&out, &compiled.module).unwrap_or_else(|e| fail(&format!("writing {}: {e}", out.display())));
    if std::fs::read(root.join(COMMITTED_MODULE)).ok().as_deref() != Some(compiled.module.as_slice()) {
        println!(
            "cargo::warning=the kernel built from source differs from the committed {COMMITTED_MODULE}; \
             run `{}` before committing",
            shader_build::REBUILD_COMMAND
        );
    }
    out
}
