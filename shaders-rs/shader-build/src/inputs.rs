//! Everything the kernel module is made from, each input hashed on its own
//! so that a stale module can say which input moved.
//!
//! The inputs are:
//! - every file of the workspace crates compiled into the kernel
//!   ([`KERNEL_CRATES`]: sources and Cargo.toml files);
//! - the part of the workspace Cargo.toml those crates read: package
//!   settings (edition), lints, profiles, and the `[workspace.dependencies]`
//!   entries they name;
//! - the Cargo.lock entries of the kernel's dependency closure (name,
//!   version, source, checksum): spirv-std, glam and the rest;
//! - [`compile`](crate::compile)'s source, which holds the rust-gpu options.
//!
//! Text is hashed with `\r\n` read as `\n`, so that a checkout with Windows
//! line endings agrees with the manifest.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fs;
use std::path::Path;

use anyhow::{Context, bail};
use sha2::{Digest, Sha256};

/// The workspace crates compiled into the kernel, relative to the root; the
/// kernel crate first. A test checks this against the lock file's closure.
pub const KERNEL_CRATES: [&str; 2] = ["shaders-rs/pt-kernel", "crates/pt-core"];

/// The kernel crate's package name, where the lock-file closure starts.
pub const KERNEL_PACKAGE: &str = "pt-kernel";

/// The file that sets the rust-gpu options, relative to the root.
const COMPILE_SOURCE: &str = "shaders-rs/shader-build/src/compile.rs";

/// Input name (a path relative to the root, or a `Cargo.lock:` or
/// `Cargo.toml:` label) to the SHA-256 of its contents, hex.
pub type Inputs = BTreeMap<String, String>;

/// Hashes every input of the kernel module under workspace root `root`.
pub fn collect(root: &Path) -> anyhow::Result<Inputs> {
    let mut inputs = Inputs::new();
    for krate in KERNEL_CRATES {
        let mut files = Vec::new();
        list_files(&root.join(krate), krate, &mut files)?;
        for rel in files {
            inputs.insert(rel.clone(), sha256_hex(&read_text(&root.join(&rel))?));
        }
    }
    inputs.insert(COMPILE_SOURCE.to_string(), sha256_hex(&read_text(&root.join(COMPILE_SOURCE))?));
    inputs.insert(
        "Cargo.toml: workspace settings the kernel crates use".to_string(),
        sha256_hex(workspace_settings(root)?.as_bytes()),
    );
    for (label, entry) in lock_closure(root)? {
        inputs.insert(format!("Cargo.lock: {label}"), sha256_hex(entry.as_bytes()));
    }
    Ok(inputs)
}

/// One hash over all inputs: SHA-256 of `name\tdigest\n` lines in name order.
pub fn combined_hash(inputs: &Inputs) -> String {
    let lines: String = inputs.iter().map(|(name, digest)| format!("{name}\t{digest}\n")).collect();
    sha256_hex(lines.as_bytes())
}

/// SHA-256 of `bytes`, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// The version of `package` in the lock file (the first, if several).
pub fn locked_version(root: &Path, package: &str) -> anyhow::Result<String> {
    lock_packages(root)?
        .iter()
        .find(|p| p.name == package)
        .map(|p| p.version.clone())
        .with_context(|| format!("{package} is not in Cargo.lock"))
}

/// Workspace crates (lock entries without a source) in the kernel's closure.
pub fn closure_workspace_crates(root: &Path) -> anyhow::Result<BTreeSet<String>> {
    let packages = lock_packages(root)?;
    Ok(closure(&packages)?
        .into_iter()
        .filter(|&i| packages[i].source.is_none())
        .map(|i| packages[i].name.clone())
        .collect())
}

/// Bytes of a text file, `\r\n` read as `\n`.
fn read_text(path: &Path) -> anyhow::Result<Vec<u8>> {
    let bytes = fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = Vec::with_capacity(bytes.len());
    for (i, &b) in bytes.iter().enumerate() {
        if !(b == b'\r' && bytes.get(i + 1) == Some(&b'\n')) {
            out.push(b);
        }
    }
    Ok(out)
}

/// Files under `dir` (named `rel` relative to the root), recursively, as
/// `/`-separated relative paths; build output (`target`) is skipped.
fn list_files(dir: &Path, rel: &str, out: &mut Vec<String>) -> anyhow::Result<()> {
    let mut entries: Vec<_> = fs::read_dir(dir)
        .with_context(|| format!("listing {}", dir.display()))?
        .collect::<Result<_, _>>()
        .with_context(|| format!("listing {}", dir.display()))?;
    entries.sort_by_key(|e| e.file_name());
    for entry in entries {
        let name = entry.file_name().to_string_lossy().into_owned();
        let child = format!("{rel}/{name}");
        let kind = entry.file_type()?;
        if kind.is_dir() {
            if name != "target" {
                list_files(&entry.path(), &child, out)?;
            }
        } else {
            out.push(child);
        }
    }
    Ok(())
}

/// The workspace Cargo.toml's settings that reach the kernel crates, as a
/// canonical string (keys sorted), so that host-only dependencies and
/// members can change without touching the kernel's hash.
fn workspace_settings(root: &Path) -> anyhow::Result<String> {
    let path = root.join("Cargo.toml");
    let text = String::from_utf8(read_text(&path)?).context("Cargo.toml is not UTF-8")?;
    let manifest: toml::Table = text.parse().with_context(|| format!("parsing {}", path.display()))?;
    let workspace = manifest.get("workspace").and_then(|w| w.as_table());
    let section = |key: &str| workspace.and_then(|w| w.get(key)).cloned();

    let mut used = BTreeSet::new();
    for krate in KERNEL_CRATES {
        let path = root.join(krate).join("Cargo.toml");
        let text = String::from_utf8(read_text(&path)?).context("Cargo.toml is not UTF-8")?;
        let krate: toml::Table = text.parse().with_context(|| format!("parsing {}", path.display()))?;
        collect_dependency_names(&krate, &mut used);
    }
    let all_deps = section("dependencies").and_then(|d| d.as_table().cloned()).unwrap_or_default();
    let deps: toml::Table = all_deps.into_iter().filter(|(name, _)| used.contains(name)).collect();

    let mut settings = toml::Table::new();
    for key in ["package", "lints"] {
        if let Some(value) = section(key) {
            settings.insert(format!("workspace.{key}"), value);
        }
    }
    settings.insert("workspace.dependencies".into(), toml::Value::Table(deps));
    if let Some(profile) = manifest.get("profile") {
        settings.insert("profile".into(), profile.clone());
    }
    Ok(canonical(&toml::Value::Table(settings)))
}

/// Names of every dependency table entry of a crate manifest, target-
/// specific and build dependencies included.
fn collect_dependency_names(krate: &toml::Table, out: &mut BTreeSet<String>) {
    for key in ["dependencies", "build-dependencies"] {
        if let Some(deps) = krate.get(key).and_then(|d| d.as_table()) {
            out.extend(deps.keys().cloned());
        }
    }
    if let Some(targets) = krate.get("target").and_then(|t| t.as_table()) {
        for target in targets.values().filter_map(|t| t.as_table()) {
            collect_dependency_names(target, out);
        }
    }
}

/// A TOML value as text with table keys in sorted order, whatever map the
/// `toml` crate was built with.
fn canonical(value: &toml::Value) -> String {
    match value {
        toml::Value::Table(table) => {
            let mut keys: Vec<_> = table.keys().collect();
            keys.sort();
            let fields: Vec<String> = keys.iter().map(|k| format!("{k:?}={}", canonical(&table[k.as_str()]))).collect();
            format!("{{{}}}", fields.join(","))
        }
        toml::Value::Array(items) => format!("[{}]", items.iter().map(canonical).collect::<Vec<_>>().join(",")),
        other => other.to_string(),
    }
}

/// One `[[package]]` of Cargo.lock.
struct LockPackage {
    name: String,
    version: String,
    source: Option<String>,
    checksum: Option<String>,
    /// `name`, `name version` or `name version (source)`, as the lock file
    /// writes them.
    dependencies: Vec<String>,
}

fn lock_packages(root: &Path) -> anyhow::Result<Vec<LockPackage>> {
    let path = root.join("Cargo.lock");
    let text = String::from_utf8(read_text(&path)?).context("Cargo.lock is not UTF-8")?;
    let lock: toml::Table = text.parse().with_context(|| format!("parsing {}", path.display()))?;
    let Some(packages) = lock.get("package").and_then(|p| p.as_array()) else {
        bail!("{} has no [[package]] entries", path.display());
    };
    let string = |t: &toml::Table, key: &str| t.get(key).and_then(|v| v.as_str()).map(str::to_string);
    packages
        .iter()
        .map(|p| {
            let t = p.as_table().context("a [[package]] entry of Cargo.lock is not a table")?;
            Ok(LockPackage {
                name: string(t, "name").context("a Cargo.lock package has no name")?,
                version: string(t, "version").context("a Cargo.lock package has no version")?,
                source: string(t, "source"),
                checksum: string(t, "checksum"),
                dependencies: t
                    .get("dependencies")
                    .and_then(|d| d.as_array())
                    .map(|d| d.iter().filter_map(|v| v.as_str().map(str::to_string)).collect())
                    .unwrap_or_default(),
            })
        })
        .collect()
}

/// Indices of the packages reachable from [`KERNEL_PACKAGE`] in the lock
/// file, whatever the target: a superset of what the SPIR-V build links.
fn closure(packages: &[LockPackage]) -> anyhow::Result<BTreeSet<usize>> {
    let find = |spec: &str| -> anyhow::Result<usize> {
        let mut parts = spec.split(' ');
        let name = parts.next().unwrap_or_default();
        let version = parts.next();
        packages
            .iter()
            .position(|p| p.name == name && version.is_none_or(|v| p.version == v))
            .with_context(|| format!("Cargo.lock names `{spec}` as a dependency but has no such package"))
    };
    let mut seen = BTreeSet::new();
    let mut queue = VecDeque::from([find(KERNEL_PACKAGE)?]);
    while let Some(i) = queue.pop_front() {
        if seen.insert(i) {
            for dep in &packages[i].dependencies {
                queue.push_back(find(dep)?);
            }
        }
    }
    Ok(seen)
}

/// `(name version, entry text)` of each package in the kernel's closure.
fn lock_closure(root: &Path) -> anyhow::Result<Vec<(String, String)>> {
    let packages = lock_packages(root)?;
    Ok(closure(&packages)?
        .into_iter()
        .map(|i| {
            let p = &packages[i];
            let label = format!("{} {}", p.name, p.version);
            let entry = format!(
                "{label} source={} checksum={} dependencies={}",
                p.source.as_deref().unwrap_or("workspace"),
                p.checksum.as_deref().unwrap_or("-"),
                p.dependencies.join(";")
            );
            (label, entry)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Case: the SHA-256 test vector of "abc" (FIPS 180-2, appendix B.1).
    #[test]
    fn sha256_of_abc() {
        assert_eq!(sha256_hex(b"abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }

    /// Case: a CRLF checkout hashes like an LF one; a lone CR is content.
    #[test]
    fn crlf_reads_as_lf() {
        let dir = std::env::temp_dir().join(format!("shader-build-crlf-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        fs::write(dir.join("lf"), b"a\nb\n").unwrap();
        fs::write(dir.join("crlf"), b"a\r\nb\r\n").unwrap();
        fs::write(dir.join("cr"), b"a\rb\n").unwrap();
        assert_eq!(read_text(&dir.join("crlf")).unwrap(), b"a\nb\n");
        assert_eq!(read_text(&dir.join("cr")).unwrap(), b"a\rb\n");
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Case: key order in the TOML source does not change the canonical text.
    #[test]
    fn canonical_sorts_keys() {
        let a: toml::Table = "b = 1\na = { y = [1, 2], x = 'q' }".parse().unwrap();
        let b: toml::Table = "a = { x = 'q', y = [1, 2] }\nb = 1".parse().unwrap();
        assert_eq!(canonical(&toml::Value::Table(a.clone())), canonical(&toml::Value::Table(b)));
        let c: toml::Table = "a = { x = 'q', y = [2, 1] }\nb = 1".parse().unwrap();
        assert_ne!(canonical(&toml::Value::Table(a)), canonical(&toml::Value::Table(c)));
    }
}
