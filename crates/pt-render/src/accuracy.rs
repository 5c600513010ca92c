//! The accuracy suite: renders of analytic scenes, image comparisons and the
//! accumulation case on each backend, each with an expected value, a
//! measurement, its standard error and a tolerance derived from it
//! (`pathtracer accuracy`). Checks of pt-core alone (intersection
//! precision, self-intersection, watertightness, chi-square tests of the
//! samplers) are pt-core's unit tests.
//!
//! Monte Carlo cases render `SEEDS` independent images (distinct seeds);
//! the spread of their means gives the standard error, and the tolerance is
//! `Z_CRIT` standard errors. With 16 seeds the t statistic has 15 degrees
//! of freedom, for which |t| > 5.5 has probability 1e-4: over the cases
//! of a run a false failure has probability under 1%. The
//! accumulation case has a tolerance from f32 rounding, stated with it.

use std::f64::consts::PI;

use pt_core::glam::{DVec3, Vec3};
use pt_core::params::{
    FLAG_CONNECT, FLAG_GLOW, FLAG_GLOW_SPARSE, FLAG_LIGHT_EDGE, FLAG_MIS, FLAG_NEE, FLAG_NEE_CONTROL,
    FLAG_NEE_PROJECTED, FLAG_RR_LUMINANCE, FLAG_SOBOL, FLAG_SOBOL_DEEP, FLAGS_DEFAULT,
};
use pt_core::rng::Rng;
use pt_core::{FrameParams, Sphere, SphereLight, Wall, light};

use crate::gpu::GpuError;
use crate::metrics::{mean_and_stderr, region_means};
use crate::renderer::{Device, render_accum};
use crate::scene::{CameraDesc, NamedSphere, NamedWall, RenderSettings, Scene};
use crate::strategy::with_connections;

/// Independent renders per Monte Carlo case.
pub const SEEDS: u32 = 16;
/// Tolerance of Monte Carlo cases in standard errors (t, 15 dof: p = 1e-4).
pub const Z_CRIT: f64 = 5.5;
/// Family-wise significance of the sampling tests (Sidak-corrected).
pub const SAMPLING_ALPHA: f64 = 0.01;

/// One line of the report.
#[derive(Clone, Debug)]
pub struct CaseResult {
    /// What is checked.
    pub case: String,
    /// "cpu", "gpu", or "core" for backend-independent checks.
    pub backend: &'static str,
    /// The exact (or reference) value.
    pub expected: f64,
    /// The measured value.
    pub measured: f64,
    /// Standard error of the measurement (0 for exact checks).
    pub stderr: f64,
    /// Largest accepted |measured - expected|.
    pub tolerance: f64,
    /// Non-finite samples seen while measuring.
    pub non_finite: u64,
    /// Within tolerance and no non-finite sample.
    pub pass: bool,
}

impl CaseResult {
    fn new(
        case: impl Into<String>,
        backend: &'static str,
        expected: f64,
        measured: f64,
        stderr: f64,
        tolerance: f64,
        non_finite: u64,
    ) -> Self {
        let pass = (measured - expected).abs() <= tolerance && non_finite == 0 && measured.is_finite();
        Self { case: case.into(), backend, expected, measured, stderr, tolerance, non_finite, pass }
    }

    fn monte_carlo(case: impl Into<String>, backend: &'static str, expected: f64, m: &Measurement) -> Self {
        // A floor of f32 resolution for cases whose noise is zero.
        let tol = (Z_CRIT * m.stderr).max(1e-6 * expected.abs());
        Self::new(case, backend, expected, m.mean, m.stderr, tol, m.non_finite)
    }
}

/// How big the suite runs.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Size {
    /// For CI: 2^24 samples in the accumulation case.
    Quick,
    /// 2^25 samples in the accumulation case.
    Full,
}

/// Mean over seeds of a per-image statistic, with its standard error.
#[derive(Clone, Debug, Default)]
pub struct Measurement {
    /// Mean over seeds.
    pub mean: f64,
    /// Standard error of the mean.
    pub stderr: f64,
    /// Non-finite samples over all seeds.
    pub non_finite: u64,
}

/// Mean radiance per pixel, row-major.
type Image = Vec<[f32; 3]>;

/// A change to a test setup.
type Variant = (&'static str, fn(&mut Setup));

/// A scene with everything the kernel needs, built in code.
struct Setup {
    scene: Scene,
    settings: RenderSettings,
    flags: u32,
}

impl Setup {
    fn new(scene: Scene, width: u32, height: u32, spp: u32, max_bounces: u32) -> Self {
        let settings = RenderSettings { width, height, spp, max_bounces, rr_start: 3 };
        Self { scene, settings, flags: FLAGS_DEFAULT }
    }

    fn params(&self, seed: u32) -> FrameParams {
        let mut p = self.scene.frame_params(&self.settings, 1, seed);
        p.flags = self.flags;
        p
    }

    /// Per-seed images (mean radiance per pixel) and the non-finite count.
    fn images(&self, t: &Device<'_>, seeds: std::ops::Range<u32>) -> Result<(Vec<Image>, u64), GpuError> {
        let mut images = Vec::new();
        let mut bad = 0;
        for seed in seeds {
            let (walls, spheres) = (self.scene.gpu_walls(), self.scene.gpu_spheres());
            let accum = render_accum(*t, self.params(seed), &walls, &spheres, self.settings.spp, 256)?;
            bad += accum.iter().map(|p| p.non_finite as u64).sum::<u64>();
            images.push(accum.iter().map(|p| p.mean().to_array()).collect());
        }
        Ok((images, bad))
    }

    /// Mean of channel-averaged radiance over all pixels, across seeds.
    fn measure(&self, t: &Device<'_>) -> Result<Measurement, GpuError> {
        let (images, non_finite) = self.images(t, 0..SEEDS)?;
        let per_seed: Vec<f64> = images
            .iter()
            .map(|img| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / img.len() as f64)
            .collect();
        let (mean, stderr) = mean_and_stderr(&per_seed);
        Ok(Measurement { mean, stderr, non_finite })
    }
}

fn wall(corner: Vec3, u: Vec3, v: Vec3, albedo: f32) -> NamedWall {
    NamedWall { name: "wall".into(), wall: Wall::new(corner, u, v, Vec3::splat(albedo)) }
}

fn sphere(center: Vec3, radius: f32, albedo: f32) -> NamedSphere {
    NamedSphere { name: "sphere".into(), sphere: Sphere::new(center, radius, Vec3::splat(albedo)) }
}

fn camera(position: Vec3, look_at: Vec3, vfov_degrees: f32) -> CameraDesc {
    let dir = (look_at - position).normalize();
    let up = if dir.y.abs() > 0.9 { Vec3::Z } else { Vec3::Y };
    CameraDesc { position, look_at, up, vfov_degrees }
}

fn empty_scene(cam: CameraDesc) -> Scene {
    Scene {
        origin: DVec3::ZERO,
        camera: cam,
        light: SphereLight::new(Vec3::new(0.0, -1e4, 0.0), 1.0, Vec3::ZERO),
        walls: vec![],
        spheres: vec![],
        background: Vec3::ZERO,
        render: RenderSettings::default(),
    }
}

/// Radiance of the wall of a diffuse spherical room of albedo `rho` lit by
/// a spherical light of radiance `l` at its centre, s = r / R, for at most
/// `bounces` scattering events: rho L s^2 sum_{k<bounces} (rho (1 - s^2))^k.
pub fn sphere_room_radiance(rho: f64, l: f64, s: f64, bounces: u32) -> f64 {
    let q = rho * (1.0 - s * s);
    let geometric = if bounces >= 10_000 { 1.0 / (1.0 - q) } else { (1.0 - q.powi(bounces as i32)) / (1.0 - q) };
    rho * l * s * s * if q == 0.0 { 1.0 } else { geometric }
}

/// Irradiance per unit radiance from a sphere of angular radius sigma
/// (sin^2 sigma = `sin2_sigma`) whose centre is at angle theta from the
/// normal (cos theta = `cos_theta`), the part below the horizon excluded.
/// Snyder (1996), in the form of Lagarde and de Rousiers, "Moving Frostbite
/// to PBR" (2014), section 4.7.
pub fn sphere_irradiance(cos_theta: f64, sin2_sigma: f64) -> f64 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    if cos_theta * cos_theta > sin2_sigma {
        PI * sin2_sigma * cos_theta.max(0.0)
    } else {
        let x = (1.0 / sin2_sigma - 1.0).max(0.0).sqrt();
        let y = -x * (cos_theta / sin_theta);
        let sin_theta_sqrt_y = sin_theta * (1.0 - y * y).max(0.0).sqrt();
        ((cos_theta * y.clamp(-1.0, 1.0).acos() - x * sin_theta_sqrt_y) * sin2_sigma + (sin_theta_sqrt_y / x).atan())
            .max(0.0)
    }
}

/// The same by brute-force quadrature over the cap (for testing the
/// closed form): midpoint rule in (theta', phi') about the cap's axis.
pub fn sphere_irradiance_quadrature(cos_theta: f64, sin2_sigma: f64, n: usize) -> f64 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let axis = DVec3::new(sin_theta, 0.0, cos_theta);
    let (t, b) = (DVec3::new(cos_theta, 0.0, -sin_theta), DVec3::Y);
    let one_minus_cos_sigma = sin2_sigma / (1.0 + (1.0 - sin2_sigma).sqrt());
    let mut sum = 0.0;
    for i in 0..n {
        // Uniform in 1 - cos over the cap, uniform in phi: equal solid angle.
        let omc = one_minus_cos_sigma * (i as f64 + 0.5) / n as f64;
        let c = 1.0 - omc;
        let s = (omc * (2.0 - omc)).sqrt();
        for j in 0..n {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n as f64;
            let d = t * (s * phi.cos()) + b * (s * phi.sin()) + axis * c;
            sum += d.z.max(0.0);
        }
    }
    sum * 2.0 * PI * one_minus_cos_sigma / (n * n) as f64
}

/// A camera `h` above surface point `x` (normal `n`), looking at it with a
/// 0.2 degree field of view: the image is a patch around `x` so small that
/// its mean is the radiance leaving `x`.
fn probe(scene: Scene, x: Vec3, n: Vec3, h: f32) -> Scene {
    Scene { camera: camera(x + n * h, x, 0.2), ..scene }
}

/// Runs the whole suite on `targets`.
pub fn run(targets: &[Device<'_>], size: Size) -> Result<Vec<CaseResult>, GpuError> {
    let mut out = Vec::new();
    for t in targets {
        analytic_scenes(t, &mut out)?;
        irradiance_probes(t, &mut out)?;
        contact(t, &mut out)?;
        equal_expectations(t, &mut out)?;
        metamorphic(t, &mut out)?;
        accumulation(t, size, &mut out)?;
    }
    irradiance_estimator(&mut out);
    Ok(out)
}

fn sphere_room(rho: f32, s: f32, radiance: f32, max_bounces: u32) -> Setup {
    let mut scene = empty_scene(camera(Vec3::new(0.0, 0.0, 0.5), Vec3::new(0.0, 0.0, 1.0), 30.0));
    scene.light = SphereLight::new(Vec3::ZERO, s, Vec3::splat(radiance));
    scene.spheres = vec![sphere(Vec3::ZERO, 1.0, rho)];
    Setup::new(scene, 8, 8, 64, max_bounces)
}

fn analytic_scenes(t: &Device<'_>, out: &mut Vec<CaseResult>) -> Result<(), GpuError> {
    const UNLIMITED: u32 = 1_000_000;
    for (rho, s, bounces) in [(0.5f32, 0.1f32, UNLIMITED), (0.5, 0.1, 1), (0.95, 0.3, UNLIMITED), (0.0, 0.2, UNLIMITED)]
    {
        let setup = sphere_room(rho, s, 10.0, bounces);
        let expected = sphere_room_radiance(rho as f64, 10.0, s as f64, bounces);
        let limit = if bounces == UNLIMITED { "unlimited bounces".to_string() } else { format!("{bounces} bounce") };
        let m = setup.measure(t)?;
        out.push(CaseResult::monte_carlo(format!("spherical room rho={rho} s={s}, {limit}"), t.name(), expected, &m));
    }
    // A Lambertian sphere under a uniform background shows albedo x
    // background; with albedo 1 it vanishes (white furnace).
    for albedo in [0.5f32, 1.0] {
        let mut scene = empty_scene(camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 10.0));
        scene.spheres = vec![sphere(Vec3::ZERO, 1.0, albedo)];
        scene.background = Vec3::splat(0.8);
        let m = Setup::new(scene, 8, 8, 32, 5).measure(t)?;
        out.push(CaseResult::monte_carlo(
            format!("sphere albedo {albedo} under background 0.8"),
            t.name(),
            0.8 * albedo as f64,
            &m,
        ));
    }
    Ok(())
}

/// The direction at angle `theta` from +y toward +x.
fn tilted(theta: f64) -> Vec3 {
    Vec3::new(theta.sin() as f32, theta.cos() as f32, 0.0)
}

/// Angles from the normal to the light's centre for the three regimes.
fn regimes(sigma: f64) -> [(&'static str, f64); 3] {
    let half_pi = PI / 2.0;
    [
        ("above horizon", (0.5 * (half_pi - sigma)).min(0.5)),
        ("partly below", half_pi),
        ("below horizon", half_pi + sigma + 0.5 * (half_pi - sigma)),
    ]
}

/// Irradiance on a plane from a sphere light, rendered: a floor of albedo 1
/// seen by a probe, one bounce, so the probe reads E / pi.
fn irradiance_probes(t: &Device<'_>, out: &mut Vec<CaseResult>) -> Result<(), GpuError> {
    for sin_sigma in [0.01f64, 0.5, 0.999] {
        for (regime, theta) in regimes(sin_sigma.asin()) {
            let d = 2.0f32;
            let mut scene =
                empty_scene(CameraDesc { position: Vec3::ONE, look_at: Vec3::ZERO, up: Vec3::Y, vfov_degrees: 1.0 });
            scene.light = SphereLight::new(tilted(theta) * d, d * sin_sigma as f32, Vec3::splat(5.0));
            scene.walls =
                vec![wall(Vec3::new(-1e3, 0.0, 1e3), Vec3::new(2e3, 0.0, 0.0), Vec3::new(0.0, 0.0, -2e3), 1.0)];
            let scene = probe(scene, Vec3::ZERO, Vec3::Y, 1e-3);
            let m = Setup::new(scene, 4, 4, 256, 1).measure(t)?;
            let expected = 5.0 * sphere_irradiance(theta.cos(), sin_sigma * sin_sigma) / PI;
            out.push(CaseResult::monte_carlo(
                format!("irradiance/pi from a sphere light, sin(a)={sin_sigma}, {regime}"),
                t.name(),
                expected,
                &m,
            ));
        }
    }
    Ok(())
}

/// The NEE estimator of irradiance (cone sampling, cos/pdf), directly.
fn irradiance_estimator(out: &mut Vec<CaseResult>) {
    for sin_sigma in [1e-4f64, 1e-2, 0.5, 0.999] {
        for (regime, theta) in regimes(sin_sigma.asin()) {
            let d = 3.0f32;
            let l = SphereLight::new(tilted(theta) * d, d * sin_sigma as f32, Vec3::ONE);
            let cone = light::light_cone(&l, Vec3::ZERO);
            let per_seed: Vec<f64> = (0..SEEDS)
                .map(|seed| {
                    let mut rng = Rng::new(seed, 1, 2, 3, 4);
                    let n = 20_000;
                    let mut sum = 0.0;
                    for _ in 0..n {
                        let (dir, _) = cone.sample(rng.next_f32(), rng.next_f32());
                        sum += (dir.y.max(0.0) / cone.pdf()) as f64;
                    }
                    sum / n as f64
                })
                .collect();
            let (mean, stderr) = mean_and_stderr(&per_seed);
            let m = Measurement { mean, stderr, non_finite: 0 };
            let expected = sphere_irradiance(theta.cos(), sin_sigma * sin_sigma);
            out.push(CaseResult::monte_carlo(
                format!("NEE irradiance estimator, sin(a)={sin_sigma}, {regime}"),
                "core",
                expected,
                &m,
            ));
        }
    }
}

/// A black sphere of radius 1 resting on a white floor under a uniform sky
/// of radiance 1: the floor at distance D from the centre shows
/// 1 - (R / D)^3 (the sphere hides pi sin^2 a cos b of the sky, with sin a
/// = cos b = R / D), one bounce. No leak and no extra dark ring.
fn contact(t: &Device<'_>, out: &mut Vec<CaseResult>) -> Result<(), GpuError> {
    for rho in [0.05f32, 0.2, 0.5, 1.0, 2.0] {
        let mut scene =
            empty_scene(CameraDesc { position: Vec3::ONE, look_at: Vec3::ZERO, up: Vec3::Y, vfov_degrees: 1.0 });
        scene.background = Vec3::ONE;
        scene.spheres = vec![sphere(Vec3::new(0.0, 1.0, 0.0), 1.0, 0.0)];
        scene.walls = vec![wall(Vec3::new(-1e3, 0.0, 1e3), Vec3::new(2e3, 0.0, 0.0), Vec3::new(0.0, 0.0, -2e3), 1.0)];
        // The probe sits well inside the gap under the sphere.
        let gap = 1.0 - (1.0 - rho.min(1.0).powi(2)).sqrt();
        let x = Vec3::new(rho, 0.0, 0.0);
        let scene = probe(scene, x, Vec3::Y, (0.25 * gap).min(1e-2));
        let m = Setup::new(scene, 4, 4, 256, 1).measure(t)?;
        let dist = (1.0 + (rho as f64).powi(2)).sqrt();
        out.push(CaseResult::monte_carlo(
            format!("contact: floor at {rho} from a resting sphere"),
            t.name(),
            1.0 - dist.powi(-3),
            &m,
        ));
    }
    Ok(())
}

/// Per-region z statistics of two sets of per-seed images.
fn largest_region_z(a: &[Image], b: &[Image], w: u32, h: u32, block: u32) -> (f64, usize) {
    let ra: Vec<_> = a.iter().map(|i| region_means(i, w, h, block)).collect();
    let rb: Vec<_> = b.iter().map(|i| region_means(i, w, h, block)).collect();
    let mut worst = 0.0f64;
    let mut tests = 0;
    for r in 0..ra[0].len() {
        for c in 0..3 {
            let (ma, sa) = mean_and_stderr(&ra.iter().map(|x| x[r][c]).collect::<Vec<_>>());
            let (mb, sb) = mean_and_stderr(&rb.iter().map(|x| x[r][c]).collect::<Vec<_>>());
            let se = (sa * sa + sb * sb).sqrt();
            tests += 1;
            if se > 0.0 {
                worst = worst.max(((ma - mb) / se).abs());
            } else if ma != mb {
                worst = f64::INFINITY;
            }
        }
    }
    (worst, tests)
}

/// The critical |z| for `tests` comparisons at family-wise 1% with a t
/// statistic of 2 x SEEDS - 2 degrees of freedom (conservative: 6.0 for up
/// to ~200 tests, from the t tail 1% / 200 = 5e-5 at 30 dof, ~4.9, rounded
/// up for the error in the estimated standard errors).
const REGION_Z_CRIT: f64 = 6.0;

fn default_small() -> Setup {
    Setup::new(Scene::default_scene(), 24, 24, 16, 5)
}

fn equal_expectations(t: &Device<'_>, out: &mut Vec<CaseResult>) -> Result<(), GpuError> {
    let base = default_small();
    let (ref_images, bad0) = base.images(t, 0..SEEDS)?;
    let variants: [Variant; 20] = [
        ("connections instead of the glow lobe (the default in a room that does not shadow the light)", |s| {
            s.flags = with_connections(s.flags)
        }),
        ("connections with the glow lobe too, and MIS", |s| s.flags |= FLAG_CONNECT | FLAG_MIS),
        ("connections with NEE uniform in the light's cone", |s| {
            s.flags = with_connections(s.flags) & !FLAG_NEE_PROJECTED
        }),
        ("connections on independent samples", |s| s.flags = with_connections(s.flags) & !FLAG_SOBOL),
        ("the glow lobe at a tenth of the samples, with MIS", |s| s.flags |= FLAG_GLOW_SPARSE | FLAG_MIS),
        ("the glow lobe off, with MIS (a large light in the open)", |s| {
            s.flags = (s.flags & !FLAG_GLOW) | FLAG_GLOW_SPARSE | FLAG_MIS
        }),
        ("randomised Sobol samples instead of independent ones", |s| s.flags ^= FLAG_SOBOL),
        ("NEE uniform in the light's cone, not by projected solid angle", |s| s.flags &= !FLAG_NEE_PROJECTED),
        ("NEE uniform in the light's cone, with MIS", |s| s.flags = (s.flags & !FLAG_NEE_PROJECTED) | FLAG_MIS),
        ("NEE uniform in the light's cone with the control variate", |s| {
            s.flags = (s.flags & !FLAG_NEE_PROJECTED) | FLAG_NEE_CONTROL
        }),
        ("the control variate with MIS, beside connections", |s| {
            s.flags = with_connections(s.flags & !FLAG_NEE_PROJECTED) | FLAG_NEE_CONTROL | FLAG_MIS
        }),
        ("Sobol points for every draw, not the first ones only", |s| s.flags |= FLAG_SOBOL_DEEP),
        ("the light's edge in the image by its control variate", |s| s.flags |= FLAG_LIGHT_EDGE),
        ("the glow lobe off (cosine BSDF sampling only)", |s| s.flags &= !FLAG_GLOW),
        ("NEE off (BSDF sampling only)", |s| s.flags = 0),
        ("NEE alone on independent samples, cosine lobe only", |s| s.flags = FLAG_NEE),
        ("NEE off, BSDF sampling with the glow lobe", |s| s.flags = FLAG_GLOW),
        ("MIS on, BSDF sampling with the glow lobe", |s| s.flags |= FLAG_MIS),
        ("Russian roulette off", |s| s.settings.rr_start = 1_000_000),
        ("Russian roulette following luminance", |s| s.flags |= FLAG_RR_LUMINANCE),
    ];
    for (name, change) in variants {
        let mut v = default_small();
        change(&mut v);
        out.push(same_image_case(t, &format!("same image with {name}"), (&ref_images, bad0), &v, 100)?);
    }
    Ok(())
}

/// The region z-test of `setup`'s images (seeds from `first_seed`) against
/// the reference images of the small default scene.
fn same_image_case(
    t: &Device<'_>,
    name: &str,
    reference: (&[Image], u64),
    setup: &Setup,
    first_seed: u32,
) -> Result<CaseResult, GpuError> {
    let (images, bad) = setup.images(t, first_seed..first_seed + SEEDS)?;
    let (z, tests) = largest_region_z(reference.0, &images, 24, 24, 8);
    Ok(CaseResult::new(
        format!("{name}: largest region |z| of {tests}"),
        t.name(),
        0.0,
        z,
        0.0,
        REGION_Z_CRIT,
        bad + reference.1,
    ))
}

/// Scales and translates the default scene.
fn transformed(scale: f32, offset: Vec3) -> Scene {
    let mut s = Scene::default_scene();
    let f = |p: Vec3| p * scale + offset;
    s.camera.position = f(s.camera.position);
    s.camera.look_at = f(s.camera.look_at);
    s.light.center = f(s.light.center);
    s.light.radius *= scale;
    for w in &mut s.walls {
        let g = w.wall;
        w.wall = Wall::new(f(g.corner), g.edge_u * scale, g.edge_v * scale, g.albedo);
    }
    for sp in &mut s.spheres {
        sp.sphere.center = f(sp.sphere.center);
        sp.sphere.radius *= scale;
    }
    s
}

/// The default scene moved by `offset` along every axis, as a scene file
/// far from the origin gives it: written with its world coordinates in
/// f64 and read back, so the loader's camera-relative coordinates are what
/// is tested.
fn moved(offset: f64) -> Scene {
    let mut s = Scene::default_scene();
    s.origin += DVec3::splat(offset);
    Scene::from_toml(&s.to_toml(), std::path::Path::new("<moved scene>")).expect("a moved default scene is valid")
}

fn metamorphic(t: &Device<'_>, out: &mut Vec<CaseResult>) -> Result<(), GpuError> {
    let base = default_small();
    let (ref_images, bad0) = base.images(t, 0..SEEDS)?;
    for (name, scene) in [
        ("scene scaled by 1e-3", transformed(1e-3, Vec3::ZERO)),
        ("scene scaled by 1e3", transformed(1e3, Vec3::ZERO)),
        ("scene moved by 1e3", moved(1e3)),
        ("scene moved by 1e4", moved(1e4)),
        ("scene moved by 1e4 + 3.7", moved(1e4 + 3.7)),
        ("scene moved by 1e6", moved(1e6)),
        ("scene moved by 1e6 + 5.3", moved(1e6 + 5.3)),
    ] {
        let setup = Setup::new(scene, 24, 24, 16, 5);
        out.push(same_image_case(t, &format!("same image with the {name}"), (&ref_images, bad0), &setup, 200)?);
    }
    // Doubling the light doubles every sample exactly (same seed: the same
    // paths, and x2 is exact in floating point).
    let mut doubled = default_small();
    doubled.scene.light.radiance *= 2.0;
    let (a, _) = base.images(t, 0..1)?;
    let (b, bad) = doubled.images(t, 0..1)?;
    let worst = a[0]
        .iter()
        .zip(&b[0])
        .flat_map(|(x, y)| (0..3).map(move |c| ((y[c] - 2.0 * x[c]) as f64).abs()))
        .fold(0.0, f64::max);
    out.push(CaseResult::new(
        "doubling the light doubles the image: max |I2 - 2 I1|",
        t.name(),
        0.0,
        worst,
        0.0,
        0.0,
        bad,
    ));
    Ok(())
}

/// After 2^24 (and, full size, 2^25) samples per pixel the compensated mean
/// is still right: relative error under 1e-5 against an f64 sum of the
/// same samples. The samples are the background seen by camera rays in an
/// empty scene, 0.1 per channel: not representable in binary.
fn accumulation(t: &Device<'_>, size: Size, out: &mut Vec<CaseResult>) -> Result<(), GpuError> {
    let spp: u32 = if size == Size::Full { 1 << 25 } else { 1 << 24 };
    let mut scene = empty_scene(camera(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 40.0));
    scene.background = Vec3::splat(0.1);
    let mut setup = Setup::new(scene, 1, 1, spp, 5);
    // The case is about the sum, not the samples: independent ones are the
    // cheapest to draw 2^25 times on one GPU invocation.
    setup.flags &= !FLAG_SOBOL;
    let accum = render_accum(*t, setup.params(0), &[], &[], spp, 1 << 16)?;
    let p = accum[0];
    let expected = 0.1f32 as f64;
    let measured = p.mean().x as f64;
    out.push(CaseResult::new(
        format!("mean after {spp} samples per pixel (relative error < 1e-5)"),
        t.name(),
        expected,
        measured,
        0.0,
        1e-5 * expected,
        p.non_finite as u64,
    ));
    Ok(())
}

/// The report as a markdown table.
pub fn markdown_table(results: &[CaseResult]) -> String {
    let mut s = String::from(
        "| case | backend | expected | measured | std. error | tolerance | NaN/Inf | pass |\n|---|---|---|---|---|---|---|---|\n",
    );
    for r in results {
        s.push_str(&format!(
            "| {} | {} | {:.6e} | {:.6e} | {:.2e} | {:.2e} | {} | {} |\n",
            r.case,
            r.backend,
            r.expected,
            r.measured,
            r.stderr,
            r.tolerance,
            r.non_finite,
            if r.pass { "yes" } else { "**NO**" }
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_irradiance_matches_quadrature_in_all_regimes() {
        for sin_sigma in [0.05f64, 0.5, 0.95] {
            for theta in [0.1f64, 0.8, 1.4, PI / 2.0, 1.9, 2.5] {
                let exact = sphere_irradiance(theta.cos(), sin_sigma * sin_sigma);
                let quad = sphere_irradiance_quadrature(theta.cos(), sin_sigma * sin_sigma, 800);
                assert!((exact - quad).abs() < 2e-4 * (1.0 + quad), "sin {sin_sigma} theta {theta}: {exact} vs {quad}");
            }
        }
    }

    #[test]
    fn sphere_room_radiance_limits() {
        // One bounce: rho L s^2. Unlimited: the geometric series.
        assert!((sphere_room_radiance(0.5, 10.0, 0.1, 1) - 0.05).abs() < 1e-12);
        let b = sphere_room_radiance(0.5, 10.0, 0.1, 1_000_000);
        assert!((b - 0.5 * 10.0 * 0.01 / (1.0 - 0.5 * 0.99)).abs() < 1e-12);
        assert_eq!(sphere_room_radiance(0.0, 10.0, 0.1, 1_000_000), 0.0);
    }
}
