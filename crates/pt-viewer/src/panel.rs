//! The egui control panel: render, scene, camera, display, output, stats.

use egui::{Color32, RichText, Ui};
use pt_core::glam::Vec3;
use pt_core::params::{FLAG_CONNECT, FLAG_GLOW, FLAG_MIS, FLAG_NEE, FLAG_SOBOL, TONEMAP_ACES, TONEMAP_CLAMP};

use crate::settings::{SamplesPerFrame, ViewSettings};

/// Live figures shown in the panel.
#[derive(Clone, Debug, Default)]
pub struct Stats {
    /// Window frames per second.
    pub fps: f64,
    /// Milliseconds of the last tracing dispatch, and whether it was
    /// measured by GPU timestamps (else wall clock around a synced submit).
    pub trace_ms: Option<(f64, bool)>,
    /// Camera samples per second while tracing.
    pub samples_per_second: f64,
    /// Samples per pixel accumulated since the last reset.
    pub accumulated_spp: u64,
    /// Milliseconds spent tracing them (the sum of the frames' times).
    pub traced_ms: f64,
    /// Samples per pixel traced by the last frame.
    pub last_frame_spp: u32,
    /// Non-finite samples discarded since the last reset.
    pub non_finite: u64,
    /// Adapter name and backend.
    pub adapter: String,
    /// Whether tracing is under way.
    pub tracing: bool,
}

/// What the user asked for besides changing settings.
#[derive(Clone, Debug, Default)]
pub struct Actions {
    /// Clear the accumulation.
    pub reset_accumulation: bool,
    /// Put the camera back where the scene file has it.
    pub reset_view: bool,
    /// Save the display image as PNG to this path.
    pub save_png: bool,
    /// Save the mean radiance as EXR.
    pub save_exr: bool,
    /// Load the scene file at `paths.scene`.
    pub load_scene: bool,
    /// Save the scene to `paths.scene`.
    pub save_scene: bool,
}

/// Where files come from and go, and the last file operation's result.
#[derive(Clone, Debug, Default)]
pub struct Files {
    /// Path fields on a desktop; `None` in a browser, where the scene comes
    /// from a file picker or a drop and outputs are downloads.
    pub paths: Option<Paths>,
    /// Result of the last file operation.
    pub status: String,
}

/// Text fields of file paths.
#[derive(Clone, Debug)]
pub struct Paths {
    /// Scene file for load and save.
    pub scene: String,
    /// PNG output.
    pub png: String,
    /// EXR output.
    pub exr: String,
}

fn vec3_edit(ui: &mut Ui, label: &str, v: &mut Vec3, speed: f32) {
    ui.horizontal(|ui| {
        ui.label(label);
        ui.add(egui::DragValue::new(&mut v.x).speed(speed).prefix("x "));
        ui.add(egui::DragValue::new(&mut v.y).speed(speed).prefix("y "));
        ui.add(egui::DragValue::new(&mut v.z).speed(speed).prefix("z "));
    });
}

fn albedo_edit(ui: &mut Ui, label: &str, albedo: &mut Vec3) {
    ui.horizontal(|ui| {
        let mut c = albedo.to_array();
        ui.color_edit_button_rgb(&mut c);
        ui.label(label);
        // Albedo must stay in [0, 1] for energy conservation.
        *albedo = Vec3::from_array(c).clamp(Vec3::ZERO, Vec3::ONE);
    });
}

/// Draws the panel; edits `s` in place and records button presses.
/// Returns the rectangle left for the image, in points.
pub fn draw(
    root: &mut Ui,
    s: &mut ViewSettings,
    stats: &Stats,
    files: &mut Files,
    actions: &mut Actions,
) -> egui::Rect {
    egui::Panel::left("controls").resizable(true).default_size(320.0).max_size(480.0).show(root, |ui| {
        egui::ScrollArea::vertical().show(ui, |ui| {
            statistics(ui, stats);
            ui.separator();
            render(ui, s, actions);
            scene(ui, s, files, actions);
            camera(ui, s, actions);
            display(ui, s);
            output(ui, files, actions);
        });
    });
    root.available_rect_before_wrap()
}

fn statistics(ui: &mut Ui, st: &Stats) {
    ui.heading("Statistics");
    egui::Grid::new("stats").num_columns(2).show(ui, |ui| {
        ui.label("adapter");
        ui.add(egui::Label::new(&st.adapter).truncate()).on_hover_text(&st.adapter);
        ui.end_row();
        ui.label("frames/s");
        ui.label(format!("{:.1}", st.fps));
        ui.end_row();
        ui.label("trace ms/frame");
        ui.label(match st.trace_ms {
            Some((ms, true)) => format!("{ms:.2} (GPU timestamps)"),
            Some((ms, false)) => format!("{ms:.2} (wall clock)"),
            None => "-".into(),
        });
        ui.end_row();
        ui.label("samples/s");
        ui.label(if st.tracing { format!("{:.3e}", st.samples_per_second) } else { "idle".into() });
        ui.end_row();
        ui.label("spp accumulated");
        ui.label(format!("{} (+{} per frame)", st.accumulated_spp, st.last_frame_spp));
        ui.end_row();
        ui.label("NaN/Inf samples");
        let text = format!("{}", st.non_finite);
        ui.label(if st.non_finite > 0 { RichText::new(text).color(Color32::RED) } else { RichText::new(text) });
        ui.end_row();
    });
}

fn render(ui: &mut Ui, s: &mut ViewSettings, actions: &mut Actions) {
    egui::CollapsingHeader::new("Render").default_open(true).show(ui, |ui| {
        let mut auto = matches!(s.samples_per_frame, SamplesPerFrame::Auto { .. });
        ui.horizontal(|ui| {
            ui.label("samples/frame");
            ui.checkbox(&mut auto, "auto");
            match &mut s.samples_per_frame {
                SamplesPerFrame::Auto { budget_ms } => {
                    ui.add(egui::DragValue::new(budget_ms).range(1.0..=1000.0).suffix(" ms budget"));
                }
                SamplesPerFrame::Fixed(n) => {
                    ui.add(egui::DragValue::new(n).range(1..=1024));
                }
            }
        });
        match (auto, s.samples_per_frame) {
            (true, SamplesPerFrame::Fixed(_)) => s.samples_per_frame = SamplesPerFrame::Auto { budget_ms: 30.0 },
            (false, SamplesPerFrame::Auto { .. }) => s.samples_per_frame = SamplesPerFrame::Fixed(4),
            _ => {}
        }
        ui.horizontal(|ui| {
            ui.label("max bounces");
            ui.add(egui::DragValue::new(&mut s.max_bounces).range(0..=64));
            ui.label("RR from");
            ui.add(egui::DragValue::new(&mut s.rr_start).range(1..=64));
        });
        ui.horizontal(|ui| {
            ui.label("target spp (0 = none)");
            ui.add(egui::DragValue::new(&mut s.target_spp).range(0..=1_000_000));
        });
        ui.horizontal(|ui| {
            let mut nee = s.flags & FLAG_NEE != 0;
            let mut mis = s.flags & FLAG_MIS != 0;
            ui.checkbox(&mut nee, "light sampling (NEE)");
            ui.add_enabled(nee, egui::Checkbox::new(&mut mis, "MIS"));
            let mut sobol = s.flags & FLAG_SOBOL != 0;
            ui.checkbox(&mut sobol, "Sobol");
            let mut glow = s.flags & FLAG_GLOW != 0;
            ui.checkbox(&mut glow, "glow lobe").on_hover_text("BSDF sampling also aims around the light");
            // Only the switches shown here change; other flags are kept.
            for (bit, on) in [(FLAG_NEE, nee), (FLAG_MIS, mis), (FLAG_SOBOL, sobol), (FLAG_GLOW, glow)] {
                s.flags = if on { s.flags | bit } else { s.flags & !bit };
            }
        });
        // On a row of its own, so that the panel keeps its width.
        ui.horizontal(|ui| {
            let nee = s.flags & FLAG_NEE != 0;
            let mut connect = s.flags & FLAG_CONNECT != 0;
            ui.add_enabled(nee, egui::Checkbox::new(&mut connect, "connections")).on_hover_text(
                "light reflected once by a wall, reached through wall points the light shines on (rooms whose walls \
                 do not shadow the light)",
            );
            s.flags = if connect { s.flags | FLAG_CONNECT } else { s.flags & !FLAG_CONNECT };
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut s.paused, "pause");
            if ui.button("reset accumulation").clicked() {
                actions.reset_accumulation = true;
            }
        });
    });
}

fn scene(ui: &mut Ui, s: &mut ViewSettings, files: &mut Files, actions: &mut Actions) {
    egui::CollapsingHeader::new("Scene").default_open(false).show(ui, |ui| {
        ui.label(RichText::new("Light").strong());
        let l = &mut s.scene.light;
        vec3_edit(ui, "position", &mut l.center, 0.01);
        ui.horizontal(|ui| {
            ui.label("radius");
            ui.add(egui::DragValue::new(&mut l.radius).speed(0.005).range(1e-4..=10.0));
        });
        // Radiance as a colour (max channel 1) times an intensity.
        let intensity = l.radiance.max_element();
        let mut colour = if intensity > 0.0 { (l.radiance / intensity).to_array() } else { [1.0; 3] };
        let mut new_intensity = intensity;
        ui.horizontal(|ui| {
            ui.color_edit_button_rgb(&mut colour);
            ui.label("intensity");
            ui.add(egui::DragValue::new(&mut new_intensity).speed(0.1).range(0.0..=1e4));
        });
        let c = Vec3::from_array(colour);
        let c = if c.max_element() > 0.0 { c / c.max_element() } else { Vec3::ONE };
        l.radiance = c * new_intensity;

        for sp in &mut s.scene.spheres {
            ui.label(RichText::new(&sp.name).strong());
            vec3_edit(ui, "centre", &mut sp.sphere.center, 0.01);
            ui.horizontal(|ui| {
                ui.label("radius");
                ui.add(egui::DragValue::new(&mut sp.sphere.radius).speed(0.005).range(1e-4..=100.0));
            });
            albedo_edit(ui, "albedo", &mut sp.sphere.albedo);
        }
        ui.label(RichText::new("Walls").strong());
        for w in &mut s.scene.walls {
            albedo_edit(ui, &w.name, &mut w.wall.albedo);
        }
        ui.separator();
        if let Some(paths) = &mut files.paths {
            ui.horizontal(|ui| {
                ui.label("file");
                ui.text_edit_singleline(&mut paths.scene);
            });
        }
        ui.horizontal(|ui| {
            let load = if files.paths.is_some() { "load" } else { "open scene file…" };
            actions.load_scene |= ui.button(load).clicked();
            actions.save_scene |= ui.button("save").clicked();
        });
        if files.paths.is_none() {
            ui.label("or drop a scene file (TOML) on the page");
        }
    });
}

fn camera(ui: &mut Ui, s: &mut ViewSettings, actions: &mut Actions) {
    egui::CollapsingHeader::new("Camera").default_open(false).show(ui, |ui| {
        ui.horizontal(|ui| {
            ui.label("vertical FOV");
            ui.add(egui::Slider::new(&mut s.scene.camera.vfov_degrees, 5.0..=120.0).suffix("°"));
        });
        vec3_edit(ui, "position", &mut s.scene.camera.position, 0.01);
        vec3_edit(ui, "look at", &mut s.scene.camera.look_at, 0.01);
        if ui.button("reset view").clicked() {
            actions.reset_view = true;
        }
        ui.label("drag: orbit · wheel: zoom · WASD/QE: fly (shift: faster)");
    });
}

fn display(ui: &mut Ui, s: &mut ViewSettings) {
    egui::CollapsingHeader::new("Display").default_open(true).show(ui, |ui| {
        ui.horizontal(|ui| {
            ui.label("exposure");
            ui.add(egui::Slider::new(&mut s.exposure, -8.0..=8.0).suffix(" EV"));
        });
        ui.horizontal(|ui| {
            ui.label("tone map");
            ui.radio_value(&mut s.tonemap, TONEMAP_ACES, "ACES filmic");
            ui.radio_value(&mut s.tonemap, TONEMAP_CLAMP, "clamp");
        });
    });
}

fn output(ui: &mut Ui, files: &mut Files, actions: &mut Actions) {
    egui::CollapsingHeader::new("Output").default_open(true).show(ui, |ui| {
        match &mut files.paths {
            Some(paths) => {
                ui.horizontal(|ui| {
                    ui.text_edit_singleline(&mut paths.png);
                    actions.save_png |= ui.button("save PNG").clicked();
                });
                ui.horizontal(|ui| {
                    ui.text_edit_singleline(&mut paths.exr);
                    actions.save_exr |= ui.button("save EXR").clicked();
                });
            }
            None => {
                ui.horizontal(|ui| {
                    actions.save_png |= ui.button("save PNG").clicked();
                    actions.save_exr |= ui.button("save EXR").clicked();
                });
            }
        }
        if !files.status.is_empty() {
            ui.label(&files.status);
        }
    });
}
