//! One viewer session: the settings, the renderer that traces them, the
//! frame loop's policy, and the image drawn inside the egui frame.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::{Arc, Mutex};

use egui::{Event, Key, MouseWheelUnit, Sense};
use pt_render::gpu::{Blit, GpuTimer, PendingRead, TraceKernel};
use pt_render::scene::CameraDesc;
use pt_render::{GpuContext, GpuError, GpuRenderer, Scene, SceneError};

use crate::Instant;
use crate::camera_control::{FLY_SPEED, ORBIT_RADIANS_PER_PIXEL, fly, orbit, zoom};
use crate::panel::{self, Actions, Files, Stats};
use crate::settings::{SamplesPerFrame, ViewSettings, invalidates_accumulation};

/// Points of wheel travel per notch, for wheels that report points (the
/// browser, touchpads): what a desktop reports as one line.
const POINTS_PER_NOTCH: f32 = 40.0;

/// How a session waits for the GPU.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Waiting {
    /// Each traced frame is waited for: exact frame times, GPU timestamps
    /// where the adapter has them (a desktop).
    Block,
    /// Nothing waits: at most one traced frame is in flight, and the queue
    /// reports when it is done (a browser, where nothing may block).
    Never,
}

/// A traced frame that the GPU has not finished ([`Waiting::Never`]).
struct InFlight {
    submitted: Instant,
    spp: u32,
    done: Arc<Mutex<Option<Instant>>>,
}

/// The viewer's state between frames.
pub struct Session {
    /// Settings as the panel and the controls leave them.
    pub settings: ViewSettings,
    /// Settings the accumulation was traced with.
    applied: ViewSettings,
    /// The camera of the scene file, for "reset view".
    initial_camera: CameraDesc,
    renderer: GpuRenderer,
    blit: Blit,
    blit_group: wgpu::BindGroup,
    timer: Option<GpuTimer>,
    waiting: Waiting,
    in_flight: Option<InFlight>,
    non_finite: Option<PendingRead>,
    /// Live figures shown in the panel.
    pub stats: Stats,
    /// File fields and the last file operation's result.
    pub files: Files,
    /// Samples per frame chosen by the automatic policy.
    auto_spp: u32,
    /// Whether the display buffer is stale (new samples or display change).
    display_dirty: bool,
    /// Whether a fly key was held in the last frame.
    flying: bool,
    frames_traced: u32,
    last_frame: Option<Instant>,
    /// When recent frames started, for frames per second.
    frame_times: VecDeque<Instant>,
    /// Where the image was drawn, in points (right of the panel).
    image_rect: egui::Rect,
    /// "reset accumulation" pressed while a frame was in flight.
    reset_asked: bool,
}

impl Session {
    /// The trace kernel a session asks for on `ctx`: the adapter's default,
    /// unspecialized. Every edit changes the scene, and a pipeline
    /// specialized to it would be made again at each (half a second and
    /// more on lavapipe).
    pub fn trace_kernel(ctx: &GpuContext) -> TraceKernel {
        GpuRenderer::default_trace_kernel(ctx).unspecialized()
    }

    /// A session on `scene`, traced at `width` x `height` until the first
    /// frame lays the image out, drawn into targets of `target_format`.
    pub fn new(
        ctx: &GpuContext,
        scene: Scene,
        (width, height): (u32, u32),
        target_format: wgpu::TextureFormat,
        files: Files,
        waiting: Waiting,
    ) -> Result<Self, GpuError> {
        let settings = ViewSettings::new(scene, width.max(1), height.max(1));
        let kernel = Self::trace_kernel(ctx);
        let (walls, spheres) = (settings.scene.gpu_walls(), settings.scene.gpu_spheres());
        let renderer = GpuRenderer::with_trace_kernel(ctx, settings.frame_params(), &walls, &spheres, kernel)?;
        let blit = Blit::new(ctx, target_format);
        let blit_group = blit.bind_group(ctx, &renderer);
        let timer = if waiting == Waiting::Block { GpuTimer::new(ctx) } else { None };
        Ok(Self {
            initial_camera: settings.scene.camera,
            applied: settings.clone(),
            settings,
            renderer,
            blit,
            blit_group,
            timer,
            waiting,
            in_flight: None,
            non_finite: None,
            stats: Stats { adapter: ctx.adapter_description(), ..Default::default() },
            files,
            auto_spp: 1,
            display_dirty: true,
            flying: false,
            frames_traced: 0,
            last_frame: None,
            frame_times: VecDeque::new(),
            image_rect: egui::Rect::NOTHING,
            reset_asked: false,
        })
    }

    /// Whether tracing is under way (not paused, target not reached).
    pub fn tracing(&self) -> bool {
        let s = &self.settings;
        !s.paused && (s.target_spp == 0 || self.stats.accumulated_spp < s.target_spp as u64)
    }

    /// Whether the shell should draw again without waiting for input.
    pub fn wants_frames(&self) -> bool {
        self.tracing()
            || self.flying
            || self.display_dirty
            || self.settings != self.applied
            || self.in_flight.is_some()
            || self.non_finite.is_some()
            || self.reset_asked
    }

    /// The traced image's size in pixels.
    pub fn image_size(&self) -> (u32, u32) {
        (self.applied.width, self.applied.height)
    }

    /// Where the last frame drew the image, in points; the panel is left
    /// of it.
    pub fn image_rect(&self) -> egui::Rect {
        self.image_rect
    }

    /// The renderer: its display buffer is current after [`Session::frame`].
    pub fn renderer(&self) -> &GpuRenderer {
        &self.renderer
    }

    /// Whether the last traced frame has finished: always on a desktop; in
    /// a browser, once the queue has said so (readbacks are whole then).
    pub fn idle(&self) -> bool {
        self.in_flight.is_none()
    }

    /// One frame: input, the panel, the settings applied, a traced frame,
    /// the display pass, and the image painted beside the panel. Returns
    /// the file actions the shell carries out (load, save).
    pub fn frame(&mut self, ui: &mut egui::Ui, ctx: &GpuContext) -> Result<Actions, GpuError> {
        let dt = self.clock();
        self.fly(ui, dt);

        let mut actions = Actions::default();
        let image_rect = panel::draw(ui, &mut self.settings, &self.stats, &mut self.files, &mut actions);
        self.image_rect = image_rect;
        self.orbit_and_zoom(ui, image_rect);
        // The image fills the rectangle right of the panel, in pixels.
        let ppp = ui.pixels_per_point();
        let px = |a: f32, b: f32| ((b * ppp).round() - (a * ppp).round()).max(1.0) as u32;
        self.settings.width = px(image_rect.min.x, image_rect.max.x);
        self.settings.height = px(image_rect.min.y, image_rect.max.y);

        if actions.reset_view {
            self.settings.scene.camera = self.initial_camera;
        }
        // Only a moved camera or an edited scene needs the check (it writes
        // and re-reads TOML) and the light edge's rule.
        if self.settings.scene != self.applied.scene {
            if self.settings.scene.validate().is_err() {
                // A value the panel allowed but the kernel cannot trace
                // (e.g. a camera at its look-at point): keep the last good
                // scene.
                self.settings.scene = self.applied.scene.clone();
            }
            self.settings.follow_edge_rule();
        }
        self.finish_in_flight();
        self.apply_settings(ctx, actions.reset_accumulation)?;
        self.trace(ctx)?;
        if self.display_dirty {
            self.renderer.submit_display(self.settings.exposure, self.settings.tonemap);
            self.display_dirty = false;
        }
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(
            image_rect,
            ImagePaint { blit: self.blit.clone(), group: self.blit_group.clone() },
        ));
        ctx.check()?;
        Ok(actions)
    }

    /// Seconds since the last frame (at most 0.1, so that a long pause does
    /// not fling a flying camera), and frames per second over two seconds.
    fn clock(&mut self) -> f32 {
        let now = Instant::now();
        let dt = self.last_frame.map_or(0.0, |t| now.duration_since(t).as_secs_f32());
        self.last_frame = Some(now);
        self.frame_times.push_back(now);
        while self.frame_times.len() > 2 && now.duration_since(self.frame_times[0]).as_secs_f64() > 2.0 {
            self.frame_times.pop_front();
        }
        let span = now.duration_since(self.frame_times[0]).as_secs_f64();
        self.stats.fps = if span > 0.0 { (self.frame_times.len() - 1) as f64 / span } else { 0.0 };
        dt.min(0.1)
    }

    /// WASD fly, QE down and up, shift faster; not while a text field
    /// has the keyboard.
    fn fly(&mut self, ui: &egui::Ui, dt: f32) {
        if ui.ctx().egui_wants_keyboard_input() {
            self.flying = false;
            return;
        }
        let (axes, fast) = ui.input(|i| {
            let axis = |pos: Key, neg: Key| i.key_down(pos) as i32 - i.key_down(neg) as i32;
            ((axis(Key::W, Key::S), axis(Key::D, Key::A), axis(Key::E, Key::Q)), i.modifiers.shift)
        });
        self.flying = axes != (0, 0, 0);
        if self.flying {
            let step = FLY_SPEED * dt * if fast { 4.0 } else { 1.0 };
            let cam = &mut self.settings.scene.camera;
            *cam = fly(cam, axes.0 as f32 * step, axes.1 as f32 * step, axes.2 as f32 * step);
        }
    }

    /// Drag on the image orbits; the wheel over it zooms.
    fn orbit_and_zoom(&mut self, ui: &egui::Ui, image_rect: egui::Rect) {
        let response = ui.interact(image_rect, egui::Id::unique("pt-image"), Sense::drag());
        let drag = response.drag_delta() * ui.pixels_per_point();
        if drag != egui::Vec2::ZERO {
            let cam = &mut self.settings.scene.camera;
            *cam = orbit(cam, -drag.x * ORBIT_RADIANS_PER_PIXEL, drag.y * ORBIT_RADIANS_PER_PIXEL);
        }
        if response.hovered() {
            let notches: f32 = ui.input(|i| {
                i.events
                    .iter()
                    .map(|e| match e {
                        Event::MouseWheel { unit: MouseWheelUnit::Line, delta, .. } => delta.y,
                        Event::MouseWheel { unit: MouseWheelUnit::Point, delta, .. } => delta.y / POINTS_PER_NOTCH,
                        Event::MouseWheel { unit: MouseWheelUnit::Page, delta, .. } => delta.y * 10.0,
                        _ => 0.0,
                    })
                    .sum()
            });
            if notches != 0.0 {
                let cam = &mut self.settings.scene.camera;
                *cam = zoom(cam, notches);
            }
        }
    }

    /// Brings the renderer in line with the settings, restarting the
    /// accumulation only when [`invalidates_accumulation`] says so.
    fn apply_settings(&mut self, ctx: &GpuContext, force_reset: bool) -> Result<(), GpuError> {
        if self.in_flight.is_some() {
            // A browser: the buffers change only between traced frames.
            self.reset_asked |= force_reset;
            return Ok(());
        }
        let force_reset = force_reset || std::mem::take(&mut self.reset_asked);
        if self.settings == self.applied && !force_reset {
            return Ok(());
        }
        let reset = force_reset || invalidates_accumulation(&self.applied, &self.settings);
        let mut params = self.settings.frame_params();
        params.frame = self.renderer.params().frame;
        let geometry_changed = self.settings.scene.walls != self.applied.scene.walls
            || self.settings.scene.spheres != self.applied.scene.spheres;
        self.renderer.set_params(params)?;
        if geometry_changed {
            self.renderer.set_geometry(&self.settings.scene.gpu_walls(), &self.settings.scene.gpu_spheres())?;
        }
        if (self.settings.width, self.settings.height) != (self.applied.width, self.applied.height) {
            self.blit_group = self.blit.bind_group(ctx, &self.renderer);
        }
        if reset {
            self.renderer.reset();
            self.stats.accumulated_spp = 0;
            self.stats.traced_ms = 0.0;
            self.stats.non_finite = 0;
            self.non_finite = None;
        }
        self.renderer.write_params();
        self.applied = self.settings.clone();
        self.display_dirty = true;
        Ok(())
    }

    /// Traces one frame if tracing, adapting the samples per frame.
    fn trace(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        self.poll_non_finite()?;
        self.stats.tracing = self.tracing();
        if !self.stats.tracing || self.in_flight.is_some() || self.settings != self.applied || self.reset_asked {
            if !self.stats.tracing {
                self.stats.last_frame_spp = 0;
            }
            return Ok(());
        }
        let mut spp = match self.settings.samples_per_frame {
            SamplesPerFrame::Auto { .. } => self.auto_spp,
            SamplesPerFrame::Fixed(n) => n,
        };
        if self.settings.target_spp > 0 {
            spp = spp.min((self.settings.target_spp as u64 - self.stats.accumulated_spp) as u32);
        }
        let start = Instant::now();
        match self.waiting {
            Waiting::Block => {
                self.renderer.submit_frame_timed(spp, self.timer.as_ref());
                ctx.wait()?;
                let wall_ms = start.elapsed().as_secs_f64() * 1e3;
                // lavapipe's timestamps do not bracket the dispatch's
                // execution (they read ~0.05 ms for a 250 ms frame): wall
                // clock there.
                let (ms, gpu) = match &self.timer {
                    Some(t) if !ctx.is_software() => (t.read_ms(ctx)?, true),
                    _ => (wall_ms, false),
                };
                self.traced(spp, ms, gpu, wall_ms);
            }
            Waiting::Never => {
                self.renderer.submit_frame(spp);
                let done = Arc::new(Mutex::new(None));
                let set = done.clone();
                ctx.queue.on_submitted_work_done(move || {
                    if let Ok(mut d) = set.lock() {
                        *d = Some(Instant::now());
                    }
                });
                self.in_flight = Some(InFlight { submitted: start, spp, done });
            }
        }
        // Counted when submitted: the display pass, queued behind this
        // frame, shows it.
        self.stats.accumulated_spp += spp as u64;
        self.stats.last_frame_spp = spp;
        self.frames_traced += 1;
        self.display_dirty = true;
        self.count_non_finite(ctx)
    }

    /// Takes the timing of a finished in-flight frame ([`Waiting::Never`]).
    fn finish_in_flight(&mut self) {
        let Some(f) = &self.in_flight else { return };
        let done = f.done.lock().ok().and_then(|d| *d);
        if let Some(end) = done {
            let ms = end.duration_since(f.submitted).as_secs_f64() * 1e3;
            let spp = f.spp;
            self.in_flight = None;
            self.traced(spp, ms, false, ms);
        }
    }

    /// Records a traced frame's time, and adapts the samples per frame.
    fn traced(&mut self, spp: u32, ms: f64, gpu: bool, wall_ms: f64) {
        self.stats.trace_ms = Some((ms, gpu));
        self.stats.traced_ms += ms;
        let pixels = self.applied.width as f64 * self.applied.height as f64;
        self.stats.samples_per_second = pixels * spp as f64 / (ms.max(1e-3) * 1e-3);
        if let SamplesPerFrame::Auto { budget_ms } = self.settings.samples_per_frame {
            // Scale toward the budget, at most x2 or /2 per frame. Wall
            // clock, not timestamps: what the user waits for is the frame.
            let ratio = (budget_ms as f64 / wall_ms.max(1e-3)).clamp(0.5, 2.0);
            self.auto_spp = ((spp.max(1) as f64 * ratio).round() as u32).clamp(1, 1024);
        }
    }

    /// Takes the non-finite sample count once its readback has arrived.
    fn poll_non_finite(&mut self) -> Result<(), GpuError> {
        if let Some(bytes) = self.non_finite.as_ref().and_then(PendingRead::try_take) {
            let b = bytes?;
            self.stats.non_finite = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64;
            self.non_finite = None;
        }
        Ok(())
    }

    /// Keeps the non-finite sample count current after a traced frame:
    /// four bytes every 16th frame and after the last, never a per-frame
    /// readback of anything sizeable.
    fn count_non_finite(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        if !self.frames_traced.is_multiple_of(16) && self.tracing() {
            return Ok(());
        }
        match self.waiting {
            Waiting::Block => self.stats.non_finite = self.renderer.read_non_finite(ctx)? as u64,
            // Queued behind the frame, so it counts the frame's samples.
            Waiting::Never if self.non_finite.is_none() => {
                self.non_finite = Some(self.renderer.start_read_non_finite(ctx));
            }
            Waiting::Never => {}
        }
        Ok(())
    }

    /// A scene file the shell read (or failed to read): on success the new
    /// scene, whose camera becomes the one "reset view" returns to; on
    /// failure the error, worded as the command line words it, in the
    /// status line, and the current scene stays. Returns whether it loaded.
    pub fn load_scene(&mut self, name: &str, scene: Result<Scene, SceneError>) -> bool {
        match scene {
            Ok(scene) => {
                self.initial_camera = scene.camera;
                self.settings.max_bounces = scene.render.max_bounces;
                // The new scene's own default strategy (the panel's switches
                // show it and can change it again).
                self.settings.flags = scene.default_flags();
                self.settings.scene = scene;
                self.files.status = format!("loaded {name}");
                true
            }
            Err(e) => {
                self.files.status = format!("error: {}", error_chain(&e));
                false
            }
        }
    }

    /// [`Session::load_scene`] of a scene file's text (a browser's pick or
    /// drop).
    pub fn load_scene_text(&mut self, name: &str, text: &str) -> bool {
        self.load_scene(name, Scene::from_toml(text, Path::new(name)))
    }

    /// The scene as a file, with the panel's bounce settings.
    pub fn scene_toml(&self) -> String {
        let mut scene = self.settings.scene.clone();
        scene.render.max_bounces = self.settings.max_bounces;
        scene.render.rr_start = self.settings.rr_start;
        scene.to_toml()
    }
}

/// An error and its sources joined by ": ", as the command line prints
/// them (anyhow's `{:#}`).
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// The traced image, drawn by the kernel's blit inside egui's render pass
/// (egui sets the viewport to the image's rectangle).
struct ImagePaint {
    blit: Blit,
    group: wgpu::BindGroup,
}

impl egui_wgpu::CallbackTrait for ImagePaint {
    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        _resources: &egui_wgpu::CallbackResources,
    ) {
        self.blit.draw(pass, &self.group);
    }
}
