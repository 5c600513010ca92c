//! The interactive viewer: a winit window, the traced image drawn by the
//! kernel's blit, an egui panel on top, and a frame loop that adapts its
//! samples per frame to a time budget and costs nothing once converged.

mod camera_control;
mod frame;
mod panel;
mod settings;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use pt_render::gpu::{Blit, GpuTimer};
use pt_render::output;
use pt_render::{GpuContext, GpuRenderer, Scene};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use camera_control::{FLY_SPEED, ORBIT_RADIANS_PER_PIXEL, fly, orbit, zoom};
use frame::surface_config;
use panel::{Actions, Paths, Stats};
use settings::{SamplesPerFrame, ViewSettings, invalidates_accumulation};

/// What `pathtracer view` was asked to do.
pub struct ViewArgs {
    /// The scene and where it came from.
    pub scene: Scene,
    /// Its file, if any: the panel's load/save field starts there.
    pub scene_path: Option<PathBuf>,
    /// Initial window size in physical pixels.
    pub width: u32,
    /// Initial window height.
    pub height: u32,
    /// Stop tracing at this many samples per pixel (0: never).
    pub target_spp: u32,
    /// Override of the scene's bounce limit.
    pub max_bounces: Option<u32>,
    /// Exit after this many frames...
    pub frames: Option<u32>,
    /// ...saving what the window shows to this PNG.
    pub screenshot: Option<PathBuf>,
}

/// Whether a display server is reachable (X11 or Wayland on Linux).
pub fn display_available() -> bool {
    if cfg!(any(target_os = "linux", target_os = "freebsd", target_os = "openbsd", target_os = "netbsd")) {
        std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty())
            || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|d| !d.is_empty())
    } else {
        true
    }
}

/// Opens the viewer and runs until the window closes (or `--frames`).
pub fn run(args: ViewArgs) -> Result<()> {
    let event_loop = EventLoop::new().context("cannot connect to the display")?;
    let mut app = App { args, viewer: None, error: None };
    event_loop.run_app(&mut app).context("the window system failed")?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

struct App {
    args: ViewArgs,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        match Viewer::new(event_loop, &self.args) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else { return };
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::RedrawRequested => viewer.redraw(event_loop, &self.args),
            other => {
                viewer.on_event(&other);
                Ok(())
            }
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(v) = self.viewer.as_ref() {
            if v.wants_frames() {
                v.window.request_redraw();
                event_loop.set_control_flow(ControlFlow::Poll);
            } else {
                // Converged or paused, no input: sleep until an event. The
                // GPU does nothing.
                event_loop.set_control_flow(ControlFlow::Wait);
            }
        }
    }
}

/// Keys that fly the camera while held.
#[derive(Default)]
struct FlyKeys {
    forward: bool,
    back: bool,
    left: bool,
    right: bool,
    up: bool,
    down: bool,
    fast: bool,
}

impl FlyKeys {
    fn any(&self) -> bool {
        self.forward || self.back || self.left || self.right || self.up || self.down
    }
}

struct Viewer {
    window: Arc<Window>,
    instance: wgpu::Instance,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    minimized: bool,
    ctx: GpuContext,
    renderer: GpuRenderer,
    blit: Blit,
    blit_group: wgpu::BindGroup,
    timer: Option<GpuTimer>,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    /// Settings as the panel and the controls leave them.
    settings: ViewSettings,
    /// Settings the accumulation was traced with.
    applied: ViewSettings,
    /// The camera of the scene file, for "reset view".
    initial_camera: pt_render::scene::CameraDesc,
    keys: FlyKeys,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    paths: Paths,
    stats: Stats,
    /// Samples per frame chosen by the automatic policy.
    auto_spp: u32,
    /// Whether the display buffer is stale (new samples or display change).
    display_dirty: bool,
    /// Whether egui asked for another frame.
    ui_repaint: bool,
    /// Top-left corner of the image in the window (right of the panel).
    image_origin: (u32, u32),
    last_frame: Instant,
    /// When recent frames started, for frames per second.
    frame_times: std::collections::VecDeque<Instant>,
    frames_drawn: u32,
}

impl Viewer {
    fn new(event_loop: &ActiveEventLoop, args: &ViewArgs) -> Result<Self> {
        let attrs = Window::default_attributes()
            .with_title("pathtracer")
            .with_inner_size(PhysicalSize::new(args.width, args.height));
        let window = Arc::new(event_loop.create_window(attrs).context("cannot create the window")?);
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
            event_loop.owned_display_handle(),
        )));
        let surface = instance.create_surface(window.clone()).context("cannot create a surface for the window")?;
        let ctx = GpuContext::with_instance(&instance, Some(&surface))?;

        let size = window.inner_size();
        let config = surface_config(&ctx, &surface, size)?;
        let minimized = size.width == 0 || size.height == 0;
        if !minimized {
            surface.configure(&ctx.device, &config);
        }

        let mut scene = args.scene.clone();
        if let Some(b) = args.max_bounces {
            scene.render.max_bounces = b;
        }
        let (w, h) = (size.width.max(1), size.height.max(1));
        let mut settings = ViewSettings::new(scene, w, h);
        settings.target_spp = args.target_spp;
        let renderer = GpuRenderer::new(
            &ctx,
            settings.frame_params(),
            &settings.scene.gpu_walls(),
            &settings.scene.gpu_spheres(),
        )?;
        let blit = Blit::new(&ctx, config.format);
        let blit_group = blit.bind_group(&ctx, &renderer);
        let timer = GpuTimer::new(&ctx);

        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, config.format, egui_wgpu::RendererOptions::default());

        let scene_path = args.scene_path.as_ref().map_or("scene.toml".to_owned(), |p| p.display().to_string());
        let stats = Stats { adapter: ctx.adapter_description(), ..Default::default() };
        Ok(Self {
            initial_camera: settings.scene.camera,
            applied: settings.clone(),
            settings,
            window,
            instance,
            surface,
            config,
            minimized,
            ctx,
            renderer,
            blit,
            blit_group,
            timer,
            egui_ctx,
            egui_state,
            egui_renderer,
            keys: FlyKeys::default(),
            dragging: false,
            cursor: None,
            paths: Paths { scene: scene_path, png: "view.png".into(), exr: "view.exr".into(), status: String::new() },
            stats,
            auto_spp: 1,
            display_dirty: true,
            ui_repaint: true,
            image_origin: (0, 0),
            last_frame: Instant::now(),
            frame_times: Default::default(),
            frames_drawn: 0,
        })
    }

    /// Whether tracing is under way (not paused, target not reached).
    fn tracing(&self) -> bool {
        let s = &self.settings;
        !self.minimized && !s.paused && (s.target_spp == 0 || self.stats.accumulated_spp < s.target_spp as u64)
    }

    /// Whether the loop should keep drawing without waiting for events.
    fn wants_frames(&self) -> bool {
        self.tracing() || self.ui_repaint || self.keys.any() || self.display_dirty
    }

    fn on_event(&mut self, event: &WindowEvent) {
        let response = self.egui_state.on_window_event(&self.window, event);
        if response.repaint {
            self.window.request_redraw();
        }
        match event {
            WindowEvent::Resized(size) => self.resize(*size),
            WindowEvent::ScaleFactorChanged { .. } => self.resize(self.window.inner_size()),
            WindowEvent::KeyboardInput { event, .. } if !response.consumed => {
                let down = event.state == ElementState::Pressed;
                let k = &mut self.keys;
                match event.physical_key {
                    PhysicalKey::Code(KeyCode::KeyW) => k.forward = down,
                    PhysicalKey::Code(KeyCode::KeyS) => k.back = down,
                    PhysicalKey::Code(KeyCode::KeyA) => k.left = down,
                    PhysicalKey::Code(KeyCode::KeyD) => k.right = down,
                    PhysicalKey::Code(KeyCode::KeyE) => k.up = down,
                    PhysicalKey::Code(KeyCode::KeyQ) => k.down = down,
                    PhysicalKey::Code(KeyCode::ShiftLeft | KeyCode::ShiftRight) => k.fast = down,
                    _ => {}
                }
                self.window.request_redraw();
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                // A drag that starts over the panel belongs to the panel.
                self.dragging = *state == ElementState::Pressed && !self.egui_ctx.is_pointer_over_egui();
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let (true, Some((px, py))) = (self.dragging, self.cursor) {
                    let cam = &mut self.settings.scene.camera;
                    *cam = orbit(
                        cam,
                        -((x - px) as f32) * ORBIT_RADIANS_PER_PIXEL,
                        ((y - py) as f32) * ORBIT_RADIANS_PER_PIXEL,
                    );
                    self.window.request_redraw();
                }
                self.cursor = Some((x, y));
            }
            WindowEvent::MouseWheel { delta, .. } if !self.egui_ctx.is_pointer_over_egui() => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                let cam = &mut self.settings.scene.camera;
                *cam = zoom(cam, notches);
                self.window.request_redraw();
            }
            _ => {}
        }
    }

    /// A new window size: reconfigure the surface; the traced image follows
    /// (through the reset rule) unless the window is minimised to 0x0.
    fn resize(&mut self, size: PhysicalSize<u32>) {
        self.minimized = size.width == 0 || size.height == 0;
        if self.minimized {
            return;
        }
        self.config.width = size.width;
        self.config.height = size.height;
        self.surface.configure(&self.ctx.device, &self.config);
        self.window.request_redraw();
    }

    /// Brings the renderer in line with the settings, restarting the
    /// accumulation only when [`invalidates_accumulation`] says so.
    fn apply_settings(&mut self, force_reset: bool) -> Result<()> {
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
            self.blit_group = self.blit.bind_group(&self.ctx, &self.renderer);
        }
        if reset {
            self.renderer.reset();
            self.stats.accumulated_spp = 0;
            self.stats.non_finite = 0;
        }
        self.renderer.write_params();
        self.applied = self.settings.clone();
        self.display_dirty = true;
        Ok(())
    }

    fn handle_actions(&mut self, a: &Actions) -> Result<()> {
        if a.reset_view {
            self.settings.scene.camera = self.initial_camera;
        }
        if a.load_scene {
            match Scene::load(Path::new(&self.paths.scene)) {
                Ok(scene) => {
                    self.initial_camera = scene.camera;
                    self.settings.max_bounces = scene.render.max_bounces;
                    self.settings.scene = scene;
                    self.paths.status = format!("loaded {}", self.paths.scene);
                }
                Err(e) => self.paths.status = e.to_string(),
            }
        }
        if a.save_scene {
            let mut scene = self.settings.scene.clone();
            scene.render.max_bounces = self.settings.max_bounces;
            scene.render.rr_start = self.settings.rr_start;
            self.paths.status = match std::fs::write(&self.paths.scene, scene.to_toml()) {
                Ok(()) => format!("saved {}", self.paths.scene),
                Err(e) => format!("{}: {e}", self.paths.scene),
            };
        }
        let (w, h) = (self.applied.width, self.applied.height);
        if a.save_png {
            self.renderer.submit_display(self.settings.exposure, self.settings.tonemap);
            let rgba = self.renderer.read_display(&self.ctx)?;
            self.paths.status = status(output::write_png(Path::new(&self.paths.png), w, h, &rgba), &self.paths.png);
        }
        if a.save_exr {
            let accum = self.renderer.read_accum(&self.ctx)?;
            let means = output::mean_radiance(&accum);
            self.paths.status = status(output::write_exr(Path::new(&self.paths.exr), w, h, &means), &self.paths.exr);
        }
        Ok(())
    }

    /// Traces one frame if tracing, adapting the samples per frame.
    fn trace(&mut self) -> Result<()> {
        self.stats.tracing = self.tracing();
        if !self.stats.tracing {
            self.stats.last_frame_spp = 0;
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
        self.renderer.submit_frame_timed(spp, self.timer.as_ref());
        self.ctx.wait()?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        // lavapipe's timestamps do not bracket the dispatch's execution
        // (they read ~0.05 ms for a 250 ms frame): wall clock there.
        let (ms, gpu) = match &self.timer {
            Some(t) if !self.ctx.is_software() => (t.read_ms(&self.ctx)?, true),
            _ => (wall_ms, false),
        };
        self.stats.trace_ms = Some((ms, gpu));
        let pixels = self.applied.width as f64 * self.applied.height as f64;
        self.stats.samples_per_second = pixels * spp as f64 / (ms.max(1e-3) * 1e-3);
        self.stats.accumulated_spp += spp as u64;
        self.stats.last_frame_spp = spp;
        if let SamplesPerFrame::Auto { budget_ms } = self.settings.samples_per_frame {
            // Scale toward the budget, at most x2 or /2 per frame. Wall
            // clock, not timestamps: what the user waits for is the frame.
            let ratio = (budget_ms as f64 / wall_ms.max(1e-3)).clamp(0.5, 2.0);
            self.auto_spp = ((spp.max(1) as f64 * ratio).round() as u32).clamp(1, 1024);
        }
        // Four bytes, only every 16th frame: the NaN count stays current
        // without a per-frame readback of anything sizeable.
        if self.frames_drawn.is_multiple_of(16) || !self.tracing() {
            self.stats.non_finite = self.renderer.read_non_finite(&self.ctx)? as u64;
        }
        self.display_dirty = true;
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop, args: &ViewArgs) -> Result<()> {
        let now = Instant::now();
        let frame_s = now.duration_since(self.last_frame).as_secs_f64().max(1e-6);
        self.last_frame = now;
        // Frames per second over the last two seconds of frames.
        self.frame_times.push_back(now);
        while self.frame_times.len() > 2 && now.duration_since(self.frame_times[0]).as_secs_f64() > 2.0 {
            self.frame_times.pop_front();
        }
        let span = now.duration_since(self.frame_times[0]).as_secs_f64();
        self.stats.fps = if span > 0.0 { (self.frame_times.len() - 1) as f64 / span } else { 0.0 };
        // A long pause (idle, or a window drag) must not fling the camera.
        let dt = frame_s.min(0.1) as f32;
        if self.minimized {
            return Ok(());
        }

        if self.keys.any() {
            let k = &self.keys;
            let step = FLY_SPEED * dt * if k.fast { 4.0 } else { 1.0 };
            let axis = |pos: bool, neg: bool| (pos as i32 - neg as i32) as f32 * step;
            let cam = &mut self.settings.scene.camera;
            *cam = fly(cam, axis(k.forward, k.back), axis(k.right, k.left), axis(k.up, k.down));
        }

        // The panel.
        let mut actions = Actions::default();
        let raw_input = self.egui_state.take_egui_input(&self.window);
        let (settings, stats, paths) = (&mut self.settings, &self.stats, &mut self.paths);
        let mut image_rect = egui::Rect::NOTHING;
        let full_output = self.egui_ctx.run_ui(raw_input, |ui| {
            image_rect = panel::draw(ui, settings, stats, paths, &mut actions);
        });
        // The image fills the window right of the panel, in physical pixels.
        let ppp = full_output.pixels_per_point;
        let (x0, y0) =
            ((image_rect.min.x * ppp).round().max(0.0) as u32, (image_rect.min.y * ppp).round().max(0.0) as u32);
        let width = self.config.width.saturating_sub(x0).max(1);
        let height = self.config.height.saturating_sub(y0).max(1);
        self.image_origin = (x0.min(self.config.width - 1), y0.min(self.config.height - 1));
        self.settings.width = width;
        self.settings.height = height;
        self.ui_repaint = full_output.viewport_output.values().any(|v| v.repaint_delay.is_zero());
        self.egui_state.handle_platform_output(&self.window, full_output.platform_output);

        self.handle_actions(&actions)?;
        // Only edited scenes need the check (it writes and re-reads TOML).
        if self.settings.scene != self.applied.scene && self.settings.scene.validate().is_err() {
            // A value the panel allowed but the kernel cannot trace (e.g. a
            // camera at its look-at point): keep the last good scene.
            self.settings.scene = self.applied.scene.clone();
        }
        self.apply_settings(actions.reset_accumulation)?;
        self.trace()?;

        if self.display_dirty {
            self.renderer.submit_display(self.settings.exposure, self.settings.tonemap);
            self.display_dirty = false;
        }

        // Draw: the traced image, then the panel over it.
        let paint_jobs = self.egui_ctx.tessellate(full_output.shapes, full_output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: full_output.pixels_per_point,
        };
        for (id, deltas) in &full_output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer.update_texture(&self.ctx.device, &self.ctx.queue, *id, delta);
            }
        }
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => return Ok(()),
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&self.ctx.device, &self.config);
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                self.surface =
                    self.instance.create_surface(self.window.clone()).context("cannot recreate the surface")?;
                self.surface.configure(&self.ctx.device, &self.config);
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Validation => return Err(anyhow!("the window surface failed validation")),
        };
        let view = frame.texture.create_view(&Default::default());
        let last = args.frames.is_some_and(|n| self.frames_drawn + 1 >= n);
        let shot = if last { args.screenshot.as_ref() } else { None };
        let offscreen = shot.map(|_| self.offscreen_target());

        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        self.egui_renderer.update_buffers(&self.ctx.device, &self.ctx.queue, &mut encoder, &paint_jobs, &screen);
        self.draw(&mut encoder, &view, &paint_jobs, &screen);
        if let Some(target) = &offscreen {
            self.draw(&mut encoder, &target.create_view(&Default::default()), &paint_jobs, &screen);
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.queue.present(frame);
        for id in &full_output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        self.ctx.check()?;
        self.frames_drawn += 1;

        if let (Some(path), Some(target)) = (shot, offscreen) {
            self.save_screenshot(&target, path)?;
        }
        if last {
            event_loop.exit();
        }
        Ok(())
    }
}

fn status(result: Result<(), output::OutputError>, path: &str) -> String {
    match result {
        Ok(()) => format!("saved {path}"),
        Err(e) => e.to_string(),
    }
}
