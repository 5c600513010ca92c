//! Split renders run as cluster engines run them: the real binary in
//! separate processes, each taking its part index from the variable its
//! engine sets (`JOB_COMPLETION_INDEX` for a Kubernetes Indexed Job,
//! `SLURM_ARRAY_TASK_ID` for a Slurm job array), then `pathtracer merge`.
//! The merged image is the single render's up to float summation order;
//! wrong or missing parts are errors that write nothing.

use std::path::Path;
use std::process::{Command, Output};

/// A small render: 40x30, 64 spp in frames of 4 (16 frames, 2 per part).
const RENDER: [&str; 12] =
    ["render", "--width", "40", "--height", "30", "--spp", "64", "--spp-per-frame", "4", "--backend", "cpu", "--seed"];

fn pathtracer(args: &[&str], env: &[(&str, String)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pathtracer"));
    cmd.args(args)
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_MIN");
    cmd.envs(env.iter().map(|(k, v)| (*k, v.as_str())));
    cmd.output().expect("run pathtracer")
}

/// Runs the 8 parts of the render with `seed` as concurrent processes,
/// each with the environment `env(k)` gives it, into `dir/part-{part}`.
fn render_parts(dir: &Path, seed: &str, env: impl Fn(u32) -> Vec<(&'static str, String)>) {
    let out = dir.join("part-{part}.ptpart");
    let mut args: Vec<&str> = RENDER.to_vec();
    args.extend([seed, "--parts", "8", "--out", out.to_str().unwrap()]);
    let children: Vec<_> = (0..8)
        .map(|k| {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_pathtracer"));
            cmd.args(&args).env_remove("JOB_COMPLETION_INDEX").env_remove("SLURM_ARRAY_TASK_ID");
            cmd.envs(env(k)).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped());
            cmd.spawn().expect("start a part")
        })
        .collect();
    for child in children {
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "a part failed: {}", String::from_utf8_lossy(&out.stderr));
    }
}

fn parts_in(dir: &Path) -> Vec<String> {
    let mut parts: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path().to_string_lossy().into_owned())
        .filter(|p| p.ends_with(".ptpart"))
        .collect();
    parts.sort();
    parts
}

/// Merges `parts` into `out` and returns the image; the merge must succeed.
fn merge(parts: &[String], out: &Path) -> Vec<[f32; 3]> {
    let mut args = vec!["merge", "--out", out.to_str().unwrap()];
    args.extend(parts.iter().rev().map(String::as_str));
    let o = pathtracer(&args, &[]);
    assert!(o.status.success(), "merge failed: {}", String::from_utf8_lossy(&o.stderr));
    pt_render::output::read_exr(out).unwrap().2
}

/// Case: the merged image equals the single render's to 1e-5 relative per
/// pixel and channel. Both sum the same samples; the single render in a
/// Kahan-compensated f32 sum over frames, the merge in f64 over parts'
/// compensated sums, so they differ by a few f32 ulps of the sum at most.
fn assert_same_image(merged: &[[f32; 3]], single: &[[f32; 3]]) {
    assert_eq!(merged.len(), single.len());
    for (i, (m, s)) in merged.iter().zip(single).enumerate() {
        for c in 0..3 {
            assert!(
                (m[c] - s[c]).abs() <= 1e-5 * (s[c].abs() + 1e-3),
                "pixel {i} channel {c}: {} against {}",
                m[c],
                s[c]
            );
        }
    }
}

#[test]
fn parts_run_as_kubernetes_and_slurm_run_them_merge_into_the_single_render() {
    let dir = tempfile::tempdir().unwrap();
    let single = dir.path().join("single.exr");
    let mut args: Vec<&str> = RENDER.to_vec();
    args.extend(["3", "--out", single.to_str().unwrap()]);
    assert!(pathtracer(&args, &[]).status.success());
    let single = pt_render::output::read_exr(&single).unwrap().2;

    // Kubernetes: completion indices 0 to 7.
    let k8s = dir.path().join("k8s");
    std::fs::create_dir(&k8s).unwrap();
    render_parts(&k8s, "3", |k| vec![("JOB_COMPLETION_INDEX", k.to_string())]);
    let parts = parts_in(&k8s);
    assert_eq!(parts.len(), 8);
    assert_same_image(&merge(&parts, &k8s.join("merged.exr")), &single);

    // Slurm: `--array=1-8`, task ids 1 to 8 from SLURM_ARRAY_TASK_MIN = 1.
    let slurm = dir.path().join("slurm");
    std::fs::create_dir(&slurm).unwrap();
    render_parts(&slurm, "3", |k| {
        vec![("SLURM_ARRAY_TASK_ID", (k + 1).to_string()), ("SLURM_ARRAY_TASK_MIN", "1".to_string())]
    });
    let parts = parts_in(&slurm);
    assert_eq!(parts.len(), 8);
    assert_same_image(&merge(&parts, &slurm.join("merged.exr")), &single);

    // Checked to fail: a merge of the parts of another seed differs.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    render_parts(&other, "4", |k| vec![("JOB_COMPLETION_INDEX", k.to_string())]);
    let merged_other = merge(&parts_in(&other), &other.join("merged.exr"));
    assert!(merged_other.iter().zip(&single).any(|(m, s)| (m[0] - s[0]).abs() > 1e-3));

    // Wrong or missing parts: an error naming the problem, nothing written.
    let out = dir.path().join("bad.exr");
    let failing = |parts: Vec<String>, expected: &str| {
        let mut args = vec!["merge".to_string(), "--out".into(), out.to_string_lossy().into_owned()];
        args.extend(parts);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = pathtracer(&args, &[]);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success() && err.contains(expected), "expected {expected:?} in: {err}");
        assert!(!out.exists(), "a failed merge wrote {}", out.display());
    };
    let k8s_parts = parts_in(&k8s);
    let without_3: Vec<String> = k8s_parts.iter().filter(|p| !p.ends_with("part-3.ptpart")).cloned().collect();
    failing(without_3, "samples 24..32 missing");
    let mut twice = k8s_parts.clone();
    twice.push(k8s_parts[5].clone());
    failing(twice, "samples 40..48 covered twice");
    let mut foreign = k8s_parts.clone();
    foreign[2] = parts_in(&other)[2].clone();
    failing(foreign, "is a part of another render");
    failing(vec![dir.path().join("single.exr").to_string_lossy().into_owned()], "not a pathtracer part file");
}

/// Case: a split render without an index to take is refused before it
/// starts, and so is an index past the last part.
#[test]
fn a_part_without_its_index_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.ptpart");
    let mut args: Vec<&str> = RENDER.to_vec();
    args.extend(["0", "--parts", "4", "--out", out.to_str().unwrap()]);
    let o = pathtracer(&args, &[]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("JOB_COMPLETION_INDEX"));
    let o = pathtracer(&args, &[("JOB_COMPLETION_INDEX", "4".to_string())]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("part 4 does not exist in a render cut into 4 parts"));
    assert!(!o.status.success() && !out.exists());
}

/// Case: the recipes in deploy/ cut the render into as many parts as they
/// run tasks, write parts where their merge reads them, and take the index
/// from their engine (no `--part`).
#[test]
fn deploy_recipes_agree_with_themselves() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    let k8s = read("deploy/kubernetes/render-job.yaml");
    let value = |text: &str, key: &str| -> String {
        let line = text.lines().find(|l| l.trim_start().starts_with(key)).unwrap_or_else(|| panic!("no {key}"));
        line.trim_start()[key.len()..].trim().trim_matches('"').to_string()
    };
    let parts_arg = |text: &str| -> String {
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        let i = lines.iter().position(|l| l.ends_with("--parts")).expect("--parts");
        lines[i + 1].trim_start_matches("- ").trim_matches('"').to_string()
    };
    assert_eq!(value(&k8s, "completions:"), parts_arg(&k8s));
    assert_eq!(value(&k8s, "parallelism:"), parts_arg(&k8s));
    assert_eq!(value(&k8s, "completionMode:"), "Indexed");
    assert!(k8s.contains("/parts/part-{part}.ptpart") && !k8s.contains("--part\n"));
    assert!(read("deploy/kubernetes/merge-job.yaml").contains("pathtracer merge /parts/part-*.ptpart"));

    let slurm = read("deploy/slurm/render.sbatch");
    let array = value(&slurm, "#SBATCH --array=");
    let (lo, hi) = array.split_once('-').unwrap();
    let tasks = hi.parse::<u32>().unwrap() - lo.parse::<u32>().unwrap() + 1;
    assert!(slurm.contains(&format!("--parts {tasks} ")), "--array={array} against the --parts of render.sbatch");
    assert!(slurm.contains("parts/part-{part}.ptpart"));
    assert!(read("deploy/slurm/merge.sbatch").contains("pathtracer merge parts/part-*.ptpart"));
    assert!(read("deploy/slurm/submit.sh").contains("--dependency=afterok:"));
}
