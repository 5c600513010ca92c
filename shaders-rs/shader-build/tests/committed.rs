//! The committed kernel module is what its sources build: a change to the
//! kernel crate, to pt-core, to their manifests or to the locked versions of
//! their dependencies, without a rebuild, fails here and names the command
//! that rebuilds it. (CI also rebuilds the module with rust-gpu and compares
//! the bytes; this test needs stable Rust only.)

use std::collections::BTreeSet;

use shader_build::inputs::{KERNEL_CRATES, closure_workspace_crates, collect, sha256_hex};
use shader_build::manifest::Manifest;
use shader_build::{MANIFEST_PATH, MODULE_PATH, REBUILD_COMMAND, workspace_root};

#[test]
fn committed_kernel_matches_its_sources() {
    let root = workspace_root().unwrap();
    let manifest = Manifest::read(&root.join(MANIFEST_PATH)).unwrap();
    let stale = manifest.stale_inputs(&collect(&root).unwrap());
    assert!(
        stale.is_empty(),
        "the committed kernel module ({MODULE_PATH}) is stale; its inputs moved:\n  {}\n\
         rebuild it with `{REBUILD_COMMAND}` and commit {MODULE_PATH} and {MANIFEST_PATH}",
        stale.join("\n  ")
    );
}

#[test]
fn committed_module_is_the_one_its_manifest_describes() {
    let root = workspace_root().unwrap();
    let manifest = Manifest::read(&root.join(MANIFEST_PATH)).unwrap();
    let module = std::fs::read(root.join(MODULE_PATH)).unwrap();
    assert_eq!(module.len() as u64, manifest.module_bytes, "{MODULE_PATH} is not the module {MANIFEST_PATH} describes");
    assert_eq!(
        sha256_hex(&module),
        manifest.module_sha256,
        "{MODULE_PATH} is not the module {MANIFEST_PATH} describes; rebuild both with `{REBUILD_COMMAND}`"
    );
}

/// Case: a new path dependency of the kernel would build into the module
/// without being hashed; the crates hashed must be the lock file's closure.
#[test]
fn hashed_crates_are_the_kernel_closure() {
    let root = workspace_root().unwrap();
    let mut hashed = BTreeSet::new();
    for dir in KERNEL_CRATES {
        let manifest: toml::Table =
            std::fs::read_to_string(root.join(dir).join("Cargo.toml")).unwrap().parse().unwrap();
        hashed.insert(manifest["package"]["name"].as_str().unwrap().to_string());
    }
    assert_eq!(closure_workspace_crates(&root).unwrap(), hashed);
}

/// Case: pt-render's build script embeds the file this crate writes.
#[test]
fn build_script_embeds_the_committed_module() {
    let root = workspace_root().unwrap();
    let build_rs = std::fs::read_to_string(root.join("crates/pt-render/build.rs")).unwrap();
    assert!(build_rs.contains(&format!("const COMMITTED_MODULE: &str = \"{MODULE_PATH}\";")));
}
