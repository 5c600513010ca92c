//! An image rendered in tiles is the image rendered whole: every pixel
//! keeps its image coordinates, so its camera ray and samples are those of
//! the untiled render. Exact on the CPU; exact on lavapipe too, whose
//! kernel runs the same instructions for a pixel whatever its tile.

use pt_core::{AccumPixel, Tile};
use pt_render::renderer::{device_tiles, render_tiled, row_bands};
use pt_render::{Device, RenderSettings, Scene};
use pt_tests::gpu;

/// The default scene at 61x47 (no multiple of a workgroup), 8 spp in
/// frames of 3, on `device`, in `tiles`; the accumulation and the display.
fn render(device: Device<'_>, tiles: &[Tile]) -> (Vec<AccumPixel>, Vec<u32>) {
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 61, height: 47, spp: 8, ..scene.render };
    let params = scene.frame_params(&settings, 3, 7);
    let r = render_tiled(
        device,
        params,
        &scene.gpu_walls(),
        &scene.gpu_spheres(),
        0..8,
        3,
        tiles,
        Some((0.5, 1)),
        |_, _| {},
    )
    .expect("render");
    (r.accum, r.display.expect("display asked for"))
}

/// Case: uneven bands (10 rows, the last 7) against the whole image.
#[test]
fn tiled_renders_equal_whole_renders_on_both_backends() {
    let bands = row_bands(61, 47, 61 * 10);
    assert_eq!(bands.len(), 5);
    let ctx = gpu();
    for device in [Device::Cpu, Device::Gpu(&ctx)] {
        let whole = render(device, &[Tile::whole(61, 47)]);
        let tiled = render(device, &bands);
        let sums = |a: &[AccumPixel]| a.iter().map(|p| (p.sum.to_array(), p.samples)).collect::<Vec<_>>();
        assert_eq!(sums(&tiled.0), sums(&whole.0), "{}: accumulation", device.name());
        assert_eq!(tiled.1, whole.1, "{}: display", device.name());
    }
}

/// Case: bands cover every row once, top to bottom, each within the pixel
/// budget (one row at least, when a row alone is over it).
#[test]
fn row_bands_cover_the_image_within_the_budget() {
    for (w, h, max) in [(7u32, 10u32, 21u64), (7, 10, 70), (7, 10, 1000), (7, 10, 3), (16384, 16384, 1 << 22)] {
        let bands = row_bands(w, h, max);
        let mut next = 0;
        for b in &bands {
            assert_eq!((b.x, b.y, b.width), (0, next, w));
            assert!(b.pixels() <= max.max(w as u64), "{b:?} over {max}");
            next += b.height;
        }
        assert_eq!(next, h, "{w}x{h} in bands of {max}");
    }
}

/// Case: a 7680x4320 image does not fit one storage buffer of lavapipe
/// (128 MiB), so the GPU takes it in bands that each fit the adapter's
/// limit; the CPU takes it whole.
#[test]
fn large_images_are_tiled_within_the_adapter_limit() {
    let ctx = gpu();
    let tiles = device_tiles(Device::Gpu(&ctx), 7680, 4320);
    let limit = pt_render::gpu::renderer::max_image_bytes(&ctx.device);
    assert!(tiles.len() > 1, "{} tiles", tiles.len());
    assert!(tiles.iter().all(|t| t.pixels() * size_of::<AccumPixel>() as u64 <= limit));
    assert_eq!(device_tiles(Device::Cpu, 7680, 4320), [Tile::whole(7680, 4320)]);
}
