//! What the viewer's user can change, and the one rule that decides when a
//! change invalidates the accumulated image.

use pt_core::FrameParams;
use pt_core::params::{FLAG_LIGHT_EDGE, TONEMAP_ACES};
use pt_render::strategy::silhouette_in_view;
use pt_render::{RenderSettings, Scene};

/// How many samples each frame traces.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum SamplesPerFrame {
    /// Adapted each frame so that tracing fits the frame-time budget.
    Auto {
        /// Milliseconds of tracing per frame to aim for.
        budget_ms: f32,
    },
    /// Fixed by hand.
    Fixed(u32),
}

/// Every setting of the viewer.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSettings {
    /// The scene, camera included.
    pub scene: Scene,
    /// Traced image size (the window's size in physical pixels).
    pub width: u32,
    /// Traced image height.
    pub height: u32,
    /// Maximum scattering events per path.
    pub max_bounces: u32,
    /// Bounces before Russian roulette starts.
    pub rr_start: u32,
    /// Integrator switches (`pt_core::params::FLAG_*`).
    pub flags: u32,
    /// Samples per frame policy.
    pub samples_per_frame: SamplesPerFrame,
    /// Stop tracing at this many samples per pixel (0: never).
    pub target_spp: u32,
    /// Tracing paused.
    pub paused: bool,
    /// Display exposure, stops.
    pub exposure: f32,
    /// Display tone mapper (`pt_core::params::TONEMAP_*`).
    pub tonemap: u32,
}

/// The part of the settings that determines the expected image: the
/// scene, the camera, the image size and the bounce limit.
///
/// Everything else leaves the expectation unchanged: Russian roulette, NEE
/// and MIS change the noise, not the mean (all unbiased); samples per frame,
/// the target, pause, exposure and the tone mapper are about how the
/// image is traced or shown.
#[derive(Clone, Debug, PartialEq)]
struct ExpectedImage<'a> {
    scene: &'a Scene,
    width: u32,
    height: u32,
    max_bounces: u32,
}

impl ViewSettings {
    /// Settings for `scene` traced at `width` x `height`.
    pub fn new(scene: Scene, width: u32, height: u32) -> Self {
        let render = scene.render;
        Self {
            flags: scene.default_flags(),
            scene,
            width,
            height,
            max_bounces: render.max_bounces,
            rr_start: render.rr_start,
            samples_per_frame: SamplesPerFrame::Auto { budget_ms: 30.0 },
            target_spp: 0,
            paused: false,
            exposure: 0.0,
            tonemap: TONEMAP_ACES,
        }
    }

    /// Sets the light edge's control variate (`FLAG_LIGHT_EDGE`) as the
    /// scene's default strategy would for the current camera: on where the
    /// camera sees the whole rim of the light, off where a wall or a sphere
    /// hides part of it (`strategy::silhouette_in_view`; its samples would
    /// then carry a step the image does not have). The panel has no switch
    /// for it, so it follows every move of the camera and every edit of
    /// the scene; the other flags stay as they are.
    pub fn follow_edge_rule(&mut self) {
        self.flags =
            if silhouette_in_view(&self.scene) { self.flags | FLAG_LIGHT_EDGE } else { self.flags & !FLAG_LIGHT_EDGE };
    }

    fn expected_image(&self) -> ExpectedImage<'_> {
        ExpectedImage { scene: &self.scene, width: self.width, height: self.height, max_bounces: self.max_bounces }
    }

    /// The kernel's parameters for these settings (frame and samples per
    /// frame are set per dispatch).
    pub fn frame_params(&self) -> FrameParams {
        let render = RenderSettings {
            width: self.width,
            height: self.height,
            max_bounces: self.max_bounces,
            rr_start: self.rr_start,
            spp: 1,
        };
        let mut p = self.scene.frame_params_with_flags(&render, 1, 0, self.flags);
        p.exposure = self.exposure;
        p.tonemap = self.tonemap;
        p
    }
}

/// Whether going from `old` to `new` invalidates the accumulated samples.
/// Every change in the viewer goes through here.
pub fn invalidates_accumulation(old: &ViewSettings, new: &ViewSettings) -> bool {
    old.expected_image() != new.expected_image()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_core::glam::Vec3;
    use pt_core::params::{FLAG_NEE, TONEMAP_CLAMP};
    use std::path::Path;

    fn base() -> ViewSettings {
        ViewSettings::new(Scene::default_scene(), 320, 240)
    }

    /// Asserts whether `change` applied to the base settings resets.
    fn resets(change: impl FnOnce(&mut ViewSettings)) -> bool {
        let old = base();
        let mut new = old.clone();
        change(&mut new);
        invalidates_accumulation(&old, &new)
    }

    #[test]
    fn no_change_keeps_accumulation() {
        assert!(!resets(|_| {}));
    }

    #[test]
    fn camera_changes_reset() {
        assert!(resets(|s| s.scene.camera.position.x += 0.1));
        assert!(resets(|s| s.scene.camera.look_at.y -= 0.1));
        assert!(resets(|s| s.scene.camera.vfov_degrees = 50.0));
    }

    #[test]
    fn scene_changes_reset() {
        assert!(resets(|s| s.scene.light.radius = 0.2));
        assert!(resets(|s| s.scene.light.center.y = 1.5));
        assert!(resets(|s| s.scene.light.radiance = Vec3::splat(10.0)));
        assert!(resets(|s| s.scene.spheres[0].sphere.radius = 0.3));
        assert!(resets(|s| s.scene.spheres[1].sphere.center.x = 0.0));
        assert!(resets(|s| s.scene.spheres[1].sphere.albedo = Vec3::ONE));
        assert!(resets(|s| s.scene.walls[3].wall.albedo = Vec3::ONE));
        assert!(resets(|s| s.scene.background = Vec3::splat(0.1)));
    }

    #[test]
    fn size_and_bounce_limit_reset() {
        assert!(resets(|s| s.width = 321));
        assert!(resets(|s| s.height = 200));
        assert!(resets(|s| s.max_bounces = 4));
    }

    #[test]
    fn unbiased_estimator_choices_keep_accumulation() {
        // Same expected image, different noise: the samples stay valid.
        assert!(!resets(|s| s.rr_start = 1));
        assert!(!resets(|s| s.flags = FLAG_NEE));
    }

    #[test]
    fn trace_control_keeps_accumulation() {
        assert!(!resets(|s| s.samples_per_frame = SamplesPerFrame::Fixed(16)));
        assert!(!resets(|s| s.target_spp = 1024));
        assert!(!resets(|s| s.paused = true));
    }

    /// Around the probe whose large sphere hides part of the light's rim
    /// from the scene's camera, the edge's control variate is off; seen
    /// from above the light, with the whole rim in view, on; back at the
    /// scene's camera, off again. No other flag moves.
    #[test]
    fn the_light_edge_follows_the_camera() {
        let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/probe/low-medium.toml"));
        let scene = Scene::load(path).unwrap();
        let mut s = ViewSettings::new(scene, 64, 64);
        let others = s.flags & !FLAG_LIGHT_EDGE;
        assert_eq!(s.flags & FLAG_LIGHT_EDGE, 0);
        let camera = s.scene.camera;
        s.scene.camera.position = s.scene.light.center + Vec3::new(0.0, 1.0, 0.6);
        s.scene.camera.look_at = s.scene.light.center;
        assert!(silhouette_in_view(&s.scene));
        s.follow_edge_rule();
        assert_eq!(s.flags, others | FLAG_LIGHT_EDGE);
        s.scene.camera = camera;
        s.follow_edge_rule();
        assert_eq!(s.flags, others);
    }

    #[test]
    fn display_settings_never_reset() {
        assert!(!resets(|s| s.exposure = 2.5));
        assert!(!resets(|s| s.tonemap = TONEMAP_CLAMP));
    }
}
