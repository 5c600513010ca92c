//! The GPU kernel and the CPU reference compute the same image, and the GPU
//! renders the default scene without a single non-finite sample.

use pt_core::glam::Vec3;
use pt_core::params::TONEMAP_ACES;
use pt_core::tonemap::{display_color, pack_rgba8};
use pt_render::gpu::TraceKernel;
use pt_render::metrics::{mean_and_stderr, region_means};
use pt_render::{GpuRenderer, RenderSettings, Scene};
use pt_tests::{gpu, means, render_cpu, render_gpu};

/// Region-by-region z-test of the GPU against the CPU on the default scene.
///
/// Each backend renders 24 independent images (distinct seeds, 16 spp
/// each) of 64x64 pixels. For each 8x8-pixel region and channel, the 24
/// region means give a mean and a standard error per backend; the two means
/// must agree within `Z_MAX` combined standard errors. 64 regions x 3
/// channels = 192 comparisons; with ~46 degrees of freedom a |t| of 6 has a
/// two-sided probability of 2e-7 each, 4e-5 for the family: a failure is a
/// real difference, not bad luck. A 2% bias in one region is ~10 standard
/// errors at these sample counts, so the test has the power to see it.
#[test]
fn gpu_and_cpu_agree_region_by_region() {
    const Z_MAX: f64 = 6.0;
    const SEEDS: u32 = 24;
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 64, height: 64, spp: 16, ..scene.render };
    let ctx = gpu();
    let mut gpu_regions = Vec::new();
    let mut cpu_regions = Vec::new();
    for i in 0..SEEDS {
        let g = render_gpu(&ctx, &scene, &settings, 4, 1000 + i);
        let c = render_cpu(&scene, &settings, 4, 2000 + i);
        gpu_regions.push(region_means(&means(&g), 64, 64, 8));
        cpu_regions.push(region_means(&means(&c), 64, 64, 8));
    }
    let mut worst = 0.0f64;
    for region in 0..gpu_regions[0].len() {
        for ch in 0..3 {
            let g: Vec<f64> = gpu_regions.iter().map(|r| r[region][ch]).collect();
            let c: Vec<f64> = cpu_regions.iter().map(|r| r[region][ch]).collect();
            let (mg, sg) = mean_and_stderr(&g);
            let (mc, sc) = mean_and_stderr(&c);
            let se = (sg * sg + sc * sc).sqrt();
            if se == 0.0 {
                // Both exactly constant (black): must be equal.
                assert_eq!(mg, mc, "region {region} channel {ch}");
                continue;
            }
            let z = (mg - mc) / se;
            worst = worst.max(z.abs());
            assert!(z.abs() < Z_MAX, "region {region} channel {ch}: GPU {mg:.5} vs CPU {mc:.5}, z = {z:.2}");
        }
    }
    eprintln!("largest |z| over 192 region comparisons: {worst:.2}");
}

/// The same seed gives the same sample streams on both backends: the images
/// must be very close (not bit-exact: GPU transcendentals and fused
/// multiply-adds differ in the last bits, and a path can diverge).
#[test]
fn same_seed_gives_nearly_the_same_image() {
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 32, height: 32, spp: 8, ..scene.render };
    let ctx = gpu();
    let g = means(&render_gpu(&ctx, &scene, &settings, 8, 7));
    let c = means(&render_cpu(&scene, &settings, 8, 7));
    let close =
        g.iter().zip(&c).filter(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-3 * (1.0 + b[k].abs()))).count();
    // At least 90% of the pixels follow the same paths to 1e-3.
    assert!(close * 10 >= g.len() * 9, "only {close} of {} pixels match", g.len());
}

#[test]
fn default_scene_on_gpu_has_no_non_finite_samples() {
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 128, height: 128, spp: 64, ..scene.render };
    let ctx = gpu();
    let params = scene.frame_params(&settings, 8, 0);
    let mut r = GpuRenderer::new(&ctx, params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
    for _ in 0..8 {
        r.submit_frame(8);
    }
    assert_eq!(r.read_non_finite(&ctx).unwrap(), 0);
    let accum = r.read_accum(&ctx).unwrap();
    let bad: u64 = accum.iter().map(|p| p.non_finite as u64).sum();
    let good: u64 = accum.iter().map(|p| p.samples as u64).sum();
    assert_eq!(bad, 0);
    assert_eq!(good, 128 * 128 * 64);
}

#[test]
fn gpu_display_pass_matches_the_cpu_transform() {
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 48, height: 40, spp: 4, ..scene.render };
    let ctx = gpu();
    let params = scene.frame_params(&settings, 4, 3);
    let mut r = GpuRenderer::new(&ctx, params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
    r.submit_frame(4);
    r.submit_display(0.5, TONEMAP_ACES);
    let shown = r.read_display(&ctx).unwrap();
    let accum = r.read_accum(&ctx).unwrap();
    assert_eq!(shown.len(), 48 * 40);
    for (i, (px, acc)) in shown.iter().zip(&accum).enumerate() {
        let want = pack_rgba8(display_color(acc.mean(), 0.5, TONEMAP_ACES));
        for shift in [0, 8, 16, 24] {
            let (a, b) = ((px >> shift) & 255, (want >> shift) & 255);
            assert!(a.abs_diff(b) <= 1, "pixel {i}: GPU {px:08x} vs CPU {want:08x}");
        }
    }
}

/// Non-finite samples are discarded and counted, never accumulated, on both
/// backends; the GPU's atomic counter agrees with the per-pixel counts.
#[test]
fn non_finite_samples_are_counted_and_discarded() {
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 32, height: 32, spp: 4, ..scene.render };
    // An infinite light (which the scene loader would reject) makes every
    // path that reaches it infinite.
    let mut params = scene.frame_params(&settings, 4, 5);
    params.light.radiance = pt_core::glam::Vec3::splat(f32::INFINITY);
    let ctx = gpu();
    let mut r = GpuRenderer::new(&ctx, params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
    r.submit_frame(4);
    let accum = r.read_accum(&ctx).unwrap();
    let per_pixel: u64 = accum.iter().map(|p| p.non_finite as u64).sum();
    assert!(per_pixel > 0, "no path reached the light");
    assert_eq!(r.read_non_finite(&ctx).unwrap() as u64, per_pixel);
    assert!(accum.iter().all(|p| p.mean().is_finite()), "a non-finite sample was accumulated");
    assert_eq!(accum.iter().map(|p| (p.samples + p.non_finite) as u64).sum::<u64>(), 32 * 32 * 4);

    let mut cpu = pt_render::CpuRenderer::new(params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
    cpu.render_frame(4);
    assert!(cpu.accum().iter().map(|p| p.non_finite).sum::<u32>() > 0);
    assert!(cpu.accum().iter().all(|p| p.mean().is_finite()));
}

/// Every workgroup shape computes the same pixels (same seed: the same
/// samples), including the ragged right and bottom edges of an image whose
/// size is no multiple of the shape.
#[test]
fn every_workgroup_shape_renders_the_same_image() {
    let scene = Scene::default_scene();
    let settings = RenderSettings { width: 37, height: 23, spp: 2, ..scene.render };
    let ctx = gpu();
    let render = |shape: usize| {
        let mut r =
            GpuRenderer::new(&ctx, scene.frame_params(&settings, 2, 9), &scene.gpu_walls(), &scene.gpu_spheres())
                .unwrap();
        r.set_workgroup_shape(&ctx, shape);
        r.submit_frame(2);
        r.read_accum(&ctx).unwrap()
    };
    let reference = render(0);
    assert!(reference.iter().all(|p| p.samples == 2), "a pixel was not traced");
    for shape in 1..pt_render::gpu::WORKGROUP_SHAPES.len() {
        assert_eq!(render(shape), reference, "shape {:?}", pt_render::gpu::WORKGROUP_SHAPES[shape]);
    }
}

/// `set_geometry` replaces the walls and spheres in place: a renderer made
/// for one scene and switched to another renders, seed for seed, what a
/// renderer made for the other renders (same device, same samples).
#[test]
fn set_geometry_renders_the_new_scene() {
    let before = Scene::default_scene();
    let mut after = Scene::default_scene();
    after.spheres.pop();
    after.walls[0].wall.albedo = pt_core::glam::Vec3::new(0.2, 0.9, 0.2);
    let settings = RenderSettings { width: 32, height: 32, spp: 8, ..before.render };
    let ctx = gpu();
    let expected = render_gpu(&ctx, &after, &settings, 8, 7);

    let mut r =
        GpuRenderer::new(&ctx, before.frame_params(&settings, 8, 7), &before.gpu_walls(), &before.gpu_spheres())
            .unwrap();
    r.submit_frame(8);
    r.reset();
    r.set_geometry(&after.gpu_walls(), &after.gpu_spheres()).unwrap();
    r.submit_frame(8);
    let got = r.read_accum(&ctx).unwrap();
    assert_eq!(means(&got), means(&expected));
    // The change is visible: the first render differs.
    assert_ne!(means(&got), means(&render_gpu(&ctx, &before, &settings, 8, 7)));
}

/// The default scene with `extra` more spheres (at most 12), hung where
/// nothing else is: with six, the box capacity with eight spheres; with
/// more, or with `box_order` false (the side walls first), the capacity of
/// eight walls of any direction and sixteen spheres.
fn more_spheres(extra: usize, box_order: bool) -> Scene {
    let mut scene = Scene::default_scene();
    let spots = [
        (Vec3::new(0.3, 1.2, -0.5), 0.2),
        (Vec3::new(-0.6, 1.3, 0.4), 0.15),
        (Vec3::new(0.7, 0.9, 0.6), 0.12),
        (Vec3::new(-0.1, 0.9, -0.8), 0.15),
        (Vec3::new(-0.7, 1.7, -0.7), 0.15),
        (Vec3::new(0.0, 0.2, 0.75), 0.15),
        (Vec3::new(0.75, 0.15, -0.75), 0.12),
        (Vec3::new(-0.8, 0.12, 0.8), 0.1),
        (Vec3::new(0.4, 1.5, 0.5), 0.1),
        (Vec3::new(-0.4, 1.4, -0.1), 0.1),
        (Vec3::new(0.8, 1.8, -0.2), 0.1),
        (Vec3::new(-0.88, 0.75, 0.0), 0.1),
    ];
    for (k, (center, radius)) in spots.into_iter().take(extra).enumerate() {
        let sphere = pt_core::Sphere::new(center, radius, Vec3::new(0.9, 0.1 + 0.06 * k as f32, 0.1));
        scene.spheres.push(pt_render::scene::NamedSphere { name: format!("extra {k}"), sphere });
    }
    if !box_order {
        scene.walls.swap(0, 3);
    }
    scene
}

/// The scenes the small-scene tests run, one per capacity, each checked
/// to take it: the default scene, eight spheres in the box, and fourteen
/// with the side walls first.
fn one_scene_per_capacity() -> Vec<Scene> {
    use pt_core::small_scene::{SMALL_SCENE_SIZES, smallest_fit};
    let scenes = vec![Scene::default_scene(), more_spheres(6, true), more_spheres(12, false)];
    for (i, scene) in scenes.iter().enumerate() {
        let settings = RenderSettings { width: 8, height: 8, ..scene.render };
        let geometry = scene.geometry().unwrap();
        let fit = smallest_fit(&scene.frame_params(&settings, 1, 0), &geometry);
        assert_eq!(fit, Some(i), "scene {i} takes capacity {:?}", SMALL_SCENE_SIZES[i]);
    }
    assert_eq!(scenes.len(), SMALL_SCENE_SIZES.len());
    scenes
}

/// A frame of `scene` with the trace kernel `kernel`.
fn render_with(ctx: &pt_render::GpuContext, scene: &Scene, kernel: TraceKernel) -> (TraceKernel, Vec<[f32; 3]>) {
    render_with_flags(ctx, scene, kernel, scene.default_flags())
}

/// A frame of `scene` with the trace kernel `kernel` and integrator `flags`.
fn render_with_flags(
    ctx: &pt_render::GpuContext,
    scene: &Scene,
    kernel: TraceKernel,
    flags: u32,
) -> (TraceKernel, Vec<[f32; 3]>) {
    let settings = RenderSettings { width: 37, height: 23, spp: 4, ..scene.render };
    let mut params = scene.frame_params(&settings, 4, 11);
    params.flags = flags;
    let r = GpuRenderer::with_trace_kernel(ctx, params, &scene.gpu_walls(), &scene.gpu_spheres(), kernel);
    let mut r = r.unwrap();
    let used = r.trace_kernel();
    r.submit_frame(4);
    (used, means(&r.read_accum(ctx).unwrap()))
}

/// Both small-scene kernels (the default on software and NVIDIA adapters),
/// each with each of the three samplers compiled in, with and without the connections' code and
/// the glow lobe's, render what the general kernel renders with the same
/// flags, seed for seed: the same tests in the same order on
/// a copy of the same numbers, on each capacity
/// (`one_scene_per_capacity`). On lavapipe that is bit for bit; another driver may fuse
/// multiply-adds differently in each, so elsewhere all but a few pixels
/// (paths that diverge) must agree to 1e-4. The three samplers' images
/// differ, and so do those with connections and those without the glow
/// lobe: each flag setting reaches its own entry point.
#[test]
fn small_scene_kernels_render_what_the_general_kernel_renders() {
    use pt_core::params::{FLAG_CONNECT, FLAG_GLOW, FLAG_SOBOL, FLAG_SOBOL_DEEP, FLAGS_DEFAULT};
    let ctx = gpu();
    let samplers = [FLAGS_DEFAULT & !FLAG_SOBOL, FLAGS_DEFAULT, FLAGS_DEFAULT | FLAG_SOBOL_DEEP];
    let connected = |flags: u32| (flags & !FLAG_GLOW) | FLAG_CONNECT;
    let all = samplers.into_iter().flat_map(|f| [f, connected(f), f & !FLAG_GLOW]);
    for scene in one_scene_per_capacity() {
        let mut images: Vec<Vec<[f32; 3]>> = Vec::new();
        for flags in all.clone() {
            let (used, general) = render_with_flags(&ctx, &scene, TraceKernel::General, flags);
            assert_eq!(used, TraceKernel::General);
            let (used, small) = render_with_flags(&ctx, &scene, TraceKernel::SmallScene, flags);
            assert_eq!(used, TraceKernel::SmallScene, "the scene fits");
            assert!(general.iter().any(|p| p[0] > 0.0), "a black image proves nothing");
            if ctx.is_software() {
                assert_eq!(small, general, "flags {flags:#x}");
            } else {
                let close = small
                    .iter()
                    .zip(&general)
                    .filter(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-4 * (1.0 + b[k].abs())))
                    .count();
                assert!(close * 100 >= general.len() * 98, "only {close} of {} pixels match", general.len());
            }
            assert!(images.iter().all(|other| *other != small), "flags {flags:#x} drew another sampler's numbers");
            images.push(small);
        }
    }
}

/// A renderer starts on its adapter's default kernel: on a software
/// adapter (lavapipe, where CI runs this), the small-scene kernel with
/// the scene compiled in, for a scene it holds.
#[test]
fn renderers_start_on_their_adapters_default_kernel() {
    let ctx = gpu();
    let scene = Scene::default_scene();
    let params = scene.frame_params(&RenderSettings { width: 16, height: 16, ..scene.render }, 4, 1);
    let r = GpuRenderer::new(&ctx, params, &scene.gpu_walls(), &scene.gpu_spheres()).unwrap();
    if ctx.is_software() {
        assert_eq!(r.trace_kernel(), TraceKernel::Specialized);
    }
    assert_eq!(r.trace_kernel(), GpuRenderer::default_trace_kernel(&ctx));
}

/// Pixels of `a` within `tolerance` (relative) of `b`, per thousand.
fn close_per_mille(a: &[[f32; 3]], b: &[[f32; 3]], tolerance: f32) -> usize {
    let close = a.iter().zip(b).filter(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() <= tolerance * (1.0 + b[k].abs())));
    close.count() * 1000 / b.len()
}

/// The small-scene kernels with the scene compiled in (each capacity,
/// with and without the connections' code) render the samples of the
/// unspecialized ones: the same arithmetic on the same values, which the
/// driver may now fold and fuse differently, so every pixel but a few
/// (paths that a rounding turns) agrees to 1e-4. The images differ from
/// flags to flags: each setting reaches its own pipeline.
#[test]
fn specialized_kernels_render_what_the_small_scene_kernels_render() {
    use pt_core::params::{FLAG_CONNECT, FLAG_GLOW, FLAGS_DEFAULT};
    let ctx = gpu();
    let connected = (FLAGS_DEFAULT & !FLAG_GLOW) | FLAG_CONNECT;
    for scene in one_scene_per_capacity() {
        let mut images: Vec<Vec<[f32; 3]>> = Vec::new();
        for flags in [FLAGS_DEFAULT, connected] {
            let (used, small) = render_with_flags(&ctx, &scene, TraceKernel::SmallScene, flags);
            assert_eq!(used, TraceKernel::SmallScene);
            let (used, specialized) = render_with_flags(&ctx, &scene, TraceKernel::Specialized, flags);
            assert_eq!(used, TraceKernel::Specialized, "the scene fits");
            assert!(small.iter().any(|p| p[0] > 0.0), "a black image proves nothing");
            let per_mille = close_per_mille(&specialized, &small, 1e-4);
            assert!(per_mille >= 980, "only {per_mille} per mille of the pixels match, flags {flags:#x}");
            assert!(images.iter().all(|other| close_per_mille(&specialized, other, 1e-4) < 500), "flags {flags:#x}");
            images.push(specialized);
        }
    }
}

/// A specialized renderer follows a change of scene: after new geometry
/// and a moved light it renders, bit for bit, what a renderer made for
/// the changed scene renders (the same constants, so the same pipeline),
/// and not what it rendered before.
#[test]
fn a_specialized_renderer_follows_a_changed_scene() {
    let ctx = gpu();
    let before = Scene::default_scene();
    let mut after = Scene::default_scene();
    after.spheres[0].sphere.center.x += 0.1;
    after.light.center.y -= 0.2;
    let settings = RenderSettings { width: 24, height: 16, ..before.render };
    let render = |r: &mut GpuRenderer| {
        r.reset();
        r.submit_frame(4);
        means(&r.read_accum(&ctx).unwrap())
    };
    let make = |scene: &Scene| {
        let params = scene.frame_params(&settings, 4, 5);
        let r = GpuRenderer::with_trace_kernel(
            &ctx,
            params,
            &scene.gpu_walls(),
            &scene.gpu_spheres(),
            TraceKernel::Specialized,
        );
        r.unwrap()
    };
    let mut r = make(&before);
    let first = render(&mut r);
    r.set_params(after.frame_params(&settings, 4, 5)).unwrap();
    r.set_geometry(&after.gpu_walls(), &after.gpu_spheres()).unwrap();
    assert_eq!(r.trace_kernel(), TraceKernel::Specialized);
    let changed = render(&mut r);
    assert_eq!(changed, render(&mut make(&after)));
    assert!(close_per_mille(&changed, &first, 1e-4) < 500, "the change shows");
}

/// A scene the small-scene kernel cannot render exactly (a 17th sphere,
/// or, read from the buffers, a panel that can shadow the light) runs on
/// the general kernel even where the small one is chosen, and renders what
/// the general kernel renders.
#[test]
fn scenes_that_do_not_fit_run_on_the_general_kernel() {
    let ctx = gpu();
    let mut too_many = Scene::default_scene();
    for k in 0..15 {
        let at = Vec3::new(-0.75 + 0.25 * (k % 7) as f32, 1.2, 0.6 - 0.25 * (k / 7) as f32);
        let sphere = pt_core::Sphere::new(at, 0.08, Vec3::splat(0.5));
        too_many.spheres.push(pt_render::scene::NamedSphere { name: format!("extra {k}"), sphere });
    }
    // Where the small-scene kernel is the adapter's default (lavapipe, where
    // CI runs this), the user is told why a scene does not get it.
    let default = GpuRenderer::default_trace_kernel(&ctx);
    assert_eq!(GpuRenderer::general_kernel_notice(&Scene::default_scene(), default), None);
    let notice = GpuRenderer::general_kernel_notice(&too_many, default);
    let small_default = default != TraceKernel::General;
    assert_eq!(notice.is_some_and(|n| n.ends_with("17 spheres (the small-scene kernel holds 16)")), small_default);
    for (scene, kernel) in [(&too_many, TraceKernel::Specialized), (&panel(), TraceKernel::SmallScene)] {
        let (used, fallback) = render_with(&ctx, scene, kernel);
        assert_eq!(used, TraceKernel::General);
        assert_eq!(fallback, render_with(&ctx, scene, TraceKernel::General).1);
    }
}

/// The default scene with a panel in the room that can shadow the light.
fn panel() -> Scene {
    let mut panel = Scene::default_scene();
    let wall = pt_core::Wall::new(Vec3::new(-0.5, 1.0, -0.5), Vec3::X, Vec3::new(0.0, 0.2, 0.6), Vec3::splat(0.5));
    panel.walls.push(pt_render::scene::NamedWall { name: "panel".into(), wall });
    panel
}

/// With the scene compiled in, the small-scene kernel takes scenes with
/// walls that can block the light (the default light raised through the
/// ceiling, on the box capacity; a panel in the room, on the capacity of
/// eight walls), and renders what the general kernel renders: every pixel
/// but a few to 1e-4, as for the specialized kernels above. The renderer
/// of the default scene renders another image.
#[test]
fn compiled_in_walls_that_block_the_light_run_on_the_small_scene_kernel() {
    let ctx = gpu();
    let mut through_ceiling = Scene::default_scene();
    through_ceiling.light.center.y = 1.9;
    let (_, default_image) = render_with(&ctx, &Scene::default_scene(), TraceKernel::General);
    for scene in [through_ceiling, panel()] {
        assert!(GpuRenderer::general_kernel_notice(&scene, TraceKernel::Specialized).is_none());
        let notice = GpuRenderer::general_kernel_notice(&scene, TraceKernel::SmallScene);
        assert!(notice.is_some_and(|n| n.contains("a wall that can block the light")));
        let (used, specialized) = render_with(&ctx, &scene, TraceKernel::Specialized);
        assert_eq!(used, TraceKernel::Specialized);
        let (_, general) = render_with(&ctx, &scene, TraceKernel::General);
        let per_mille = close_per_mille(&specialized, &general, 1e-4);
        assert!(per_mille >= 980, "only {per_mille} per mille of the pixels match");
        assert!(close_per_mille(&general, &default_image, 1e-4) < 500, "the change shows");
    }
}
