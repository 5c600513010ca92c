//! Smoke test of the real viewer: a window under Xvfb on the software
//! Vulkan driver, a few frames, a screenshot of what the window shows.

use std::process::Command;

/// Runs `pathtracer view` under `xvfb-run` and returns the screenshot.
fn screenshot(width: u32, height: u32, frames: u32) -> image::RgbaImage {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let (w, h, n) = (width.to_string(), height.to_string(), frames.to_string());
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1600x1200x24", env!("CARGO_BIN_EXE_pathtracer"), "view"])
        .args(["--width", &w, "--height", &h, "--frames", &n, "--screenshot", shot.to_str().unwrap()])
        .output()
        .unwrap_or_else(|e| panic!("the viewer test needs xvfb-run (Debian: apt-get install xvfb xauth): {e}"));
    assert!(out.status.success(), "viewer failed: {}", String::from_utf8_lossy(&out.stderr));
    image::open(&shot).expect("screenshot is a PNG").into_rgba8()
}

#[test]
fn viewer_shows_the_room_and_the_panel() {
    let img = screenshot(900, 500, 6);
    assert_eq!(img.dimensions(), (900, 500));

    // The panel: its left 250 pixels are egui's dark background with
    // light text on it.
    let panel: Vec<_> =
        (0..250).flat_map(|x| (0..400).map(move |y| (x, y))).map(|(x, y)| img.get_pixel(x, y).0).collect();
    let dark = panel.iter().filter(|p| p[0] < 60 && p[1] < 60 && p[2] < 60).count();
    let text = panel.iter().filter(|p| p[0] > 150 && p[1] > 150 && p[2] > 150).count();
    assert!(dark * 10 > panel.len() * 6, "no dark panel background ({dark} of {})", panel.len());
    assert!(text > 500, "no panel text ({text} light pixels)");

    // The room, right of the panel: not blank, not uniform; the red left
    // wall and the green right wall both show.
    let room: Vec<_> =
        (450..900).flat_map(|x| (0..500).map(move |y| (x, y))).map(|(x, y)| img.get_pixel(x, y).0).collect();
    let red = room.iter().filter(|p| p[0] as u32 > 2 * p[1] as u32 + 20).count();
    let green = room.iter().filter(|p| p[1] as u32 > p[0] as u32 * 3 / 2 + 20).count();
    assert!(red * 100 > room.len(), "no red wall ({red} pixels)");
    assert!(green * 100 > room.len(), "no green wall ({green} pixels)");
    let mean = room.iter().map(|p| p[1] as f64).sum::<f64>() / room.len() as f64;
    let var = room.iter().map(|p| (p[1] as f64 - mean).powi(2)).sum::<f64>() / room.len() as f64;
    assert!(mean > 20.0 && var > 100.0, "image blank or uniform: mean {mean}, variance {var}");
}
