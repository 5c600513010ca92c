//! The viewer session as both shells drive it: egui input in, frames
//! traced on the GPU (lavapipe where there is no other), the reset rule
//! applied. The browser page runs this same code with `Waiting::Never`.

use egui::{Event, Key, Modifiers, PointerButton, Pos2, RawInput, Rect, vec2};
use pt_render::{GpuContext, Scene};
use pt_viewer::session::Waiting;
use pt_viewer::{Actions, Files, SamplesPerFrame, Session};

struct Harness {
    ctx: GpuContext,
    egui: egui::Context,
    session: Session,
}

impl Harness {
    fn new(waiting: Waiting) -> Self {
        let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
        let files = Files::default();
        let mut session =
            Session::new(&ctx, Scene::default_scene(), (64, 64), wgpu::TextureFormat::Rgba8Unorm, files, waiting)
                .unwrap();
        session.settings.samples_per_frame = SamplesPerFrame::Fixed(2);
        Self { ctx, egui: egui::Context::default(), session }
    }

    /// One frame of a 640x240-point window with these input events.
    fn frame(&mut self, events: Vec<Event>) -> Actions {
        let input = RawInput {
            screen_rect: Some(Rect::from_min_size(Pos2::ZERO, vec2(640.0, 240.0))),
            events,
            ..Default::default()
        };
        let (session, ctx) = (&mut self.session, &self.ctx);
        let mut actions = None;
        let mut output = self.egui.run_ui(input, |ui| actions = Some(session.frame(ui, ctx).unwrap()));
        output.textures_delta.clear();
        actions.unwrap()
    }

    /// Frames until `spp` samples per pixel are accumulated and the GPU is
    /// done (a browser session learns that a frame ended a frame later).
    fn trace_to(&mut self, spp: u64) {
        self.session.settings.target_spp = spp as u32;
        for _ in 0..1000 {
            self.frame(vec![]);
            if self.spp() == spp && self.session.idle() {
                return;
            }
            self.ctx.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
        }
        panic!("the session stopped at {} spp, not {spp}", self.spp());
    }

    fn spp(&self) -> u64 {
        self.session.stats.accumulated_spp
    }

    /// A point inside the image (right of the panel).
    fn over_image(&self) -> Pos2 {
        self.session.image_rect().center()
    }
}

#[test]
fn display_settings_keep_the_accumulation_and_scene_changes_restart_it() {
    for waiting in [Waiting::Block, Waiting::Never] {
        let mut h = Harness::new(waiting);
        h.trace_to(6);
        // The image fills the window right of the panel.
        let (w, hgt) = h.session.image_size();
        assert!(h.session.image_rect().min.x > 100.0, "no panel");
        // Its edges snap to whole pixels (one pixel per point here).
        let rect = h.session.image_rect();
        assert_eq!((w, hgt), ((rect.max.x.round() - rect.min.x.round()) as u32, 240), "{waiting:?}");

        // Exposure, tone map, pause: the expected image is the same.
        h.session.settings.exposure = 1.5;
        h.session.settings.tonemap = pt_core::params::TONEMAP_CLAMP;
        h.trace_to(8);
        // Had it restarted, it would hold the 2 samples of one frame.
        assert_eq!(h.spp(), 8, "a display change restarted the accumulation ({waiting:?})");

        // The light: another image, so the accumulation restarts: the
        // first frame after the change holds 2 samples, not 10.
        h.session.settings.scene.light.radius *= 1.5;
        h.frame(vec![]);
        assert_eq!(h.spp(), 2, "a scene change kept the old samples ({waiting:?})");

        // Samples per frame change the noise per frame, not the image.
        h.trace_to(4);
        h.session.settings.samples_per_frame = SamplesPerFrame::Fixed(3);
        h.trace_to(7);
    }
}

#[test]
fn dragging_the_image_orbits_and_restarts() {
    let mut h = Harness::new(Waiting::Block);
    h.session.settings.target_spp = 0;
    h.frame(vec![]);
    h.frame(vec![]);
    let camera = h.session.settings.scene.camera;
    let p = h.over_image();
    let button = |pressed, pos| Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers: Modifiers::NONE,
    };
    h.frame(vec![Event::PointerMoved(p), button(true, p)]);
    for i in 1..=5 {
        h.frame(vec![Event::PointerMoved(p + vec2(10.0 * i as f32, 0.0))]);
    }
    let q = p + vec2(50.0, 0.0);
    h.frame(vec![button(false, q)]);
    let moved = h.session.settings.scene.camera;
    assert_ne!(moved.position, camera.position, "a drag did not orbit");
    assert_eq!(moved.look_at, camera.look_at, "an orbit moved the look-at point");
    // Seven frames of 2 samples: 18 spp had nothing restarted; the last
    // moving frame restarted it, and the release frame added 2.
    assert!(h.spp() <= 4, "an orbit kept the old samples ({} spp)", h.spp());
}

#[test]
fn a_held_key_flies_the_camera() {
    let mut h = Harness::new(Waiting::Block);
    h.frame(vec![]);
    let camera = h.session.settings.scene.camera;
    let key =
        |pressed| Event::Key { key: Key::W, physical_key: None, pressed, repeat: false, modifiers: Modifiers::NONE };
    h.frame(vec![key(true)]);
    std::thread::sleep(std::time::Duration::from_millis(20));
    h.frame(vec![]);
    assert!(h.session.wants_frames(), "a held key must keep frames coming");
    h.frame(vec![key(false)]);
    let moved = h.session.settings.scene.camera;
    let forward = (camera.look_at - camera.position).normalize();
    let step = moved.position - camera.position;
    assert!(step.dot(forward) > 0.0, "W did not move forward: {step:?}");
    assert!(step.cross(forward).length() < 1e-4, "W moved sideways: {step:?}");
}

#[test]
fn a_bad_scene_file_keeps_the_scene_and_says_why() {
    let mut h = Harness::new(Waiting::Never);
    h.trace_to(2);
    let scene = h.session.settings.scene.clone();
    let mut bad = scene.clone();
    bad.light.radius = -0.1;
    let bad = bad.to_toml();
    assert!(!h.session.load_scene_text("bad.toml", &bad));
    assert_eq!(h.session.settings.scene, scene);
    let status = &h.session.files.status;
    // The command line's wording: the file, the line and the field.
    let expected = pt_viewer::error_chain(&Scene::from_toml(&bad, "bad.toml".as_ref()).unwrap_err());
    assert_eq!(status, &format!("error: {expected}"));
    assert!(status.starts_with("error: bad.toml:") && status.contains("light.radius"), "{status}");

    let mut other = scene.clone();
    other.light.radius = 0.2;
    assert!(h.session.load_scene_text("good.toml", &other.to_toml()));
    h.trace_to(2);
    assert_eq!(h.session.settings.scene.light.radius, 0.2);
    assert_eq!(h.session.files.status, "loaded good.toml");
}
