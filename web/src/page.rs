//! The page around the viewer: its canvas, files in and out, and the
//! reports a browser test reads.

use std::cell::RefCell;
use std::rc::Rc;

use js_sys::{Object, Reflect, Uint8Array};
use pt_viewer::Session;
use wasm_bindgen::JsCast;
use wasm_bindgen::prelude::*;

/// A scene file's name and text (or why it could not be read), filled in
/// by the page after a pick or a drop.
pub type PickedFile = Rc<RefCell<Option<(String, Result<String, String>)>>>;

fn window() -> Result<web_sys::Window, JsValue> {
    web_sys::window().ok_or_else(|| JsValue::from_str("no window"))
}

fn document() -> Result<web_sys::Document, JsValue> {
    window()?.document().ok_or_else(|| JsValue::from_str("no document"))
}

/// The canvas with this id.
pub fn canvas(id: &str) -> Result<web_sys::HtmlCanvasElement, JsValue> {
    document()?
        .get_element_by_id(id)
        .ok_or_else(|| JsValue::from_str(&format!("no element with id {id}")))?
        .dyn_into()
        .map_err(|_| JsValue::from_str(&format!("element {id} is not a canvas")))
}

/// Test mode, from the page's address: `?test&spp=64&per_frame=4` traces
/// 64 samples per pixel, 4 per frame, then reports the image.
#[derive(Copy, Clone, Debug)]
pub struct TestRequest {
    /// Samples per pixel to trace.
    pub spp: u32,
    /// Samples per pixel per frame.
    pub per_frame: u32,
}

impl TestRequest {
    /// The request in the page's address, if it has `test`.
    pub fn from_url() -> Option<Self> {
        let search = window().ok()?.location().search().ok()?;
        let params = web_sys::UrlSearchParams::new_with_str(&search).ok()?;
        params.has("test").then_some(())?;
        let number = |name: &str, default: u32| {
            params.get(name).and_then(|v| v.parse::<u32>().ok()).filter(|&n| n > 0).unwrap_or(default)
        };
        Some(Self { spp: number("spp", 64), per_frame: number("per_frame", 4) })
    }
}

/// Reads `file` as text into `slot`, then asks egui for a frame.
pub fn read_text(file: web_sys::File, slot: PickedFile, egui_ctx: egui::Context) {
    wasm_bindgen_futures::spawn_local(async move {
        let text = wasm_bindgen_futures::JsFuture::from(file.text()).await;
        let text = text.map(|t| t.as_string().unwrap_or_default()).map_err(|e| format!("{e:?}"));
        *slot.borrow_mut() = Some((file.name(), text));
        egui_ctx.request_repaint();
    });
}

/// Opens the browser's file picker for a scene file; the chosen file is
/// read into `slot`.
pub fn pick_file(slot: PickedFile, egui_ctx: egui::Context) {
    let Ok(input) = document().and_then(|d| d.create_element("input")) else { return };
    let Ok(input) = input.dyn_into::<web_sys::HtmlInputElement>() else { return };
    input.set_type("file");
    input.set_accept(".toml,text/plain");
    let chosen = input.clone();
    let on_change = Closure::once_into_js(move || {
        if let Some(file) = chosen.files().and_then(|f| f.get(0)) {
            read_text(file, slot, egui_ctx);
        }
    });
    input.set_onchange(Some(on_change.unchecked_ref()));
    input.click();
}

/// Offers `bytes` as a download named `name`; returns the status line.
pub fn download(name: &str, bytes: &[u8]) -> String {
    let offer = || -> Result<(), JsValue> {
        let parts = js_sys::Array::of1(&Uint8Array::from(bytes));
        let blob = web_sys::Blob::new_with_u8_array_sequence(&parts)?;
        let url = web_sys::Url::create_object_url_with_blob(&blob)?;
        let a: web_sys::HtmlAnchorElement = document()?.create_element("a")?.dyn_into()?;
        a.set_href(&url);
        a.set_download(name);
        a.click();
        web_sys::Url::revoke_object_url(&url)
    };
    match offer() {
        Ok(()) => format!("saved {name} (download)"),
        Err(e) => format!("error: cannot offer {name} for download: {e:?}"),
    }
}

fn set(object: &Object, key: &str, value: impl Into<JsValue>) {
    let _ = Reflect::set(object, &JsValue::from_str(key), &value.into());
}

/// What the page shows, every frame, as `window.ptState`; `scene` is the
/// scene as TOML, which the caller keeps until the scene changes.
pub fn report_state(session: &Session, scene: &str) {
    let Ok(window) = window() else { return };
    let state = Object::new();
    let (w, h) = session.image_size();
    set(&state, "spp", session.stats.accumulated_spp as f64);
    set(&state, "width", w);
    set(&state, "height", h);
    set(&state, "tracing", session.stats.tracing);
    set(&state, "idle", session.idle());
    set(&state, "status", session.files.status.as_str());
    set(&state, "scene", scene);
    set(&state, "panelWidth", session.image_rect().min.x);
    set(&state, "adapter", session.stats.adapter.as_str());
    set(&state, "nonFinite", session.stats.non_finite as f64);
    let _ = Reflect::set(&window, &JsValue::from_str("ptState"), &state);
}

/// The traced image for the browser test, as `window.ptTest`: its linear
/// mean radiance as an EXR file, its size, and the tracing time.
pub fn report_test(session: &Session, (width, height): (u32, u32), exr: &[u8]) {
    let Ok(window) = window() else { return };
    let report = Object::new();
    let stats = &session.stats;
    set(&report, "width", width);
    set(&report, "height", height);
    set(&report, "spp", stats.accumulated_spp as f64);
    set(&report, "tracedMs", stats.traced_ms);
    let samples = width as f64 * height as f64 * stats.accumulated_spp as f64;
    set(&report, "samplesPerSecond", samples / (stats.traced_ms.max(1e-3) * 1e-3));
    set(&report, "adapter", stats.adapter.as_str());
    set(&report, "panelWidth", session.image_rect().min.x);
    set(&report, "exr", Uint8Array::from(exr));
    let _ = Reflect::set(&window, &JsValue::from_str("ptTest"), &report);
}
