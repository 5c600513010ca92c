//! The interactive viewer that the desktop window and the browser page
//! share: settings and their reset rule, the egui panel, the camera
//! controls, and one [`Session`] that traces, shows and reports the image.
//!
//! A shell around it owns the window, the egui integration and the files:
//! the desktop one (`pathtracer view`: winit, egui-winit, path fields) and
//! the browser one (the `pt-web` crate: eframe on WebGPU, a file picker,
//! drops and downloads). Both call [`Session::frame`] once per frame inside
//! their egui pass and then carry out the file [`Actions`] it returns.
//!
//! - [`settings`]: every setting and [`settings::invalidates_accumulation`].
//! - [`panel`]: the egui panel.
//! - [`camera_control`]: orbit, zoom and fly as camera maths.
//! - [`session`]: input, tracing policy, the image's paint callback.

pub mod camera_control;
pub mod panel;
pub mod session;
pub mod settings;

pub use panel::{Actions, Files, Paths, Stats};
pub use session::{Session, error_chain};
pub use settings::{SamplesPerFrame, ViewSettings, invalidates_accumulation};

/// `web_time::Instant` is `std::time::Instant` on a desktop and the page's
/// clock in a browser, where `std`'s clock panics.
pub use web_time::Instant;
