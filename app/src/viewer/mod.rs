//! The desktop shell of the viewer: a winit window and its surface,
//! egui-winit for input, the path fields for files, and a frame loop that
//! costs nothing once the image has converged. The viewer itself (panel,
//! controls, tracing policy, the image) is `pt_viewer::Session`, which the
//! browser page shares.

mod frame;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, anyhow};
use pt_render::output;
use pt_render::{GpuContext, GpuRenderer, Scene};
use pt_viewer::session::Waiting;
use pt_viewer::{Actions, Files, Paths, Session};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

use frame::surface_config;

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

struct Viewer {
    window: Arc<Window>,
    instance: wgpu::Instance,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    minimized: bool,
    ctx: GpuContext,
    session: Session,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    /// Whether egui asked for another frame.
    ui_repaint: bool,
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
        if let Some(notice) = GpuRenderer::general_kernel_notice(&scene, Session::trace_kernel(&ctx)) {
            eprintln!("{notice}");
        }
        let scene_path = args.scene_path.as_ref().map_or("scene.toml".to_owned(), |p| p.display().to_string());
        let files = Files {
            paths: Some(Paths { scene: scene_path, png: "view.png".into(), exr: "view.exr".into() }),
            status: String::new(),
        };
        let mut session = Session::new(&ctx, scene, (size.width, size.height), config.format, files, Waiting::Block)?;
        session.settings.target_spp = args.target_spp;

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
        Ok(Self {
            window,
            instance,
            surface,
            config,
            minimized,
            ctx,
            session,
            egui_ctx,
            egui_state,
            egui_renderer,
            ui_repaint: true,
            frames_drawn: 0,
        })
    }

    /// Whether the loop should keep drawing without waiting for events.
    fn wants_frames(&self) -> bool {
        !self.minimized && (self.session.wants_frames() || self.ui_repaint)
    }

    /// Window events go to egui; the session reads the controls from it.
    fn on_event(&mut self, event: &WindowEvent) {
        let response = self.egui_state.on_window_event(&self.window, event);
        if response.repaint {
            self.window.request_redraw();
        }
        match event {
            WindowEvent::Resized(size) => self.resize(*size),
            WindowEvent::ScaleFactorChanged { .. } => self.resize(self.window.inner_size()),
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

    /// The file actions of the panel, on the paths its fields hold.
    fn handle_actions(&mut self, a: &Actions) -> Result<()> {
        let Some(paths) = self.session.files.paths.clone() else { return Ok(()) };
        if a.load_scene {
            self.session.load_scene(&paths.scene, Scene::load(Path::new(&paths.scene)));
        }
        if a.save_scene {
            self.session.files.status = match std::fs::write(&paths.scene, self.session.scene_toml()) {
                Ok(()) => format!("saved {}", paths.scene),
                Err(e) => format!("{}: {e}", paths.scene),
            };
        }
        let (w, h) = self.session.image_size();
        if a.save_png {
            let rgba = self.session.renderer().read_display(&self.ctx)?;
            self.session.files.status = status(output::write_png(Path::new(&paths.png), w, h, &rgba), &paths.png);
        }
        if a.save_exr {
            let accum = self.session.renderer().read_accum(&self.ctx)?;
            let means = output::mean_radiance(&accum);
            self.session.files.status = status(output::write_exr(Path::new(&paths.exr), w, h, &means), &paths.exr);
        }
        if a.load_scene || a.save_scene || a.save_png || a.save_exr {
            self.window.request_redraw();
        }
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop, args: &ViewArgs) -> Result<()> {
        if self.minimized {
            return Ok(());
        }
        // The panel, the controls, a traced frame and the image.
        let raw_input = self.egui_state.take_egui_input(&self.window);
        let (session, ctx) = (&mut self.session, &self.ctx);
        let mut result = Ok(Actions::default());
        let mut full_output = self.egui_ctx.run_ui(raw_input, |ui| result = session.frame(ui, ctx));
        let actions = result.inspect_err(|_| full_output.textures_delta.clear())?;
        self.ui_repaint = full_output.viewport_output.values().any(|v| v.repaint_delay.is_zero());
        self.egui_state.handle_platform_output(&self.window, full_output.platform_output);

        // Draw: the panel with the image in it.
        let paint_jobs = self.egui_ctx.tessellate(full_output.shapes, full_output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: full_output.pixels_per_point,
        };
        // Every texture delta is applied here, whatever happens next: an
        // unapplied delta (the font atlas) would be lost for good.
        let mut textures = std::mem::take(&mut full_output.textures_delta);
        for (id, deltas) in textures.set.drain() {
            for delta in deltas {
                self.egui_renderer.update_texture(&self.ctx.device, &self.ctx.queue, id, &delta);
            }
        }
        let freed: Vec<_> = textures.free.drain().collect();
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f) | wgpu::CurrentSurfaceTexture::Suboptimal(f) => Some(f),
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => None,
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.surface.configure(&self.ctx.device, &self.config);
                None
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                self.surface =
                    self.instance.create_surface(self.window.clone()).context("cannot recreate the surface")?;
                self.surface.configure(&self.ctx.device, &self.config);
                None
            }
            wgpu::CurrentSurfaceTexture::Validation => return Err(anyhow!("the window surface failed validation")),
        };
        let Some(frame) = frame else {
            for id in &freed {
                self.egui_renderer.free_texture(id);
            }
            return Ok(());
        };
        let view = frame.texture.create_view(&Default::default());
        let last = args.frames.is_some_and(|n| self.frames_drawn + 1 >= n);
        let shot = if last { args.screenshot.as_ref() } else { None };
        let offscreen = shot.map(|_| self.offscreen_target());

        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        let callbacks =
            self.egui_renderer.update_buffers(&self.ctx.device, &self.ctx.queue, &mut encoder, &paint_jobs, &screen);
        self.draw(&mut encoder, &view, &paint_jobs, &screen);
        if let Some(target) = &offscreen {
            self.draw(&mut encoder, &target.create_view(&Default::default()), &paint_jobs, &screen);
        }
        self.ctx.queue.submit(callbacks.into_iter().chain([encoder.finish()]));
        self.ctx.queue.present(frame);
        for id in &freed {
            self.egui_renderer.free_texture(id);
        }
        self.ctx.check()?;
        self.frames_drawn += 1;

        if let (Some(path), Some(target)) = (shot, offscreen) {
            self.save_screenshot(&target, path)?;
        }
        self.handle_actions(&actions)?;
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
