//! The browser shell of the viewer: eframe on WebGPU around the same
//! `pt_viewer::Session` as the desktop window, so the panel, the controls,
//! the reset rule and the kernel are the desktop's. What differs is only
//! what a page must do differently:
//! - nothing waits for the GPU (`Waiting::Never`): a traced frame's end and
//!   every readback arrive through the page's event loop;
//! - scene files come from a file picker or a drop, outputs are downloads;
//! - `window.ptState` and `window.ptTest` report to a browser test what
//!   the page shows (a screenshot of a WebGPU canvas can come out blank).
//!
//! `index.html` checks for WebGPU before it loads this module, and calls
//! [`start`]. Built by `scripts/web.sh build`.

#![cfg(target_arch = "wasm32")]

mod page;

use std::sync::Arc;

use eframe::egui_wgpu::{WgpuConfiguration, WgpuSetup, WgpuSetupCreateNew};
use pt_core::AccumPixel;
use pt_render::gpu::PendingRead;
use pt_render::{GpuContext, Scene, output};
use pt_viewer::session::Waiting;
use pt_viewer::{Files, SamplesPerFrame, Session};
use wasm_bindgen::prelude::*;

/// Starts the viewer in the canvas with id `canvas_id`. Fails (for the
/// page to show) when WebGPU gives no device or the kernel is rejected.
#[wasm_bindgen]
pub async fn start(canvas_id: String) -> Result<(), JsValue> {
    let canvas = page::canvas(&canvas_id)?;
    let setup = WgpuSetupCreateNew {
        instance_descriptor: wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..WgpuSetupCreateNew::without_display_handle().instance_descriptor
        },
        // The renderer's device: the adapter's limits, not egui's defaults.
        device_descriptor: Arc::new(GpuContext::device_descriptor),
        ..WgpuSetupCreateNew::without_display_handle()
    };
    let options = eframe::WebOptions {
        wgpu_options: WgpuConfiguration { wgpu_setup: WgpuSetup::CreateNew(setup), ..Default::default() },
        ..Default::default()
    };
    let test = page::TestRequest::from_url();
    eframe::WebRunner::new().start(canvas, options, Box::new(move |cc| Ok(Box::new(WebViewer::new(cc, test)?)))).await
}

/// What a readback is for.
#[derive(Copy, Clone, PartialEq, Eq)]
enum Purpose {
    /// The display buffer, to download as PNG.
    Png,
    /// The accumulation, to download as EXR.
    Exr,
    /// The accumulation, for the browser test.
    Test,
}

/// A buffer on its way to the host, with the image size it was read at.
struct Readback {
    purpose: Purpose,
    pending: PendingRead,
    size: (u32, u32),
}

struct WebViewer {
    ctx: GpuContext,
    session: Session,
    picked: page::PickedFile,
    readbacks: Vec<Readback>,
    test: Option<page::TestRequest>,
    test_started: bool,
    /// The scene `window.ptState` shows, and its TOML: written again only
    /// when the scene changes, not every frame.
    reported_scene: Option<(Scene, String)>,
}

impl WebViewer {
    fn new(cc: &eframe::CreationContext<'_>, test: Option<page::TestRequest>) -> Result<Self, String> {
        let rs = cc.wgpu_render_state.as_ref().ok_or("eframe gave no WebGPU device")?;
        let ctx = GpuContext::from_device(rs.adapter.clone(), rs.device.clone(), rs.queue.clone());
        let files = Files { paths: None, status: String::new() };
        let mut session = Session::new(&ctx, Scene::default_scene(), (1, 1), rs.target_format, files, Waiting::Never)
            .map_err(|e| e.to_string())?;
        if let Some(t) = &test {
            session.settings.samples_per_frame = SamplesPerFrame::Fixed(t.per_frame);
            session.settings.target_spp = t.spp;
        }
        ctx.check().map_err(|e| e.to_string())?;
        Ok(Self {
            ctx,
            session,
            picked: Default::default(),
            readbacks: Vec::new(),
            test,
            test_started: false,
            reported_scene: None,
        })
    }

    /// Scene files dropped on the page or picked: read as text, then
    /// loaded by the session as the desktop loads them.
    fn take_files(&mut self, ui: &egui::Ui) {
        for file in ui.input(|i| i.raw.dropped_files.clone()) {
            if let Some(f) = file.web_file() {
                page::read_text(f.clone(), self.picked.clone(), ui.ctx().clone());
            }
        }
        let picked = self.picked.borrow_mut().take();
        match picked {
            Some((name, Ok(text))) => {
                self.session.load_scene_text(&name, &text);
            }
            Some((name, Err(e))) => self.session.files.status = format!("error: {name}: {e}"),
            None => {}
        }
    }

    fn handle_actions(&mut self, a: &pt_viewer::Actions, ui: &egui::Ui) {
        if a.load_scene {
            page::pick_file(self.picked.clone(), ui.ctx().clone());
        }
        if a.save_scene {
            self.session.files.status = page::download("scene.toml", self.session.scene_toml().as_bytes());
        }
        if a.save_png {
            self.read(Purpose::Png);
        }
        if a.save_exr {
            self.read(Purpose::Exr);
        }
    }

    fn read(&mut self, purpose: Purpose) {
        let renderer = self.session.renderer();
        let pending = match purpose {
            Purpose::Png => renderer.start_read_display(&self.ctx),
            Purpose::Exr | Purpose::Test => renderer.start_read_accum(&self.ctx),
        };
        self.readbacks.push(Readback { purpose, pending, size: self.session.image_size() });
    }

    /// Finished readbacks become downloads or the test's report.
    fn finish_readbacks(&mut self) {
        for r in std::mem::take(&mut self.readbacks) {
            let Some(bytes) = r.pending.try_take() else {
                self.readbacks.push(r);
                continue;
            };
            let (w, h) = r.size;
            let encoded = bytes.map_err(|e| e.to_string()).and_then(|bytes| {
                let encoded = match r.purpose {
                    Purpose::Png => output::encode_png(w, h, &bytemuck::pod_collect_to_vec(&bytes)),
                    Purpose::Exr | Purpose::Test => {
                        let accum: Vec<AccumPixel> = bytemuck::pod_collect_to_vec(&bytes);
                        output::encode_exr(w, h, &output::mean_radiance(&accum))
                    }
                };
                encoded.map_err(|e| e.to_string())
            });
            self.session.files.status = match (encoded, r.purpose) {
                (Ok(png), Purpose::Png) => page::download("view.png", &png),
                (Ok(exr), Purpose::Exr) => page::download("view.exr", &exr),
                (Ok(exr), Purpose::Test) => {
                    page::report_test(&self.session, r.size, &exr);
                    continue;
                }
                (Err(e), _) => format!("error: {e}"),
            };
        }
    }

    /// Test mode: once the asked samples are traced and the GPU is done,
    /// read the image back for `window.ptTest`.
    fn drive_test(&mut self) {
        let Some(t) = &self.test else { return };
        let done = self.session.stats.accumulated_spp >= t.spp as u64 && self.session.idle();
        if done && !self.test_started {
            self.test_started = true;
            self.read(Purpose::Test);
        }
    }
}

impl eframe::App for WebViewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.take_files(ui);
        match self.session.frame(ui, &self.ctx) {
            Ok(actions) => self.handle_actions(&actions, ui),
            Err(e) => self.session.files.status = format!("error: {e}"),
        }
        self.finish_readbacks();
        self.drive_test();
        let scene = &self.session.settings.scene;
        if self.reported_scene.as_ref().is_none_or(|(s, _)| s != scene) {
            self.reported_scene = Some((scene.clone(), scene.to_toml()));
        }
        if let Some((_, toml)) = &self.reported_scene {
            page::report_state(&self.session, toml);
        }
        if self.session.wants_frames() || !self.readbacks.is_empty() {
            ui.ctx().request_repaint();
        }
    }
}
