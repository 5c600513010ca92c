//! The manifest committed beside the kernel module: what made the module,
//! and the hashes of what it was made from.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use serde::Deserialize;

use crate::REBUILD_COMMAND;
use crate::inputs::{Inputs, combined_hash};

/// The contents of `manifest.toml`.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// SHA-256 of the module file, hex.
    pub module_sha256: String,
    /// Size of the module file in bytes.
    pub module_bytes: u64,
    /// rust-gpu's version (that of `spirv-std` in Cargo.lock; the codegen
    /// backend is built at the same version).
    pub rust_gpu: String,
    /// The nightly toolchain rust-gpu's codegen backend pins.
    pub toolchain: String,
    /// The SPIR-V target.
    pub target: String,
    /// The module's entry points, sorted.
    pub entry_points: Vec<String>,
    /// [`combined_hash`] of [`Self::inputs`].
    pub source_sha256: String,
    /// Every input of the module and its SHA-256 ([`crate::inputs`]).
    pub inputs: BTreeMap<String, String>,
}

impl Manifest {
    /// Reads a manifest file.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        toml::from_str(&text).with_context(|| format!("parsing {}", path.display()))
    }

    /// The manifest as TOML text, fields in a fixed order: the same manifest
    /// gives the same bytes, so an unchanged rebuild leaves no diff.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        let quote = |v: &str| toml::Value::String(v.to_string()).to_string();
        let _ = writeln!(s, "# The committed kernel module beside this file and what made it.");
        let _ = writeln!(s, "# Written by `{REBUILD_COMMAND}`; do not edit by hand.");
        let _ = writeln!(s, "module_sha256 = {}", quote(&self.module_sha256));
        let _ = writeln!(s, "module_bytes = {}", self.module_bytes);
        let _ = writeln!(s, "rust_gpu = {}", quote(&self.rust_gpu));
        let _ = writeln!(s, "toolchain = {}", quote(&self.toolchain));
        let _ = writeln!(s, "target = {}", quote(&self.target));
        let _ = writeln!(s, "entry_points = [");
        for name in &self.entry_points {
            let _ = writeln!(s, "    {},", quote(name));
        }
        let _ = writeln!(s, "]");
        let _ = writeln!(s, "source_sha256 = {}", quote(&self.source_sha256));
        let _ = writeln!(s);
        let _ = writeln!(s, "[inputs]");
        for (name, digest) in &self.inputs {
            let _ = writeln!(s, "{} = {}", quote(name), quote(digest));
        }
        s
    }

    /// How `current` differs from the inputs this manifest records, one
    /// line per input (changed, new or gone); empty when the module is up to
    /// date.
    pub fn stale_inputs(&self, current: &Inputs) -> Vec<String> {
        let mut lines = Vec::new();
        for (name, digest) in current {
            match self.inputs.get(name) {
                None => lines.push(format!("new:     {name}")),
                Some(old) if old != digest => lines.push(format!("changed: {name}")),
                Some(_) => {}
            }
        }
        for name in self.inputs.keys().filter(|name| !current.contains_key(*name)) {
            lines.push(format!("gone:    {name}"));
        }
        if lines.is_empty() && combined_hash(current) != self.source_sha256 {
            lines.push("source_sha256 does not match the inputs listed".to_string());
        }
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(inputs: &[(&str, &str)]) -> Manifest {
        let inputs: Inputs = inputs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        Manifest {
            module_sha256: "00".into(),
            module_bytes: 4,
            rust_gpu: "0.11.0".into(),
            toolchain: "nightly-2026-08-15".into(),
            target: "spirv-unknown-vulkan1.2".into(),
            entry_points: vec!["a".into(), "b \"q\"".into()],
            source_sha256: combined_hash(&inputs),
            inputs,
        }
    }

    /// Case: what `to_toml` writes, `read` gives back field for field.
    #[test]
    fn toml_round_trip() {
        let m = manifest(&[("crates/pt-core/src/lib.rs", "ab"), ("Cargo.lock: glam 0.34.1", "cd")]);
        let back: Manifest = toml::from_str(&m.to_toml()).unwrap();
        assert_eq!(back, m);
    }

    /// Case: each kind of difference is named with its input; equal inputs
    /// are not stale.
    #[test]
    fn stale_inputs_name_the_input() {
        let m = manifest(&[("a.rs", "1"), ("b.rs", "2"), ("c.rs", "3")]);
        let same: Inputs = m.inputs.clone();
        assert!(m.stale_inputs(&same).is_empty());
        let mut now = same.clone();
        now.insert("a.rs".into(), "9".into());
        now.remove("b.rs");
        now.insert("d.rs".into(), "4".into());
        assert_eq!(m.stale_inputs(&now), ["changed: a.rs", "new:     d.rs", "gone:    b.rs"]);
        let mut tampered = m.clone();
        tampered.source_sha256 = "ff".into();
        assert_eq!(tampered.stale_inputs(&same).len(), 1);
    }
}
