//! The panels: menu bar, tool bar, animation bar, wind, light, parameters, kernel timings,
//! status bar, the 3-D view's mouse handling and its context menu.

use std::collections::VecDeque;

use clothlab::core::RenderMode;
use clothlab::core::params::StiffnessUnits;
use clothlab::core::params::{MAX_STRAIN_ITERATIONS, MAX_SUBSTEPS};
use clothlab::core::timing::SUBSTEP;
use egui::{Color32, RichText};
use egui_plot::{Legend, Line, Plot, PlotPoints};

use super::input::{self, Action, Panel, SHORTCUT_KEYS, Tool};
use super::{Command, UiState};
use clothlab::backend::{Api, Backend};

/// What the panels show that the UI does not own.
pub struct Info<'a> {
    /// Running solver.
    pub backend: Backend,
    /// Its variant and what its adapter and cloth offer (GPU solvers).
    pub variant: Option<(clothlab::engine::Variant, clothlab::engine::Caps)>,
    /// Drawing API.
    pub api: Api,
    /// The window's adapter in one line.
    pub adapter: String,
    /// Where the solver runs when that is not the window's API (the CPU, or a GPU solver
    /// of another API whose state is copied to the window each frame), in one line.
    pub solver_adapter: Option<String>,
    /// Last substep time.
    pub substep: Option<super::sim::SubstepTime>,
    /// Per-frame kernel timings.
    pub history: &'a VecDeque<Vec<(String, f64)>>,
    /// Frames since reset.
    pub frames: u64,
    /// The scene image to paint behind the panels (wgpu), if egui paints it.
    pub scene_tex: Option<egui::TextureId>,
    /// Scene size in pixels.
    pub scene_size: (u32, u32),
}

/// A drag of the cloth with the cursor tool, in scene pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drag {
    /// Pressed at `(x, y)`: grab what is there.
    Start {
        /// Pixel x.
        x: f32,
        /// Pixel y.
        y: f32,
    },
    /// Moved to `(x, y)`.
    Move {
        /// Pixel x.
        x: f32,
        /// Pixel y.
        y: f32,
    },
    /// Released.
    End,
}

fn shown(ui: &UiState, p: Panel) -> bool {
    ui.panels.contains(&p)
}

/// Lays out one frame of the UI; returns a cloth drag, if any.
pub fn draw(root: &mut egui::Ui, s: &mut UiState, info: &Info<'_>, out: &mut Vec<Command>) -> Option<Drag> {
    let ctx = root.ctx().clone();
    // Shortcuts, unless a text field has the keyboard.
    if !ctx.egui_wants_keyboard_input() {
        ctx.input(|i| {
            for k in SHORTCUT_KEYS {
                if i.key_pressed(k)
                    && let Some(a) = input::shortcut(k, i.modifiers.command)
                {
                    out.push(Command::Action(a));
                }
            }
        });
    }
    // The scene behind everything (wgpu; Vulkan puts it under egui itself).
    if let Some(tex) = info.scene_tex {
        let rect = ctx.content_rect();
        ctx.layer_painter(egui::LayerId::background()).image(
            tex,
            rect,
            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
            Color32::WHITE,
        );
    }
    egui::Panel::top("menu").show(root, |ui| menu_bar(ui, s, out));
    if shown(s, Panel::Toolbar) {
        egui::Panel::top("tools").show(root, |ui| tool_bar(ui, s, out));
    }
    if shown(s, Panel::Status) {
        egui::Panel::bottom("status").show(root, |ui| status_bar(ui, s, info, out));
    }
    if shown(s, Panel::Animation) {
        egui::Panel::bottom("animation").show(root, |ui| animation_bar(ui, s, info, out));
    }
    let side =
        [Panel::Wind, Panel::Light, Panel::Parameters, Panel::Scene, Panel::Timings].iter().any(|p| shown(s, *p));
    if side {
        egui::Panel::right("side").resizable(true).default_size(300.0).show(root, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.label(RichText::new("Backend").strong());
                backend_picker(ui, info, out);
                if let Some((v, caps)) = info.variant {
                    variant_panel(ui, v, caps, out);
                }
                ui.horizontal(|ui| {
                    ui.label("API");
                    for api in [Api::Wgpu, Api::Vulkan, Api::Gl] {
                        if ui.selectable_label(info.api == api, format!("{api:?}")).clicked() && info.api != api {
                            out.push(Command::Api(api));
                        }
                    }
                });
                if shown(s, Panel::Wind) {
                    ui.separator();
                    wind_panel(ui, s);
                }
                if shown(s, Panel::Light) {
                    ui.separator();
                    light_panel(ui, s);
                }
                if shown(s, Panel::Parameters) {
                    ui.separator();
                    params_panel(ui, s, out);
                }
                if shown(s, Panel::Scene) {
                    ui.separator();
                    scene_panel(ui, s, out);
                }
                if shown(s, Panel::Timings) {
                    ui.separator();
                    timing_chart(ui, info);
                }
            });
        });
    }
    if s.open_dialog {
        open_dialog(&ctx, s, out);
    }
    if s.about {
        egui::Window::new("About clothlab").collapsible(false).open(&mut s.about).show(&ctx, |ui| {
            ui.label("clothlab — a mass-spring cloth on CPU, wgpu, raw Vulkan and raw OpenGL.");
            ui.label(
                "After the master's thesis \"Interactive Cloth Simulation Accelerated by GPU\" (Melichar, Brno, 2016).",
            );
            ui.label(format!("version {}", env!("CARGO_PKG_VERSION")));
        });
    }
    // The 3-D view: what is left, transparent, takes the mouse.
    egui::CentralPanel::no_frame().show(root, |ui| view_area(ui, s, info, out)).inner
}

fn menu_bar(ui: &mut egui::Ui, s: &mut UiState, out: &mut Vec<Command>) {
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| {
            if ui.button("Open scene…").clicked() {
                s.open_dialog = true;
                ui.close();
            }
            item(ui, "Reset", "Ctrl+R", Action::Reset, out);
            item(ui, "Save image", "Ctrl+S", Action::SaveImage, out);
            item(ui, "Exit", "Ctrl+Q", Action::Exit, out);
        });
        ui.menu_button("View", |ui| view_items(ui, out));
        ui.menu_button("Animation", |ui| animation_items(ui, s, out));
        ui.menu_button("Window", |ui| {
            for p in Panel::ALL {
                let mut on = shown(s, p);
                if ui.checkbox(&mut on, p.name()).clicked() {
                    out.push(Command::Action(Action::TogglePanel(p)));
                }
            }
        });
        ui.menu_button("Help", |ui| item(ui, "About", "", Action::About, out));
    });
}

fn item(ui: &mut egui::Ui, label: &str, key: &str, a: Action, out: &mut Vec<Command>) {
    if ui.add(egui::Button::new(label).shortcut_text(key)).clicked() {
        out.push(Command::Action(a));
        ui.close();
    }
}

/// The View menu (also in the context menu).
fn view_items(ui: &mut egui::Ui, out: &mut Vec<Command>) {
    item(ui, "Cursor", "C", Action::Tool(Tool::Cursor), out);
    item(ui, "Rotate X", "X", Action::Tool(Tool::RotateX), out);
    item(ui, "Rotate Y", "Y", Action::Tool(Tool::RotateY), out);
    item(ui, "Rotate Z", "Z", Action::Tool(Tool::RotateZ), out);
    item(ui, "Rotate free", "F", Action::Tool(Tool::RotateFree), out);
    ui.separator();
    item(ui, "Zoom in", "I", Action::ZoomIn, out);
    item(ui, "Zoom out", "O", Action::ZoomOut, out);
    ui.separator();
    item(ui, "Points", "P", Action::Mode(RenderMode::Points), out);
    item(ui, "Lines", "L", Action::Mode(RenderMode::Lines), out);
    item(ui, "Triangles", "T", Action::Mode(RenderMode::Triangles), out);
}

/// The Animation menu (also in the context menu).
fn animation_items(ui: &mut egui::Ui, s: &UiState, out: &mut Vec<Command>) {
    item(ui, if s.paused { "Play" } else { "Pause" }, "Space", Action::TogglePlay, out);
}

fn tool_bar(ui: &mut egui::Ui, s: &UiState, out: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        for (t, label, tip) in [
            (Tool::Cursor, "✋ Cursor", "Grab and drag the cloth (C)"),
            (Tool::RotateX, "⟲ X", "Rotate about x (X)"),
            (Tool::RotateY, "⟲ Y", "Rotate about y (Y)"),
            (Tool::RotateZ, "⟲ Z", "Roll (Z)"),
            (Tool::RotateFree, "⟲ free", "Rotate freely (F)"),
        ] {
            if ui.selectable_label(s.tool == t, label).on_hover_text(tip).clicked() {
                out.push(Command::Action(Action::Tool(t)));
            }
        }
        ui.separator();
        if ui.button("🔍+").on_hover_text("Zoom in (I)").clicked() {
            out.push(Command::Action(Action::ZoomIn));
        }
        if ui.button("🔍−").on_hover_text("Zoom out (O)").clicked() {
            out.push(Command::Action(Action::ZoomOut));
        }
        ui.separator();
        for (m, label) in
            [(RenderMode::Points, "Points"), (RenderMode::Lines, "Lines"), (RenderMode::Triangles, "Triangles")]
        {
            if ui.selectable_label(s.mode == m, label).clicked() {
                out.push(Command::Action(Action::Mode(m)));
            }
        }
    });
}

fn animation_bar(ui: &mut egui::Ui, s: &mut UiState, info: &Info<'_>, out: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        if ui.button(if s.paused { "▶ Play" } else { "⏸ Pause" }).clicked() {
            out.push(Command::Action(Action::TogglePlay));
        }
        if ui.button("⟲ Reset").clicked() {
            out.push(Command::Action(Action::Reset));
        }
        ui.separator();
        let mut substeps = s.params.substeps;
        // Up to 256 (logarithmic): XPBD in small steps and physical stiffness at large n
        // take 32 … 260 (the state keeps velocities, so no count loses the motion).
        let r = ui.add(egui::Slider::new(&mut substeps, 1..=256).logarithmic(true).text("substeps per frame"));
        if r.changed() && substeps <= MAX_SUBSTEPS {
            s.params.substeps = substeps;
            if s.params.validate().is_ok() {
                out.push(Command::Params(s.params.clone()));
            }
        }
        ui.label(format!("frame {}", info.frames));
    });
}

fn status_bar(ui: &mut egui::Ui, s: &mut UiState, info: &Info<'_>, out: &mut Vec<Command>) {
    ui.horizontal(|ui| {
        ui.label(format!("{:.0} fps", s.fps));
        ui.separator();
        match &info.substep {
            Some(t) => ui.label(substep_label(t)),
            None => ui.label("— ms per substep"),
        };
        ui.separator();
        if s.scene.cloth.is_mesh() {
            // A mesh has no grid side to change: its size, not a slider that would do nothing.
            ui.label(format!("mesh: {} particles", s.scene.num_particles()));
        } else {
            let r = ui.add(egui::Slider::new(&mut s.grid_n, 10..=1024).logarithmic(true).text("grid"));
            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                out.push(Command::Grid(s.grid_n));
            }
        }
        ui.separator();
        ui.label(status_line(info)).on_hover_text(format!("window: {}", info.adapter));
        ui.separator();
        ui.label(&s.message);
    });
}

/// The status bar's backend and adapter: the solver's adapter when it is not the window's
/// (its state is then copied to the window each frame; the window's adapter is in the
/// label's tooltip, the line would not fit the bar).
pub fn status_line(info: &Info<'_>) -> String {
    match &info.solver_adapter {
        None => format!("{} · {:?} · {}", info.backend.name(), info.api, info.adapter),
        Some(solver) => {
            format!("{} on {solver} · drawn by {:?}", info.backend.name(), info.api)
        }
    }
}

/// The status bar's substep time, saying which clock measured it.
pub fn substep_label(t: &super::sim::SubstepTime) -> String {
    match t {
        super::sim::SubstepTime::Measured(ns) => format!("{:.2} ms per substep", ns / 1e6),
        super::sim::SubstepTime::Wall { wall, timestamps } => format!(
            // "Kernel timings": GPU timestamps, or a CPU solver's own median per substep
            // (which rayon's stalls behind a busy renderer can leave far below the mean).
            "{:.2} ms per substep (wall clock: the kernel timings' {:.2} ms do not fit the frame's time)",
            wall / 1e6,
            timestamps / 1e6
        ),
        super::sim::SubstepTime::NoTimestamps { wall } => {
            format!("{:.2} ms per substep (wall clock: this adapter gives no kernel timings)", wall / 1e6)
        }
    }
}

fn backend_picker(ui: &mut egui::Ui, info: &Info<'_>, out: &mut Vec<Command>) {
    egui::ComboBox::from_id_salt("backend").selected_text(info.backend.name()).show_ui(ui, |ui| {
        for b in Backend::ALL {
            if ui.selectable_label(b == info.backend, b.name()).clicked() && b != info.backend {
                out.push(Command::Backend(b));
            }
        }
    });
}

/// The GPU solver's variant: the presets (as they fit the adapter and the cloth: a mesh
/// has no table=uniform or shuffles, an adapter may lack push constants or subgroups),
/// and one picker per switch (see `clothlab::engine::variant::SWITCHES`); a pick the
/// adapter or cloth lacks is refused with the reason in the status bar.
fn variant_panel(
    ui: &mut egui::Ui,
    v: clothlab::engine::Variant,
    caps: clothlab::engine::Caps,
    out: &mut Vec<Command>,
) {
    use clothlab::engine::variant::{PRESETS, SWITCHES};
    let preset = PRESETS.iter().find(|(_, p)| p.fit(&caps) == v);
    let title = match preset {
        Some((name, p)) if *p != v => format!("Variant: {name} (fitted)"),
        Some((name, _)) => format!("Variant: {name}"),
        None => format!("Variant: {}", v.label()),
    };
    let header = egui::CollapsingHeader::new(title).id_salt("variant").show(ui, |ui| {
        ui.horizontal(|ui| {
            for (name, preset) in PRESETS {
                let fitted = preset.fit(&caps);
                if ui.selectable_label(v == fitted, name).clicked() && v != fitted {
                    out.push(Command::Variant(fitted));
                }
            }
        });
        egui::Grid::new("switches").num_columns(2).show(ui, |ui| {
            for s in SWITCHES {
                ui.label(s.key).on_hover_text(s.help);
                let now = v.get(s.key).unwrap_or_default();
                egui::ComboBox::from_id_salt(s.key).selected_text(now).show_ui(ui, |ui| {
                    for value in s.values {
                        if ui.selectable_label(*value == now, *value).clicked() && *value != now {
                            let mut next = v;
                            if next.set(s.key, value).is_ok() {
                                out.push(Command::Variant(next));
                            }
                        }
                    }
                });
                ui.end_row();
            }
        });
    });
    header.header_response.on_hover_text(format!("{}: {}", v.label(), v.switches().replace(',', ", ")));
}

fn wind_panel(ui: &mut egui::Ui, s: &mut UiState) {
    ui.label(RichText::new("Wind").strong());
    ui.checkbox(&mut s.wind_on, "on");
    ui.add(egui::Slider::new(&mut s.wind_speed, 0.0..=15.0).text("speed m/s"));
    ui.add(egui::Slider::new(&mut s.wind_azimuth, 0.0..=360.0).text("direction °"));
    ui.add(egui::Slider::new(&mut s.gusts, 0.0..=1.0).text("gusts"));
}

/// Scene files the Open scene window lists: `*.toml` in `./scenes` and `./`, sorted.
fn scene_files() -> Vec<std::path::PathBuf> {
    let mut files: Vec<std::path::PathBuf> = ["scenes", "."]
        .iter()
        .filter_map(|d| std::fs::read_dir(d).ok())
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml") && p.file_name().is_some_and(|f| f != "Cargo.toml"))
        .collect();
    files.sort();
    files
}

/// File → Open scene: the scene files found here, or a path typed in (or drop a file on
/// the window).
fn open_dialog(ctx: &egui::Context, s: &mut UiState, out: &mut Vec<Command>) {
    let mut open = true;
    egui::Window::new("Open scene").collapsible(false).open(&mut open).show(ctx, |ui| {
        let files = scene_files();
        if files.is_empty() {
            ui.label("No scene files in ./scenes or here.");
        }
        for f in files {
            if ui.button(f.display().to_string()).clicked() {
                out.push(Command::OpenScene(f));
            }
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("file");
            let edit = ui.text_edit_singleline(&mut s.open_path);
            let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if (ui.button("Open").clicked() || enter) && !s.open_path.trim().is_empty() {
                out.push(Command::OpenScene(s.open_path.trim().into()));
            }
        });
        ui.label(RichText::new("or drop a .toml file on the window").weak());
    });
    s.open_dialog &= open;
}

/// The floor, spheres and boxes: edited here, applied under the same cloth with Apply.
fn scene_panel(ui: &mut egui::Ui, s: &mut UiState, out: &mut Vec<Command>) {
    ui.label(RichText::new(format!("Scene — {}", s.scene_title)).strong());
    let c = &s.scene.cloth;
    match &c.mesh {
        Some(file) if c.is_mesh() => ui.label(format!(
            "cloth: mesh {}, {} particles, pinned: {}",
            file.display(),
            s.scene.num_particles(),
            c.pinning.label()
        )),
        _ => ui.label(format!("cloth {n}×{n}, {} m, pinned: {}", c.size, c.pinning.label(), n = c.n)),
    };
    // A scene of several cloths: each one, with its particles and mass.
    let parts = c.mesh_data.as_ref().map_or(&[][..], |m| m.parts.as_slice());
    for (k, part) in parts.iter().enumerate() {
        let mass = part.mass.map_or("cloth_mass".to_owned(), |m| format!("{m} kg"));
        ui.label(format!("  cloth[{k}]: {}, {} particles, {mass}", part.label, part.count));
    }
    let sc = &mut s.scene;
    let mut floor = sc.floor_y.is_some();
    ui.horizontal(|ui| {
        ui.checkbox(&mut floor, "floor");
        let mut y = sc.floor_y.unwrap_or(0.0);
        if floor {
            ui.add(egui::DragValue::new(&mut y).speed(0.01).range(-100.0..=100.0).suffix(" m"));
        }
        sc.floor_y = floor.then_some(y);
    });
    let xyz = |ui: &mut egui::Ui, v: &mut [f32]| {
        for c in v.iter_mut().take(3) {
            ui.add(egui::DragValue::new(c).speed(0.01).range(-100.0..=100.0));
        }
    };
    let mut remove = None;
    for (i, sp) in sc.spheres.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("sphere {i}"));
            xyz(ui, &mut sp.center);
            ui.label("r");
            ui.add(egui::DragValue::new(&mut sp.radius).speed(0.01).range(0.01..=50.0));
            if ui.small_button("remove").clicked() {
                remove = Some(i);
            }
        });
    }
    if let Some(i) = remove.take() {
        sc.remove_collider(clothlab::core::ColliderId::Sphere(i));
    }
    for (i, b) in sc.boxes.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("box {i} min"));
            xyz(ui, &mut b.min);
        });
        ui.horizontal(|ui| {
            ui.label(format!("box {i} max"));
            xyz(ui, &mut b.max);
            if ui.small_button("remove").clicked() {
                remove = Some(i);
            }
        });
        // Keep every max above its min while dragging.
        for k in 0..3 {
            b.max[k] = b.max[k].max(b.min[k] + 0.01);
        }
    }
    if let Some(i) = remove {
        sc.remove_collider(clothlab::core::ColliderId::Box(i));
    }
    ui.horizontal(|ui| {
        let room = clothlab::core::scene::MAX_COLLIDERS;
        if ui.add_enabled(sc.spheres.len() < room, egui::Button::new("+ sphere")).clicked() {
            sc.spheres.push(clothlab::core::Sphere::new([0.0, 0.4, 0.0], 0.4));
        }
        if ui.add_enabled(sc.boxes.len() < room, egui::Button::new("+ box")).clicked() {
            sc.boxes.push(clothlab::core::Aabb::new([-0.4, 0.0, -0.4], [0.4, 0.6, 0.4]));
        }
        if ui.button("Apply").on_hover_text("the cloth stays where it is").clicked() {
            out.push(Command::Scene(Box::new(sc.clone())));
        }
    });
}

fn light_panel(ui: &mut egui::Ui, s: &mut UiState) {
    ui.label(RichText::new("Light").strong());
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let range = if k == 1 { 0.5..=10.0 } else { -8.0..=8.0 };
        ui.add(egui::Slider::new(&mut s.light[k], range).text(format!("{name} m")));
    }
}

/// The thinnest self-collision thickness a parameter accepts, m (`SimParams::validate`).
const MIN_THICKNESS: f32 = 1e-3;

fn params_panel(ui: &mut egui::Ui, s: &mut UiState, out: &mut Vec<Command>) {
    ui.label(RichText::new("Parameters").strong());
    // A mesh's springs are its edges and the springs across them: no shear family.
    let mesh = s.scene.cloth.is_mesh();
    let p = &mut s.params;
    // Stiffness as fractions of the explicit limit, or a material in physical units (a
    // substep count Verlet cannot integrate is refused, naming the one it needs).
    let mut units_changed = false;
    ui.horizontal(|ui| {
        ui.label("stiffness");
        for (units, name) in [(StiffnessUnits::Fraction, "fraction of limit"), (StiffnessUnits::Physical, "physical")] {
            if ui.selectable_label(p.stiffness_units == units, name).clicked() && p.stiffness_units != units {
                p.stiffness_units = units;
                units_changed = true;
            }
        }
    });
    // Friction: the thesis's share of the tangential velocity, or Coulomb's coefficients
    // (SimParams::static_friction, kinetic_friction; either above 0 switches to Coulomb).
    ui.horizontal(|ui| {
        ui.label("friction");
        let coulomb = p.coulomb();
        if ui.selectable_label(!coulomb, "share").clicked() && coulomb {
            (p.static_friction, p.kinetic_friction) = (0.0, 0.0);
            units_changed = true;
        }
        if ui.selectable_label(coulomb, "Coulomb").clicked() && !coulomb {
            (p.static_friction, p.kinetic_friction) = (0.5, 0.4);
            units_changed = true;
        }
    });
    // The integrator (thesis §4.1): an explicit one that cannot integrate these springs
    // at this dt is refused in the status bar, naming the substeps it needs.
    ui.horizontal(|ui| {
        ui.label("integrator");
        egui::ComboBox::from_id_salt("integrator").selected_text(p.integrator.name()).show_ui(ui, |ui| {
            for i in clothlab::core::Integrator::ALL {
                if ui.selectable_label(p.integrator == i, i.name()).clicked() && p.integrator != i {
                    p.integrator = i;
                    units_changed = true;
                }
            }
        });
    });
    if p.integrator == clothlab::core::Integrator::Implicit {
        units_changed |= ui
            .add(
                egui::Slider::new(&mut p.cg_iterations, 1..=clothlab::core::params::MAX_CG_ITERATIONS.min(64))
                    .text("CG iterations"),
            )
            .changed();
    }
    if p.integrator == clothlab::core::Integrator::Xpbd {
        units_changed |= ui.add(egui::Slider::new(&mut p.xpbd_iterations, 1..=16).text("XPBD iterations")).changed();
    }
    if p.integrator == clothlab::core::Integrator::Vbd {
        units_changed |= ui.add(egui::Slider::new(&mut p.vbd_iterations, 1..=64).text("VBD iterations")).changed();
        units_changed |= ui.add(egui::Slider::new(&mut p.vbd_rho, 0.0..=0.99).text("VBD Chebyshev ρ")).changed();
    }
    let physical = p.stiffness_units == StiffnessUnits::Physical;
    let mut changed = units_changed;
    let mut f = |ui: &mut egui::Ui, v: &mut f32, r: std::ops::RangeInclusive<f32>, label: &str, log: bool| {
        changed |= ui.add(egui::Slider::new(v, r).text(label).logarithmic(log)).changed();
    };
    f(ui, &mut p.frame_dt, 1.0 / 240.0..=1.0 / 15.0, "frame dt s", false);
    f(ui, &mut p.gravity[1], -30.0..=0.0, "gravity y m/s²", false);
    f(ui, &mut p.cloth_mass, 0.01..=10.0, "cloth mass kg", true);
    f(ui, &mut p.air_drag, 0.0..=5.0, "air drag 1/s", false);
    f(ui, &mut p.damping, 0.0..=0.1, "damping", false);
    if physical {
        f(ui, &mut p.stretch_modulus, 1.0..=5000.0, "stretch modulus N/m", true);
        if !mesh {
            f(ui, &mut p.shear_modulus, 0.1..=5000.0, "shear modulus N/m", true);
        }
        f(ui, &mut p.bend_modulus, 1e-6..=1.0, "bend modulus N·m", true);
    } else {
        f(ui, &mut p.structural_stiffness, 0.001..=1.0, "structural κ", true);
        if !mesh {
            f(ui, &mut p.shear_stiffness, 0.001..=1.0, "shear κ", true);
        }
        f(ui, &mut p.bend_stiffness, 0.0001..=1.0, "bend κ", true);
    }
    let damping = if physical { "damping ratio" } else { "damping" };
    f(ui, &mut p.structural_damping, 0.0..=1.0, &format!("structural {damping}"), false);
    if !mesh {
        f(ui, &mut p.shear_damping, 0.0..=1.0, &format!("shear {damping}"), false);
    }
    f(ui, &mut p.bend_damping, 0.0..=1.0, &format!("bend {damping}"), false);
    if mesh {
        ui.label(RichText::new("a mesh: edges (structural) and springs across them (bend); no shear family").weak());
    }
    f(ui, &mut p.strain_limit, 0.01..=1.0, "strain limit τ", false);
    if p.coulomb() {
        // Coulomb's coefficients replace the share (SimParams::static_friction); μk ≤ μs.
        f(ui, &mut p.static_friction, 0.0..=2.0, "static friction μs", false);
        f(ui, &mut p.kinetic_friction, 0.0..=2.0, "kinetic friction μk", false);
        p.kinetic_friction = p.kinetic_friction.min(p.static_friction);
    } else {
        f(ui, &mut p.friction, 0.0..=1.0, "friction", false);
    }
    f(ui, &mut p.collision_margin, 0.0..=0.05, "collision margin m", false);
    f(ui, &mut p.wind_coefficient, 0.0..=5.0, "wind coefficient", false);
    changed |= ui
        .add(egui::Slider::new(&mut p.strain_iterations, 0..=MAX_STRAIN_ITERATIONS.min(16)).text("strain passes"))
        .changed();
    // Self-collision (off by default): the particles' contact or the triangles' (the CPU
    // solvers; a GPU backend refuses it in the status bar). A grid's thickness is bounded
    // by its spacing (SimParams::max_thickness_on_grid): the slider ends there (a mesh's
    // bound, from its closest pair, is refused in the status bar).
    ui.horizontal(|ui| {
        ui.label("self-collision");
        egui::ComboBox::from_id_salt("self_collision").selected_text(p.self_collision.name()).show_ui(ui, |ui| {
            for mode in clothlab::core::SelfCollision::ALL {
                changed |= ui.selectable_value(&mut p.self_collision, mode, mode.name()).changed();
            }
        });
        let max_thickness = if mesh {
            0.1
        } else {
            let c = &s.scene.cloth;
            clothlab::core::SimParams::max_thickness_on_grid(p.self_collision, c.size / (c.n - 1) as f32).min(0.1)
        };
        if p.self_collision.on() {
            let lo = MIN_THICKNESS.min(max_thickness);
            if p.self_thickness > max_thickness {
                p.self_thickness = max_thickness.max(MIN_THICKNESS);
                changed = true;
            }
            changed |= ui
                .add(egui::Slider::new(&mut p.self_thickness, lo..=max_thickness).logarithmic(true).text("thickness m"))
                .changed();
        }
    });
    if changed {
        match p.validate() {
            Ok(()) => out.push(Command::Params(p.clone())),
            Err(e) => s.message = format!("{e}"),
        }
    }
    if ui.button("Defaults").clicked() {
        *p = clothlab::core::SimParams { wind: p.wind, ..Default::default() };
        out.push(Command::Params(p.clone()));
    }
}

fn timing_chart(ui: &mut egui::Ui, info: &Info<'_>) {
    ui.label(RichText::new("Kernel timings (ms, median per frame)").strong());
    match info.substep {
        Some(super::sim::SubstepTime::Wall { .. }) => {
            ui.colored_label(
                Color32::from_rgb(200, 120, 0),
                "GPU timestamps disagree with the wall clock on this adapter once it has drawn: the per-kernel figures below are not true (clothlab sim / bench measure on an undrawn device)",
            );
        }
        Some(super::sim::SubstepTime::NoTimestamps { .. }) => {
            ui.colored_label(
                Color32::from_rgb(200, 120, 0),
                "this adapter gives no kernel timings here (its timestamps read zero in the window's context): only the wall clock's substep is true",
            );
        }
        _ => {}
    }
    let mut labels: Vec<&str> = Vec::new();
    for row in info.history {
        for (l, _) in row {
            if !labels.contains(&l.as_str()) {
                labels.push(l);
            }
        }
    }
    Plot::new("timings").height(180.0).legend(Legend::default()).allow_scroll(false).show(ui, |plot| {
        for label in labels {
            let pts: PlotPoints = info
                .history
                .iter()
                .enumerate()
                .filter_map(|(k, row)| row.iter().find(|(l, _)| l == label).map(|(_, v)| [k as f64, v / 1e6]))
                .collect();
            let line = Line::new(label.to_string(), pts);
            plot.line(if label == SUBSTEP { line.width(2.5) } else { line });
        }
    });
}

fn view_area(ui: &mut egui::Ui, s: &mut UiState, info: &Info<'_>, out: &mut Vec<Command>) -> Option<Drag> {
    let rect = ui.max_rect();
    let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
    response.context_menu(|ui| {
        view_items(ui, out);
        ui.separator();
        animation_items(ui, s, out);
    });
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            input::zoom(&mut s.camera, scroll / 50.0);
        }
    }
    // Pixels of the scene image, which covers the whole window.
    let ppp = ui.ctx().pixels_per_point();
    let to_px = |p: egui::Pos2| {
        let (w, h) = info.scene_size;
        ((p.x * ppp).clamp(0.0, w as f32 - 1.0), (p.y * ppp).clamp(0.0, h as f32 - 1.0))
    };
    let primary =
        response.dragged_by(egui::PointerButton::Primary) || response.drag_started_by(egui::PointerButton::Primary);
    if s.tool == Tool::Cursor {
        if response.drag_started_by(egui::PointerButton::Primary)
            && let Some(p) = response.interact_pointer_pos()
        {
            let (x, y) = to_px(p);
            return Some(Drag::Start { x, y });
        }
        if response.drag_stopped() {
            return Some(Drag::End);
        }
        if primary && let Some(p) = response.interact_pointer_pos() {
            let (x, y) = to_px(p);
            return Some(Drag::Move { x, y });
        }
    } else if primary {
        let d = response.drag_delta() * ppp;
        input::rotate(&mut s.camera, s.tool, d.x, d.y);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_backend_of_the_command_line_is_offered_in_the_picker() {
        use clap::ValueEnum;
        // A backend added to the CLI but not to the picker fails here.
        for b in Backend::value_variants() {
            assert!(Backend::ALL.contains(b), "{b:?} missing from the backend picker");
        }
        assert_eq!(Backend::ALL.len(), Backend::value_variants().len());
    }

    #[test]
    fn the_status_line_names_the_solvers_adapter_when_it_is_not_the_windows() {
        let history = VecDeque::new();
        let mut info = Info {
            backend: Backend::Vulkan,
            variant: None,
            api: Api::Gl,
            adapter: "llvmpipe (raw OpenGL)".into(),
            solver_adapter: Some("llvmpipe (Vulkan)".into()),
            substep: None,
            history: &history,
            frames: 0,
            scene_tex: None,
            scene_size: (1, 1),
        };
        assert_eq!(status_line(&info), "vulkan on llvmpipe (Vulkan) · drawn by Gl");
        info.solver_adapter = None;
        info.backend = Backend::Gl;
        assert_eq!(status_line(&info), "gl · Gl · llvmpipe (raw OpenGL)");
    }
}
