//! Scene files: TOML with unknown fields rejected, every value checked, and
//! errors that name the file, the line and the field.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use pt_core::geometry::{MAX_SPHERES, MAX_WALLS};
use pt_core::glam::{DVec3, Vec3};
use pt_core::params::TONEMAP_ACES;
use pt_core::{Camera, FrameParams, Geometry, Sphere, SphereLight, Tile, Wall};
use serde::Deserialize;
use toml::Spanned;

/// The built-in default scene: `scenes/default.toml`, embedded.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../../scenes/default.toml");
/// The name the embedded default scene goes by in messages.
pub const DEFAULT_SCENE_NAME: &str = "<built-in default scene>";

/// Largest image side accepted, in pixels (16K): beyond it buffers outgrow
/// what GPUs bind.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest `max_bounces` accepted. Russian roulette ends paths long before.
pub const MAX_BOUNCES_LIMIT: u32 = 1_000_000;

/// More walls or spheres than the kernel's geometry block holds (the
/// scene loader reports such files with their line first).
#[derive(Debug, Clone, Copy, thiserror::Error)]
#[error("{walls} walls and {spheres} spheres: the renderer holds at most {MAX_WALLS} walls and {MAX_SPHERES} spheres")]
pub struct TooManyObjects {
    /// Walls given.
    pub walls: usize,
    /// Spheres given.
    pub spheres: usize,
}

/// The kernel's geometry block holding `walls` and `spheres`.
pub fn geometry(walls: &[Wall], spheres: &[Sphere]) -> Result<Geometry, TooManyObjects> {
    Geometry::new(walls, spheres).ok_or(TooManyObjects { walls: walls.len(), spheres: spheres.len() })
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read the scene file: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// TOML syntax, a wrong type, a missing or unknown field.
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// A value that parses but cannot be rendered.
    #[error("{path}:{line}: {field}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// 1-based line of the offending value.
        line: usize,
        /// Dotted path of the field, e.g. `spheres[1].radius`.
        field: String,
        /// What is wrong with it.
        message: String,
    },
}

/// Three numbers of a scene file, read in f64: positions far from the
/// origin keep their precision until the camera's neighbourhood is
/// subtracted (see [`Scene::origin`]).
type V3 = Spanned<[f64; 3]>;

/// Spacing of the grid that [`Scene::origin`] is snapped to. A power of two
/// far above a scene's detail: scenes near the world origin keep origin 0
/// (their coordinates are read as before), and any other origin is exact
/// in f32 and f64 and leaves the camera within 8 units of it.
const ORIGIN_GRID: f64 = 16.0;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    background: Option<V3>,
    camera: CameraFile,
    #[serde(default)]
    render: RenderFile,
    light: LightFile,
    #[serde(default)]
    walls: Vec<WallFile>,
    #[serde(default)]
    spheres: Vec<SphereFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    position: V3,
    look_at: V3,
    #[serde(default)]
    up: Option<V3>,
    vfov_degrees: Spanned<f32>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderFile {
    width: Option<Spanned<i64>>,
    height: Option<Spanned<i64>>,
    spp: Option<Spanned<i64>>,
    max_bounces: Option<Spanned<i64>>,
    rr_start: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightFile {
    center: V3,
    radius: Spanned<f32>,
    radiance: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WallFile {
    #[serde(default)]
    name: Option<String>,
    corner: V3,
    edge_u: V3,
    edge_v: V3,
    albedo: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereFile {
    #[serde(default)]
    name: Option<String>,
    center: V3,
    radius: Spanned<f32>,
    albedo: V3,
}

/// The camera as a user describes it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CameraDesc {
    /// Pinhole position.
    pub position: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
    /// Rough up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_degrees: f32,
}

impl CameraDesc {
    /// The kernel's camera for a film of `width` x `height` pixels.
    pub fn to_gpu(&self, width: u32, height: u32) -> Camera {
        Camera::look_at(self.position, self.look_at, self.up, self.vfov_degrees, width as f32 / height as f32)
    }
}

/// Bounces before Russian roulette starts, by default. `pathtracer bench`
/// found roulette from bounce 3 slower to a given error than none at all on
/// the default scene with Sobol samples (roulette's random cut-offs undo
/// part of the stratification), so it starts at 5: never within the
/// default 5 bounces, still there for deeper limits.
pub const DEFAULT_RR_START: u32 = 5;

/// Render settings; a scene file may set them, the command line overrides.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel in all.
    pub spp: u32,
    /// Maximum scattering events per path (docs/ARCHITECTURE.md, Conventions).
    pub max_bounces: u32,
    /// Bounces before Russian roulette starts.
    pub rr_start: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { width: 512, height: 512, spp: 256, max_bounces: 5, rr_start: DEFAULT_RR_START }
    }
}

/// A named wall.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedWall {
    /// Name shown in the viewer and in messages.
    pub name: String,
    /// The wall.
    pub wall: Wall,
}

/// A named sphere.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedSphere {
    /// Name shown in the viewer and in messages.
    pub name: String,
    /// The sphere.
    pub sphere: Sphere,
}

/// A validated scene.
///
/// Positions (camera, light, wall corners, sphere centres) are relative to
/// [`Scene::origin`], a point near the camera: a file's coordinates are
/// read in f64 and the origin subtracted before they become f32, so a scene
/// 10^6 units from the world origin keeps the precision it would have at
/// it. The kernel sees these camera-relative coordinates only.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// World position of the scene's own origin: the camera's position
    /// rounded to a multiple of 16 (0 for scenes near the world origin).
    pub origin: DVec3,
    /// The camera.
    pub camera: CameraDesc,
    /// The light.
    pub light: SphereLight,
    /// The walls.
    pub walls: Vec<NamedWall>,
    /// The spheres.
    pub spheres: Vec<NamedSphere>,
    /// Radiance of escaping rays.
    pub background: Vec3,
    /// Render settings from the file (or defaults).
    pub render: RenderSettings,
}

impl Scene {
    /// The built-in default scene, `scenes/default.toml`.
    pub fn default_scene() -> Self {
        Self::from_toml(DEFAULT_SCENE_TOML, Path::new(DEFAULT_SCENE_NAME)).expect("the embedded default scene is valid")
    }

    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_owned(), source })?;
        Self::from_toml(&text, path)
    }

    /// Parses and validates scene TOML; `path` names it in messages.
    pub fn from_toml(text: &str, path: &Path) -> Result<Self, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map(|s| line_col(text, s.start)).unwrap_or((1, 1));
            SceneError::Syntax { path: path.to_owned(), line, column, message: e.message().trim().to_owned() }
        })?;
        let camera = DVec3::from_array(*file.camera.position.get_ref());
        let origin = if camera.is_finite() { (camera / ORIGIN_GRID).round() * ORIGIN_GRID } else { DVec3::ZERO };
        Checker { text, path, origin }.scene(file)
    }

    /// Checks a scene edited in memory (the viewer's panel) against the
    /// rules the loader applies to files, by writing and re-reading it.
    pub fn validate(&self) -> Result<(), SceneError> {
        Self::from_toml(&self.to_toml(), Path::new("<edited scene>")).map(|_| ())
    }

    /// The kernel's walls.
    pub fn gpu_walls(&self) -> Vec<Wall> {
        self.walls.iter().map(|w| w.wall).collect()
    }

    /// The kernel's spheres.
    pub fn gpu_spheres(&self) -> Vec<Sphere> {
        self.spheres.iter().map(|s| s.sphere).collect()
    }

    /// The kernel's geometry block (walls and spheres).
    pub fn geometry(&self) -> Result<Geometry, TooManyObjects> {
        geometry(&self.gpu_walls(), &self.gpu_spheres())
    }

    /// The kernel's parameters for frame 0 of a render with `settings`,
    /// with the scene's default flags.
    pub fn frame_params(&self, settings: &RenderSettings, samples_per_frame: u32, seed: u32) -> FrameParams {
        let flags = self.default_flags();
        self.frame_params_with_flags(settings, samples_per_frame, seed, flags)
    }

    /// [`Scene::frame_params`] with integrator `flags` of the caller's
    /// choosing (the viewer's switches), without working out the default
    /// ones, which take a pass over the scene's surfaces.
    pub fn frame_params_with_flags(
        &self,
        settings: &RenderSettings,
        samples_per_frame: u32,
        seed: u32,
        flags: u32,
    ) -> FrameParams {
        FrameParams {
            camera: self.camera.to_gpu(settings.width, settings.height),
            light: self.light,
            background: self.background,
            exposure: 0.0,
            width: settings.width,
            height: settings.height,
            frame: 0,
            samples_per_frame,
            max_bounces: settings.max_bounces,
            rr_start: settings.rr_start,
            seed,
            wall_count: self.walls.len() as u32,
            sphere_count: self.spheres.len() as u32,
            tonemap: TONEMAP_ACES,
            flags,
            sample_offset: 0,
            tile: Tile::whole(settings.width, settings.height),
        }
    }

    /// The integrator flags this scene renders with unless told otherwise
    /// (`strategy::default_flags`: the project's defaults, adapted to the
    /// light and the room).
    pub fn default_flags(&self) -> u32 {
        crate::strategy::default_flags(self)
    }

    /// The scene as TOML that [`Scene::from_toml`] reads back unchanged.
    pub fn to_toml(&self) -> String {
        let v = |v: Vec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
        // Positions in world coordinates: the f32 ones where the origin is 0
        // (as they were read), else origin + position in f64, which reads
        // back to the same f32 position.
        let origin = self.origin;
        let p = |p: Vec3| {
            if origin == DVec3::ZERO {
                v(p)
            } else {
                let w = origin + p.as_dvec3();
                format!("[{:?}, {:?}, {:?}]", w.x, w.y, w.z)
            }
        };
        let mut s = String::new();
        let _ = writeln!(s, "background = {}\n", v(self.background));
        let c = &self.camera;
        let _ = writeln!(
            s,
            "[camera]\nposition = {}\nlook_at = {}\nup = {}\nvfov_degrees = {:?}\n",
            p(c.position),
            p(c.look_at),
            v(c.up),
            c.vfov_degrees
        );
        let r = &self.render;
        let _ = writeln!(
            s,
            "[render]\nwidth = {}\nheight = {}\nspp = {}\nmax_bounces = {}\nrr_start = {}\n",
            r.width, r.height, r.spp, r.max_bounces, r.rr_start
        );
        let l = &self.light;
        let _ =
            writeln!(s, "[light]\ncenter = {}\nradius = {:?}\nradiance = {}\n", p(l.center), l.radius, v(l.radiance));
        for w in &self.walls {
            let g = &w.wall;
            let _ = writeln!(
                s,
                "[[walls]]\nname = {:?}\ncorner = {}\nedge_u = {}\nedge_v = {}\nalbedo = {}\n",
                w.name,
                p(g.corner),
                v(g.edge_u),
                v(g.edge_v),
                v(g.albedo)
            );
        }
        for sp in &self.spheres {
            let g = &sp.sphere;
            let _ = writeln!(
                s,
                "[[spheres]]\nname = {:?}\ncenter = {}\nradius = {:?}\nalbedo = {}\n",
                sp.name,
                p(g.center),
                g.radius,
                v(g.albedo)
            );
        }
        s
    }
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, column)
}

/// Validation with access to the source text for line numbers.
struct Checker<'a> {
    text: &'a str,
    path: &'a Path,
    /// The scene's origin ([`Scene::origin`]), subtracted from positions.
    origin: DVec3,
}

impl Checker<'_> {
    fn err<T>(&self, span: std::ops::Range<usize>, field: &str, message: impl Into<String>) -> Result<T, SceneError> {
        Err(SceneError::Invalid {
            path: self.path.to_owned(),
            line: line_col(self.text, span.start).0,
            field: field.to_owned(),
            message: message.into(),
        })
    }

    /// The three numbers, which must be finite in f64.
    fn finite_f64(&self, v: &V3, field: &str) -> Result<DVec3, SceneError> {
        let a = *v.get_ref();
        if a.iter().any(|x| !x.is_finite()) {
            return self.err(v.span(), field, format!("every component must be a finite number, got {a:?}"));
        }
        Ok(DVec3::from_array(a))
    }

    /// A vector (a direction, an edge, a colour), which must be finite in
    /// f32.
    fn finite(&self, v: &V3, field: &str) -> Result<Vec3, SceneError> {
        self.in_f32(v, field, self.finite_f64(v, field)?)
    }

    /// A position, relative to the scene's origin.
    fn position(&self, v: &V3, field: &str) -> Result<Vec3, SceneError> {
        self.in_f32(v, field, self.finite_f64(v, field)? - self.origin)
    }

    fn in_f32(&self, v: &V3, field: &str, x: DVec3) -> Result<Vec3, SceneError> {
        let f = x.as_vec3();
        if !f.is_finite() {
            return self.err(
                v.span(),
                field,
                format!("{:?} is too large for the renderer's 32-bit floats", v.get_ref()),
            );
        }
        Ok(f)
    }

    fn albedo(&self, v: &V3, field: &str) -> Result<Vec3, SceneError> {
        let a = self.finite(v, field)?;
        if a.min_element() < 0.0 || a.max_element() > 1.0 {
            return self.err(v.span(), field, format!("albedo components must lie in [0, 1], got {:?}", v.get_ref()));
        }
        Ok(a)
    }

    fn radius(&self, r: &Spanned<f32>, field: &str) -> Result<f32, SceneError> {
        let x = *r.get_ref();
        if !x.is_finite() || x <= 0.0 {
            return self.err(r.span(), field, format!("radius must be a positive finite number, got {x}"));
        }
        Ok(x)
    }

    fn count(
        &self,
        v: &Option<Spanned<i64>>,
        field: &str,
        default: u32,
        min: i64,
        max: u32,
    ) -> Result<u32, SceneError> {
        match v {
            None => Ok(default),
            Some(s) => {
                let x = *s.get_ref();
                if x < min || x > max as i64 {
                    return self.err(s.span(), field, format!("must be an integer in [{min}, {max}], got {x}"));
                }
                Ok(x as u32)
            }
        }
    }

    fn scene(&self, f: SceneFile) -> Result<Scene, SceneError> {
        let background = match &f.background {
            Some(b) => {
                let v = self.finite(b, "background")?;
                if v.min_element() < 0.0 {
                    return self.err(b.span(), "background", "radiance cannot be negative");
                }
                v
            }
            None => Vec3::ZERO,
        };

        let c = &f.camera;
        let position = self.position(&c.position, "camera.position")?;
        let look_at = self.position(&c.look_at, "camera.look_at")?;
        let up = match &c.up {
            Some(u) => self.finite(u, "camera.up")?,
            None => Vec3::Y,
        };
        let view = look_at - position;
        if view.length_squared() == 0.0 || !view.length_squared().is_finite() {
            return self.err(c.look_at.span(), "camera.look_at", "must differ from camera.position");
        }
        if view.normalize().cross(up).length_squared() < 1e-12 {
            let span = c.up.as_ref().map_or(c.look_at.span(), |u| u.span());
            return self.err(span, "camera.up", "must not be zero or parallel to the viewing direction");
        }
        let fov = *c.vfov_degrees.get_ref();
        if !(fov > 0.0 && fov < 180.0) {
            return self.err(c.vfov_degrees.span(), "camera.vfov_degrees", format!("must lie in (0, 180), got {fov}"));
        }

        let d = RenderSettings::default();
        let r = &f.render;
        let render = RenderSettings {
            width: self.count(&r.width, "render.width", d.width, 1, MAX_IMAGE_SIDE)?,
            height: self.count(&r.height, "render.height", d.height, 1, MAX_IMAGE_SIDE)?,
            spp: self.count(&r.spp, "render.spp", d.spp, 1, u32::MAX)?,
            max_bounces: self.count(&r.max_bounces, "render.max_bounces", d.max_bounces, 0, MAX_BOUNCES_LIMIT)?,
            rr_start: self.count(&r.rr_start, "render.rr_start", d.rr_start, 1, MAX_BOUNCES_LIMIT)?,
        };

        let l = &f.light;
        let radiance = self.finite(&l.radiance, "light.radiance")?;
        if radiance.min_element() < 0.0 {
            return self.err(l.radiance.span(), "light.radiance", "radiance cannot be negative");
        }
        let light = SphereLight::new(
            self.position(&l.center, "light.center")?,
            self.radius(&l.radius, "light.radius")?,
            radiance,
        );

        let mut walls = Vec::with_capacity(f.walls.len());
        for (i, w) in f.walls.iter().enumerate() {
            let field = |name: &str| format!("walls[{i}].{name}");
            if i == MAX_WALLS {
                return self.err(w.corner.span(), &format!("walls[{i}]"), format!("at most {MAX_WALLS} walls"));
            }
            let corner = self.position(&w.corner, &field("corner"))?;
            let edge_u = self.finite(&w.edge_u, &field("edge_u"))?;
            let edge_v = self.finite(&w.edge_v, &field("edge_v"))?;
            let albedo = self.albedo(&w.albedo, &field("albedo"))?;
            // Zero area: a zero edge, or edges (nearly) parallel.
            let area = edge_u.cross(edge_v).length();
            if area <= 1e-6 * edge_u.length() * edge_v.length() || !area.is_finite() {
                return self.err(
                    w.edge_v.span(),
                    &field("edge_v"),
                    "the wall has zero area: edges are zero or parallel",
                );
            }
            let wall = Wall::new(corner, edge_u, edge_v, albedo);
            walls.push(NamedWall { name: w.name.clone().unwrap_or_else(|| format!("wall {}", i + 1)), wall });
        }

        let mut spheres = Vec::with_capacity(f.spheres.len());
        for (i, s) in f.spheres.iter().enumerate() {
            let field = |name: &str| format!("spheres[{i}].{name}");
            if i == MAX_SPHERES {
                return self.err(s.center.span(), &format!("spheres[{i}]"), format!("at most {MAX_SPHERES} spheres"));
            }
            let sphere = Sphere::new(
                self.position(&s.center, &field("center"))?,
                self.radius(&s.radius, &field("radius"))?,
                self.albedo(&s.albedo, &field("albedo"))?,
            );
            spheres.push(NamedSphere { name: s.name.clone().unwrap_or_else(|| format!("sphere {}", i + 1)), sphere });
        }

        Ok(Scene {
            origin: self.origin,
            camera: CameraDesc { position, look_at, up, vfov_degrees: fov },
            light,
            walls,
            spheres,
            background,
            render,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Scene, SceneError> {
        Scene::from_toml(text, Path::new("test.toml"))
    }

    /// The default scene with `from` replaced by `to` (which must occur).
    fn with(from: &str, to: &str) -> String {
        assert!(DEFAULT_SCENE_TOML.contains(from), "{from:?} not in the default scene");
        DEFAULT_SCENE_TOML.replacen(from, to, 1)
    }

    fn invalid(text: &str) -> (usize, String, String) {
        match load(text) {
            Err(SceneError::Invalid { line, field, message, .. }) => (line, field, message),
            other => panic!("expected an invalid-value error, got {other:?}"),
        }
    }

    fn line_of(text: &str, needle: &str) -> usize {
        text[..text.find(needle).unwrap()].matches('\n').count() + 1
    }

    #[test]
    fn default_scene_has_the_design_numbers() {
        let s = Scene::default_scene();
        assert_eq!(s.walls.len(), 5);
        assert_eq!(s.spheres.len(), 2);
        assert_eq!(s.light, SphereLight::new(Vec3::new(0.0, 1.7, 0.0), 0.15, Vec3::splat(20.0)));
        assert_eq!(s.spheres[0].sphere, Sphere::new(Vec3::new(-0.45, 0.40, -0.30), 0.40, Vec3::splat(0.73)));
        assert_eq!(s.spheres[1].sphere, Sphere::new(Vec3::new(0.50, 0.28, 0.35), 0.28, Vec3::new(0.20, 0.40, 0.80)));
        assert_eq!(s.camera.position, Vec3::new(0.0, 1.0, 3.4));
        assert_eq!(s.camera.vfov_degrees, 40.0);
        assert_eq!(s.render.max_bounces, 5);
        assert_eq!(s.background, Vec3::ZERO);
        // Both spheres rest exactly on the floor (y = 0).
        for sp in &s.spheres {
            assert_eq!(sp.sphere.center.y - sp.sphere.radius, 0.0);
        }
        // Walls span the room x in [-1, 1], y in [0, 2], z in [-1, 1].
        let area: f32 = s.walls.iter().map(|w| w.wall.area()).sum();
        assert_eq!(area, 20.0);
    }

    #[test]
    fn more_objects_than_the_geometry_block_holds_are_rejected() {
        let sphere = |i: usize| {
            format!("\n[[spheres]]\ncenter = [{i}.0, 0.0, -9.0] # extra\nradius = 0.1\nalbedo = [0.5, 0.5, 0.5]\n")
        };
        let wall = |i: usize| {
            format!(
                "\n[[walls]]\ncorner = [{i}.0, 0.0, -9.0] # extra\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 1.0, 0.0]\nalbedo = [0.5, 0.5, 0.5]\n"
            )
        };
        // The default scene has 5 walls and 2 spheres: fill up to the limits.
        let full: String = (5..MAX_WALLS).map(wall).chain((2..MAX_SPHERES).map(sphere)).collect();
        let scene = load(&format!("{DEFAULT_SCENE_TOML}{full}")).unwrap();
        assert_eq!((scene.walls.len(), scene.spheres.len()), (MAX_WALLS, MAX_SPHERES));
        assert!(scene.geometry().is_ok());

        let text = format!("{DEFAULT_SCENE_TOML}{full}{}", wall(MAX_WALLS));
        let (line, field, message) = invalid(&text);
        assert_eq!(line, line_of(&text, &format!("corner = [{MAX_WALLS}.0")));
        assert_eq!((field, message), (format!("walls[{MAX_WALLS}]"), format!("at most {MAX_WALLS} walls")));

        let text = format!("{DEFAULT_SCENE_TOML}{full}{}", sphere(MAX_SPHERES));
        let (line, field, message) = invalid(&text);
        assert_eq!(line, line_of(&text, &format!("center = [{MAX_SPHERES}.0")));
        assert_eq!((field, message), (format!("spheres[{MAX_SPHERES}]"), format!("at most {MAX_SPHERES} spheres")));
    }

    #[test]
    fn to_toml_round_trips() {
        let s = Scene::default_scene();
        assert_eq!(load(&s.to_toml()).unwrap(), s);
    }

    #[test]
    fn negative_radius_names_line_and_field() {
        let text = with("radius = 0.28", "radius = -0.28");
        let (line, field, _) = invalid(&text);
        assert_eq!(field, "spheres[1].radius");
        assert_eq!(line, line_of(&text, "radius = -0.28"));
    }

    #[test]
    fn zero_light_radius_is_rejected() {
        let (_, field, _) = invalid(&with("radius = 0.15", "radius = 0.0"));
        assert_eq!(field, "light.radius");
    }

    #[test]
    fn degenerate_wall_is_rejected() {
        // Parallel edges: zero area.
        let text = with("edge_v = [0.0, 2.0, 0.0]", "edge_v = [4.0, 0.0, 0.0]");
        let (line, field, message) = invalid(&text);
        assert_eq!(field, "walls[2].edge_v");
        assert_eq!(line, line_of(&text, "edge_v = [4.0, 0.0, 0.0]"));
        assert!(message.contains("zero area"));
    }

    #[test]
    fn nan_and_infinity_are_rejected() {
        let (_, field, _) = invalid(&with("center = [0.0, 1.7, 0.0]", "center = [nan, 1.7, 0.0]"));
        assert_eq!(field, "light.center");
        let (_, field, _) = invalid(&with("albedo = [0.20, 0.40, 0.80]", "albedo = [0.20, inf, 0.80]"));
        assert_eq!(field, "spheres[1].albedo");
    }

    #[test]
    fn albedo_above_one_is_rejected() {
        let (_, field, _) = invalid(&with("albedo = [0.65, 0.05, 0.05]", "albedo = [1.65, 0.05, 0.05]"));
        assert_eq!(field, "walls[3].albedo");
    }

    #[test]
    fn non_positive_image_size_and_spp_are_rejected() {
        assert_eq!(invalid(&with("width = 512", "width = 0")).1, "render.width");
        assert_eq!(invalid(&with("height = 512", "height = -3")).1, "render.height");
        assert_eq!(invalid(&with("spp = 256", "spp = 0")).1, "render.spp");
    }

    #[test]
    fn unknown_field_is_a_syntax_error_with_its_line() {
        let text = with("radius = 0.40", "radius = 0.40\nradious = 0.5");
        match load(&text) {
            Err(SceneError::Syntax { line, message, .. }) => {
                assert_eq!(line, line_of(&text, "radious"));
                assert!(message.contains("radious"), "{message}");
            }
            other => panic!("expected a syntax error, got {other:?}"),
        }
    }

    #[test]
    fn broken_toml_is_a_syntax_error_with_its_line() {
        let text = with("[light]", "[light");
        match load(&text) {
            Err(SceneError::Syntax { line, .. }) => assert_eq!(line, line_of(&text, "[light")),
            other => panic!("expected a syntax error, got {other:?}"),
        }
    }

    #[test]
    fn camera_up_parallel_to_view_is_rejected() {
        let (_, field, _) = invalid(&with("up = [0.0, 1.0, 0.0]", "up = [0.0, 0.0, 2.0]"));
        assert_eq!(field, "camera.up");
    }

    #[test]
    fn messages_name_file_line_and_field() {
        let err = load(&with("radius = 0.28", "radius = -1.0")).unwrap_err().to_string();
        assert!(err.starts_with("test.toml:"), "{err}");
        assert!(err.contains("spheres[1].radius"), "{err}");
    }
}
