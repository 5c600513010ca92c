//! The `pathtracer` binary end to end: bad input gets a message naming the
//! file, line and field, a non-zero exit and no output file; good input
//! renders on both backends.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use pt_render::scene::DEFAULT_SCENE_TOML;

fn pathtracer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pathtracer")).args(args).output().expect("run pathtracer")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes the default scene with `from` replaced by `to` into `dir`.
fn scene_with(dir: &Path, from: &str, to: &str) -> PathBuf {
    assert!(DEFAULT_SCENE_TOML.contains(from));
    let path = dir.join("scene.toml");
    std::fs::write(&path, DEFAULT_SCENE_TOML.replacen(from, to, 1)).unwrap();
    path
}

/// "scene.toml:N:" for the line of the default scene that holds `needle`.
fn at_line_of(needle: &str) -> String {
    let line = DEFAULT_SCENE_TOML[..DEFAULT_SCENE_TOML.find(needle).unwrap()].matches('\n').count() + 1;
    format!("scene.toml:{line}:")
}

/// Runs a render that must fail, and checks the message and that no output
/// file (nor a temporary one) was left behind.
fn assert_fails(dir: &Path, args: &[&str], expected: &[&str]) {
    let out = dir.join("out.png");
    let mut all = vec!["render", "--width", "8", "--height", "8", "--spp", "1", "--backend", "cpu"];
    if !args.contains(&"--out") {
        all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    }
    all.extend_from_slice(args);
    let o = pathtracer(&all);
    let err = stderr(&o);
    assert!(!o.status.success(), "expected failure for {args:?}");
    for e in expected {
        assert!(err.contains(e), "message for {args:?} lacks {e:?}: {err}");
    }
    let left: Vec<_> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name()).filter(|n| n != "scene.toml").collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

#[test]
fn syntax_error_names_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), "[light]", "[light");
    assert_fails(dir.path(), &["--scene", scene.to_str().unwrap()], &[&at_line_of("[light]")]);
}

#[test]
fn negative_radius_names_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), "radius = 0.28", "radius = -0.28");
    assert_fails(
        dir.path(),
        &["--scene", scene.to_str().unwrap()],
        &[&at_line_of("radius = 0.28"), "spheres[1].radius"],
    );
}

#[test]
fn degenerate_wall_names_the_wall() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), "edge_u = [2.0, 0.0, 0.0]", "edge_u = [0.0, 0.0, 0.0]");
    assert_fails(dir.path(), &["--scene", scene.to_str().unwrap()], &["walls[0].edge_v", "zero area"]);
}

#[test]
fn nan_names_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), "radiance = [20.0, 20.0, 20.0]", "radiance = [20.0, nan, 20.0]");
    assert_fails(dir.path(), &["--scene", scene.to_str().unwrap()], &["light.radiance", "finite"]);
}

#[test]
fn unknown_field_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), "vfov_degrees = 40.0", "vfov_degrees = 40.0\nfocal = 3");
    assert_fails(dir.path(), &["--scene", scene.to_str().unwrap()], &["scene.toml:", "focal"]);
}

#[test]
fn missing_scene_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(dir.path(), &["--scene", "/nonexistent/room.toml"], &["/nonexistent/room.toml"]);
}

#[test]
fn non_positive_size_and_spp_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(dir.path(), &["--width", "0"], &["--width"]);
    assert_fails(dir.path(), &["--height=-4"], &["--height"]);
    assert_fails(dir.path(), &["--spp", "0"], &["--spp"]);
}

#[test]
fn unwritable_or_unknown_output_is_rejected_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(dir.path(), &["--out", "/nonexistent-dir/x.png"], &["/nonexistent-dir/x.png"]);
    let bad = dir.path().join("image.bmp");
    assert_fails(dir.path(), &["--out", bad.to_str().unwrap()], &["image.bmp", ".png"]);
}

/// Renders an EXR on `backend` and checks its size and a plausible mean.
fn renders_exr(backend: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("img.exr");
    let o = pathtracer(&[
        "render",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "8",
        "--backend",
        backend,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("samples per second"), "{text}");
    assert!(text.contains("non-finite samples: 0"), "{text}");
    let (w, h, px) = pt_render::output::read_exr(&out).unwrap();
    assert_eq!((w, h), (24, 16));
    // The top-centre pixels look at the light (radiance 20) or the
    // ceiling; every pixel is finite and non-negative, and the image is lit.
    assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    let mean: f32 = px.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / (3 * px.len()) as f32;
    assert!(mean > 0.05 && mean < 5.0, "mean radiance {mean}");
}

#[test]
fn renders_exr_on_cpu() {
    renders_exr("cpu");
}

#[test]
fn renders_exr_on_gpu() {
    renders_exr("gpu");
}

/// The default backend takes the Vulkan adapter when it is hardware, and
/// the CPU beside a software one (lavapipe, as in CI) where the CPU
/// renderer runs eight pixels at a time: the faster on the same cores.
#[test]
fn auto_backend_prefers_the_cpu_to_a_software_adapter() {
    let ctx = pt_render::GpuContext::new().expect("a Vulkan adapter: scripts/test.sh installs lavapipe");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("img.exr");
    let o = pathtracer(&["render", "--width", "8", "--height", "8", "--spp", "1", "--out", out.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let cpu = ctx.is_software() && pt_render::cpu::lanes_available();
    assert_eq!(err.contains("rendering on the CPU, which is faster here"), cpu, "{err}");
    assert_eq!(err.contains("\nCPU: "), cpu, "{err}");
    assert_eq!(err.contains(&format!("GPU: {}", ctx.adapter_description())), !cpu, "{err}");
}

#[test]
fn renders_png_of_the_requested_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("img.png");
    let o = pathtracer(&["render", "--width", "20", "--height", "10", "--spp", "2", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // IHDR: width and height, big-endian, at bytes 16..24.
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 20);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 10);
}
