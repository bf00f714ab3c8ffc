//! The view's controls (egui): the settings panel on the left, the halves' images in the
//! middle (dragged to orbit and pan, scrolled to dolly), and the keys. It reads the
//! [`App`] and answers with [`Input`]s; the window applies them.

use super::app::{App, Component, Input, Variant, METHODS};
use super::overlay::Overlay;
use crate::config::KNOBS;
use crate::frame::SamplerKind;
use egui::{ComboBox, DragValue, Key, PointerButton, Sense, Ui};

/// Degrees of orbit per pixel dragged.
pub const ORBIT_DEG_PER_PIXEL: f32 = 0.3;

/// The keys, as the panel lists them.
pub const KEYS: &[(&str, &str)] = &[
    ("drag (left)", "orbit about the target"),
    ("drag (right/middle), shift+drag", "pan"),
    ("wheel", "dolly toward the target"),
    ("W A S D, Q E", "fly forward, left, back, right, down, up"),
    ("arrows", "orbit"),
    ("Space", "play / pause"),
    (", .", "step the time back / forward one frame"),
    ("R", "back to the scene's camera"),
    ("H", "flicker heat map on / off"),
    (
        "1 2 3",
        "show the whole frame, the direct light, the indirect light",
    ),
    (
        "V",
        "VPLs overlay (green kept, red replaced; brighter heavier)",
    ),
    ("F", "shadow-map faces overlay"),
    ("I", "ISM atlas inset"),
    (
        "C",
        "copy the view as --camera and `irad render` command line (clipboard and stdout)",
    ),
    ("P", "save the frame (EXR and PNG) in --out"),
    ("Esc", "quit"),
];

/// Draws the controls and the images; returns what the user asked for this frame, and
/// whether they asked to quit.
pub fn ui(ui: &mut Ui, app: &App, textures: &[egui::TextureHandle]) -> (Vec<Input>, bool) {
    let mut inputs = Vec::new();
    egui::Panel::left("settings")
        .resizable(true)
        .default_size(300.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| settings(ui, app, &mut inputs));
        });
    egui::CentralPanel::default_margins().show(ui, |ui| images(ui, app, textures, &mut inputs));
    let quit = keys(ui, app, &mut inputs);
    (inputs, quit)
}

fn settings(ui: &mut Ui, app: &App, inputs: &mut Vec<Input>) {
    let fps = if app.frame_seconds > 0.0 {
        1.0 / app.frame_seconds
    } else {
        0.0
    };
    ui.heading("irad view");
    ui.label(format!(
        "{fps:.1} fps ({:.0} ms: render {:.0} ms), size {}{}",
        app.frame_seconds * 1e3,
        app.render_seconds * 1e3,
        app.cfg.sequence.size,
        if app.auto.is_some() { " (auto)" } else { "" }
    ));
    ui.label(format!("adapter: {}", app.gpu.adapter.name));
    if app.building() {
        ui.label("building the renderers for the new settings ...");
    }
    ui.separator();
    // Time.
    ui.horizontal(|ui| {
        let label = if app.playing { "Pause" } else { "Play" };
        if ui.button(label).clicked() {
            inputs.push(Input::Play(!app.playing));
        }
        let mut t = app.time;
        let d = app.duration();
        if ui
            .add(
                egui::Slider::new(&mut t, 0.0..=d.max(1e-3))
                    .max_decimals(2)
                    .text("s"),
            )
            .changed()
        {
            inputs.push(Input::Scrub(t));
        }
    });
    // Scene.
    let scene = app
        .cfg
        .sequence
        .scene_or(crate::config::DEFAULT_STILL_SCENE);
    ComboBox::from_label("scene")
        .selected_text(scene)
        .show_ui(ui, |ui| {
            for b in crate::scene::builtin::BUILTINS {
                if ui.selectable_label(b.name == scene, b.name).clicked() {
                    inputs.push(Input::Scene(b.name.to_string()));
                }
            }
        });
    ui.horizontal(|ui| {
        let id = ui.scope_id().with("scene_path");
        let mut path: String = ui.data_mut(|d| d.get_temp(id).unwrap_or_default());
        let r = ui.add(egui::TextEdit::singleline(&mut path).hint_text(".gltf/.glb path"));
        if r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter)) && !path.is_empty() {
            inputs.push(Input::Scene(path.clone()));
        }
        ui.data_mut(|d| d.insert_temp(id, path));
    });
    // Method, samplers, VPLs.
    ComboBox::from_label("method")
        .selected_text(app.cfg.method.name())
        .show_ui(ui, |ui| {
            for m in METHODS {
                if ui.selectable_label(m == app.cfg.method, m.name()).clicked() {
                    inputs.push(Input::Method(m));
                }
            }
        });
    if let Some(s) = sampler_combo(ui, "sampler", app.cfg.sampler.kind) {
        inputs.push(Input::Sampler(s));
    }
    ui.horizontal(|ui| {
        let mut on = app.split.is_some();
        if ui.checkbox(&mut on, "split view").changed() {
            inputs.push(Input::Split(on.then_some(SamplerKind::Mh.into())));
        }
        if let Some(b) = app.split {
            if let Some(v) = variant_combo(ui, "right", b, app) {
                inputs.push(Input::Split(Some(v)));
            }
        }
    });
    let mut v = app.cfg.vpls;
    if ui
        .add(DragValue::new(&mut v).range(1..=65535).prefix("VPLs "))
        .changed()
    {
        inputs.push(Input::Vpls(v));
    }
    // The knobs the halves' samplers read.
    let samplers = app.samplers();
    for k in KNOBS
        .iter()
        .filter(|k| samplers.iter().any(|&s| k.used_by(s)))
    {
        let Some(mut value) = k.get(&app.cfg.sampler.knobs) else {
            continue;
        };
        let r = ui.add(
            DragValue::new(&mut value)
                .speed(if k.integer() { 1.0 } else { 0.005 })
                .prefix(format!("{} ", k.name)),
        );
        if r.changed() {
            inputs.push(Input::Knob(k.name, value));
        }
    }
    ui.horizontal(|ui| {
        let mut aa = crate::resolve::aa(&app.cfg);
        if ui
            .add(DragValue::new(&mut aa).range(1..=8).prefix("aa "))
            .changed()
        {
            inputs.push(Input::Aa(aa));
        }
        let mut ism = app.cfg.quality.ism_size;
        ComboBox::from_label("ISM")
            .selected_text(ism.to_string())
            .show_ui(ui, |ui| {
                for s in [8, 16, 32, 64, 128, 256] {
                    ui.selectable_value(&mut ism, s, s.to_string());
                }
            });
        if ism != app.cfg.quality.ism_size {
            inputs.push(Input::IsmSize(ism));
        }
    });
    let mut e = app.cfg.exposure;
    if ui
        .add(
            DragValue::new(&mut e)
                .speed(0.02)
                .range(0.01..=100.0)
                .prefix("exposure "),
        )
        .changed()
    {
        inputs.push(Input::Exposure(e));
    }
    let mut heat = app.heat;
    if ui.checkbox(&mut heat, "flicker heat map (H)").changed() {
        inputs.push(Input::Heat(heat));
    }
    ui.horizontal(|ui| {
        for (c, label) in [
            (Component::Full, "frame (1)"),
            (Component::Direct, "direct (2)"),
            (Component::Indirect, "indirect (3)"),
        ] {
            if ui.radio(app.component == c, label).clicked() && app.component != c {
                inputs.push(Input::Component(c));
            }
        }
    });
    ui.horizontal(|ui| {
        let ov = app.overlays;
        for (o, on, label) in [
            (Overlay::Vpls, ov.vpls, "VPLs (V)"),
            (Overlay::ShadowFaces, ov.shadow_faces, "shadow faces (F)"),
            (Overlay::Ism, ov.ism, "ISM atlas (I)"),
        ] {
            let mut v = on;
            if ui.checkbox(&mut v, label).changed() {
                inputs.push(Input::Overlay(o, v));
            }
        }
    });
    ui.horizontal(|ui| {
        if ui.button("Copy view (C)").clicked() {
            inputs.push(Input::CopyView);
        }
        if ui.button("Save frame (P)").clicked() {
            inputs.push(Input::SaveFrame);
        }
        if ui.button("Scene camera (R)").clicked() {
            inputs.push(Input::ResetCamera);
        }
    });
    if !app.message.is_empty() {
        ui.add(egui::Label::new(egui::RichText::new(&app.message).monospace().small()).wrap());
    }
    ui.separator();
    egui::CollapsingHeader::new("keys").show(ui, |ui| {
        for (k, what) in KEYS {
            ui.label(format!("{k}: {what}"));
        }
    });
}

/// A sampler (instant radiosity with it) or a classical method.
fn variant_combo(ui: &mut Ui, label: &str, current: Variant, app: &App) -> Option<Variant> {
    let mut chosen = None;
    ComboBox::from_label(label)
        .selected_text(current.name())
        .show_ui(ui, |ui| {
            let choices =
                SamplerKind::ALL
                    .iter()
                    .map(|&s| Variant::from(s))
                    .chain(METHODS[1..].iter().map(|&m| Variant {
                        method: m,
                        sampler: app.cfg.sampler.kind,
                    }));
            for v in choices {
                if ui.selectable_label(v == current, v.name()).clicked() {
                    chosen = Some(v);
                }
            }
        });
    chosen.filter(|&v| v != current)
}

fn sampler_combo(ui: &mut Ui, label: &str, current: SamplerKind) -> Option<SamplerKind> {
    let mut chosen = None;
    ComboBox::from_label(label)
        .selected_text(current.name())
        .show_ui(ui, |ui| {
            for s in SamplerKind::ALL {
                if ui.selectable_label(s == current, s.name()).clicked() {
                    chosen = Some(s);
                }
            }
        });
    chosen.filter(|&s| s != current)
}

/// The halves side by side, each scaled to fit its share of the room; dragging and scrolling
/// over them moves the camera.
fn images(ui: &mut Ui, app: &App, textures: &[egui::TextureHandle], inputs: &mut Vec<Input>) {
    let room = ui.available_size();
    let n = textures.len().max(1) as f32;
    ui.horizontal(|ui| {
        for (t, h) in textures.iter().zip(&app.halves) {
            let size = t.size_vec2();
            // Room below for the labels, the flicker and the stages' table.
            let height = (room.y - 230.0).max(0.5 * room.y);
            let scale = (((room.x - 16.0 * n) / n) / size.x)
                .min(height / size.y)
                .max(0.05);
            ui.vertical(|ui| {
                ui.label(match h.variant.method {
                    crate::config::Method::Instant => format!("{} (instant)", h.variant.name()),
                    m => format!("{} radiosity", m.name()),
                });
                let r = ui.add(
                    egui::Image::new(egui::load::SizedTexture::new(t.id(), size * scale))
                        .sense(Sense::click_and_drag()),
                );
                let d = r.drag_delta();
                let shift = ui.input(|i| i.modifiers.shift);
                if r.dragged_by(PointerButton::Primary) && !shift && d != egui::Vec2::ZERO {
                    inputs.push(Input::Orbit {
                        yaw: -d.x * ORBIT_DEG_PER_PIXEL,
                        pitch: d.y * ORBIT_DEG_PER_PIXEL,
                    });
                } else if (r.dragged_by(PointerButton::Secondary)
                    || r.dragged_by(PointerButton::Middle)
                    || (shift && r.dragged_by(PointerButton::Primary)))
                    && d != egui::Vec2::ZERO
                {
                    let px = size.y * scale;
                    inputs.push(Input::Pan {
                        dx: -d.x / px,
                        dy: d.y / px,
                    });
                }
                if r.hovered() {
                    let s = ui.input(|i| i.smooth_scroll_delta.y);
                    if s != 0.0 {
                        inputs.push(Input::Dolly(s / 50.0));
                    }
                }
                let f = &h.flicker;
                ui.label(match f.f1 {
                    Some(f1) => format!(
                        "flicker F1 {f1:.2e} ({:.1}% of the indirect)\nmean over {} still frames {:.2e} ({:.1}%)",
                        100.0 * f.relative.unwrap_or(0.0),
                        f.still_frames,
                        f.mean_f1,
                        100.0 * f.mean_relative
                    ),
                    None => "flicker: - (the view moved)".to_string(),
                });
                if let Some(r) = &h.reference {
                    ui.label(format!(
                        "against the cached reference ({} spp, frame {}): relMSE {:.4}, F1 {}",
                        r.spp,
                        r.frame,
                        r.relmse,
                        match r.f1 {
                            Some(f1) => format!("{f1:.2e} (mean over {} frames {:.2e})", r.frames, r.mean_f1),
                            None => "-".to_string(),
                        }
                    ));
                }
                if let Some(o) = &h.output {
                    let ov = app.overlays;
                    if ov.vpls && !h.kept.is_empty() {
                        let kept = h.kept.iter().filter(|&&k| k).count();
                        ui.label(format!(
                            "VPLs: {} kept, {} replaced ({:.0}%)",
                            kept,
                            h.kept.len() - kept,
                            100.0 * o.selection.replaced
                        ));
                    }
                    if ov.shadow_faces {
                        let d = &o.image.drawn;
                        ui.label(format!(
                            "shadow faces drawn this frame: {} ({} triangles; 0: maps kept)",
                            d.shadow_faces, d.shadow_triangles
                        ));
                    }
                    if ov.ism {
                        let r = &o.image.reused;
                        ui.label(format!(
                            "ISM tiles: {} redrawn, {} kept",
                            r.ism_tiles_drawn, r.ism_tiles_kept
                        ));
                    }
                }
            });
        }
    });
    // The stages of the left half's last frame (CPU stages and GPU passes), in columns.
    if let Some(o) = app.halves.first().and_then(|h| h.output.as_ref()) {
        ui.separator();
        ui.label(format!(
            "stages of a frame of {} ({:.1} ms)",
            app.halves[0].sampler.name(),
            o.seconds * 1e3
        ));
        let stages: Vec<_> = o.stages.iter().filter(|(_, t)| *t > 0.0).collect();
        let rows = stages.len().div_ceil(3);
        egui::Grid::new("stages").striped(true).show(ui, |ui| {
            for r in 0..rows {
                for c in 0..3 {
                    if let Some((name, t)) = stages.get(c * rows + r) {
                        ui.monospace(format!("{name:16} {:7.2} ms", t * 1e3));
                    }
                }
                ui.end_row();
            }
        });
    }
}

/// The keys (when no text field has the focus); returns whether Esc asked to quit.
fn keys(ui: &mut Ui, app: &App, inputs: &mut Vec<Input>) -> bool {
    if ui.ctx().egui_wants_keyboard_input() {
        return false;
    }
    ui.input(|i| {
        let dt = i.stable_dt.min(0.25);
        let axis = |plus: Key, minus: Key| {
            (i.key_down(plus) as i32 - i.key_down(minus) as i32) as f32 * dt
        };
        let (forward, right, up) = (
            axis(Key::W, Key::S),
            axis(Key::D, Key::A),
            axis(Key::E, Key::Q),
        );
        if (forward, right, up) != (0.0, 0.0, 0.0) {
            inputs.push(Input::Fly { forward, right, up });
        }
        let yaw = axis(Key::ArrowRight, Key::ArrowLeft) * 90.0;
        let pitch = axis(Key::ArrowUp, Key::ArrowDown) * 90.0;
        if (yaw, pitch) != (0.0, 0.0) {
            inputs.push(Input::Orbit { yaw, pitch });
        }
        let frame = 1.0 / app.cfg.sequence.fps;
        let pressed = [
            (Key::Space, Input::Play(!app.playing)),
            (Key::Comma, Input::Scrub(app.time - frame)),
            (Key::Period, Input::Scrub(app.time + frame)),
            (Key::R, Input::ResetCamera),
            (Key::H, Input::Heat(!app.heat)),
            (Key::Num1, Input::Component(Component::Full)),
            (Key::Num2, Input::Component(Component::Direct)),
            (Key::Num3, Input::Component(Component::Indirect)),
            (Key::V, Input::Overlay(Overlay::Vpls, !app.overlays.vpls)),
            (
                Key::F,
                Input::Overlay(Overlay::ShadowFaces, !app.overlays.shadow_faces),
            ),
            (Key::I, Input::Overlay(Overlay::Ism, !app.overlays.ism)),
            (Key::C, Input::CopyView),
            (Key::P, Input::SaveFrame),
        ];
        for (k, input) in pressed {
            if i.key_pressed(k) {
                inputs.push(input);
            }
        }
        i.key_pressed(Key::Escape)
    })
}
