//! What the user can ask for, and how keys and mouse motion map onto it — plain logic,
//! tested without a window.

use clothlab::core::{OrbitCamera, RenderMode};
use glam::Vec3;

/// The mouse tool (the thesis's View menu).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tool {
    /// Grab and drag the cloth.
    Cursor,
    /// Turn about the x axis (drag up/down).
    RotateX,
    /// Turn about the y axis (drag left/right).
    RotateY,
    /// Roll about the line of sight (drag left/right).
    RotateZ,
    /// Turn freely (both directions).
    RotateFree,
}

/// A panel of the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Panel {
    /// Play/pause and substeps.
    Animation,
    /// The tool buttons.
    Toolbar,
    /// Wind on/off, strength, direction.
    Wind,
    /// Light position.
    Light,
    /// fps, time per substep, grid size.
    Status,
    /// Every simulation parameter.
    Parameters,
    /// The per-kernel timing chart.
    Timings,
    /// The floor, spheres and boxes.
    Scene,
}

impl Panel {
    /// Every panel, in menu order.
    pub const ALL: [Panel; 8] = [
        Panel::Animation,
        Panel::Toolbar,
        Panel::Wind,
        Panel::Light,
        Panel::Status,
        Panel::Parameters,
        Panel::Scene,
        Panel::Timings,
    ];

    /// Its menu name.
    pub fn name(self) -> &'static str {
        match self {
            Panel::Animation => "Animation bar",
            Panel::Toolbar => "Tool bar",
            Panel::Wind => "Wind panel",
            Panel::Light => "Light panel",
            Panel::Status => "Status bar",
            Panel::Parameters => "Parameters",
            Panel::Timings => "Kernel timings",
            Panel::Scene => "Scene panel",
        }
    }
}

/// Everything a menu item, a shortcut or a button can do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Back to the starting cloth (File → Reset, Ctrl+R).
    Reset,
    /// Save the 3-D view as a PNG (Ctrl+S).
    SaveImage,
    /// Quit (Ctrl+Q).
    Exit,
    /// Choose the mouse tool (C, X, Y, Z, F).
    Tool(Tool),
    /// Zoom in (I).
    ZoomIn,
    /// Zoom out (O).
    ZoomOut,
    /// Cloth drawn as points (P), lines (L) or triangles (T).
    Mode(RenderMode),
    /// Play / pause (Space).
    TogglePlay,
    /// Show or hide a panel.
    TogglePanel(Panel),
    /// Help → About.
    About,
}

/// The action of key `key` with Ctrl (or Cmd) held or not; `None` for other keys.
pub fn shortcut(key: egui::Key, ctrl: bool) -> Option<Action> {
    use egui::Key as K;
    Some(match (key, ctrl) {
        (K::R, true) => Action::Reset,
        (K::S, true) => Action::SaveImage,
        (K::Q, true) => Action::Exit,
        (K::C, false) => Action::Tool(Tool::Cursor),
        (K::X, false) => Action::Tool(Tool::RotateX),
        (K::Y, false) => Action::Tool(Tool::RotateY),
        (K::Z, false) => Action::Tool(Tool::RotateZ),
        (K::F, false) => Action::Tool(Tool::RotateFree),
        (K::I, false) => Action::ZoomIn,
        (K::O, false) => Action::ZoomOut,
        (K::P, false) => Action::Mode(RenderMode::Points),
        (K::L, false) => Action::Mode(RenderMode::Lines),
        (K::T, false) => Action::Mode(RenderMode::Triangles),
        (K::Space, false) => Action::TogglePlay,
        _ => return None,
    })
}

/// The keys [`shortcut`] knows, for polling.
pub const SHORTCUT_KEYS: [egui::Key; 14] = [
    egui::Key::R,
    egui::Key::S,
    egui::Key::Q,
    egui::Key::C,
    egui::Key::X,
    egui::Key::Y,
    egui::Key::Z,
    egui::Key::F,
    egui::Key::I,
    egui::Key::O,
    egui::Key::P,
    egui::Key::L,
    egui::Key::T,
    egui::Key::Space,
];

/// Radians of camera turn per pixel of drag.
pub const TURN_PER_PIXEL: f32 = 0.008;
/// Zoom factor per zoom step (I / O, one wheel notch).
pub const ZOOM_STEP: f32 = 1.15;

/// Turns `camera` for a drag of `(dx, dy)` pixels with rotate tool `tool` (the cursor tool
/// does not turn it).
pub fn rotate(camera: &mut OrbitCamera, tool: Tool, dx: f32, dy: f32) {
    let (dx, dy) = (dx * TURN_PER_PIXEL, dy * TURN_PER_PIXEL);
    match tool {
        Tool::Cursor => {}
        Tool::RotateX => camera.rotate(0.0, dy),
        Tool::RotateY => camera.rotate(-dx, 0.0),
        Tool::RotateZ => camera.roll_by(dx),
        Tool::RotateFree => camera.rotate(-dx, dy),
    }
}

/// Zooms `camera` for `notches` wheel notches (positive: in).
pub fn zoom(camera: &mut OrbitCamera, notches: f32) {
    if notches.is_finite() {
        camera.zoom(ZOOM_STEP.powf(-notches.clamp(-20.0, 20.0)));
    }
}

/// Where a grabbed particle that was at `grabbed` goes when the cursor is at pixel
/// `(x, y)` of a `width × height` view: onto the ray under the cursor, in the plane through
/// the particle facing the camera (the view plane). Never below the floor.
pub fn drag_target(
    camera: &OrbitCamera,
    grabbed: Vec3,
    x: f32,
    y: f32,
    width: u32,
    height: u32,
    floor: f32,
) -> [f32; 3] {
    let t = camera.drag_target(grabbed, x, y, width, height);
    if !t.is_finite() {
        return grabbed.to_array();
    }
    [t.x, t.y.max(floor), t.z]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thesis_shortcuts_map_to_their_actions() {
        assert_eq!(shortcut(egui::Key::R, true), Some(Action::Reset));
        assert_eq!(shortcut(egui::Key::S, true), Some(Action::SaveImage));
        assert_eq!(shortcut(egui::Key::Q, true), Some(Action::Exit));
        assert_eq!(shortcut(egui::Key::C, false), Some(Action::Tool(Tool::Cursor)));
        assert_eq!(shortcut(egui::Key::F, false), Some(Action::Tool(Tool::RotateFree)));
        assert_eq!(shortcut(egui::Key::I, false), Some(Action::ZoomIn));
        assert_eq!(shortcut(egui::Key::P, false), Some(Action::Mode(RenderMode::Points)));
        assert_eq!(shortcut(egui::Key::Space, false), Some(Action::TogglePlay));
        // R without Ctrl is not Reset; Ctrl+C is not the cursor tool (copy).
        assert_eq!(shortcut(egui::Key::R, false), None);
        assert_eq!(shortcut(egui::Key::C, true), None);
        assert_eq!(shortcut(egui::Key::A, false), None);
        // Every key listed for polling has an action with or without Ctrl.
        for k in SHORTCUT_KEYS {
            assert!(shortcut(k, false).is_some() || shortcut(k, true).is_some(), "{k:?}");
        }
    }

    #[test]
    fn rotate_tools_turn_only_their_axis() {
        let base = OrbitCamera::default();
        let mut c = base.clone();
        rotate(&mut c, Tool::RotateX, 50.0, 20.0);
        assert_eq!(c.yaw, base.yaw);
        assert!((c.pitch - base.pitch - 20.0 * TURN_PER_PIXEL).abs() < 1e-6);
        let mut c = base.clone();
        rotate(&mut c, Tool::RotateY, 50.0, 20.0);
        assert_eq!(c.pitch, base.pitch);
        assert!((c.yaw - (base.yaw - 50.0 * TURN_PER_PIXEL)).abs() < 1e-6);
        let mut c = base.clone();
        rotate(&mut c, Tool::RotateZ, 50.0, 20.0);
        assert_eq!((c.yaw, c.pitch), (base.yaw, base.pitch));
        assert!((c.roll - 50.0 * TURN_PER_PIXEL).abs() < 1e-6);
        let mut c = base.clone();
        rotate(&mut c, Tool::Cursor, 50.0, 20.0);
        assert_eq!(c, base, "the cursor tool drags the cloth, not the camera");
    }

    #[test]
    fn zoom_steps_multiply_the_distance() {
        let mut c = OrbitCamera::default();
        let d = c.distance;
        zoom(&mut c, 1.0);
        assert!((c.distance - d / ZOOM_STEP).abs() < 1e-5);
        zoom(&mut c, f32::NAN);
        assert!((c.distance - d / ZOOM_STEP).abs() < 1e-5, "NaN scroll ignored");
    }

    #[test]
    fn a_drag_moves_the_grabbed_particle_in_the_view_plane_under_the_cursor() {
        let cam = OrbitCamera::default();
        let p = Vec3::new(0.2, 1.2, 0.1);
        let [x, y] = cam.project(p, 800, 600).unwrap();
        // No motion: the target is the particle (f32 through two inversions: 1e-4 m).
        let t = Vec3::from(drag_target(&cam, p, x, y, 800, 600, 0.0));
        assert!((t - p).length() < 1e-4, "{t} vs {p}");
        // 40 px to the right: the target projects 40 px to the right, at the same depth.
        let t = Vec3::from(drag_target(&cam, p, x + 40.0, y, 800, 600, 0.0));
        let [tx, ty] = cam.project(t, 800, 600).unwrap();
        assert!((tx - x - 40.0).abs() < 0.05 && (ty - y).abs() < 0.05, "({tx}, {ty}) vs ({x}, {y})");
        let view_dir = (cam.target - cam.eye()).normalize();
        assert!((t - p).dot(view_dir).abs() < 1e-4, "stays in the plane facing the camera");
        // Far below: held at the floor.
        let t = drag_target(&cam, p, x, y + 5000.0, 800, 600, 0.0);
        assert!(t[1] >= 0.0);
    }
}
