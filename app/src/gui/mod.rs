//! The interactive app: the thesis's Qt program rebuilt in egui + winit, on wgpu or raw
//! Vulkan, with any solver.

mod gfx;
pub mod input;
mod sim;
mod ui;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clothlab::core::{OrbitCamera, RenderMode, SimParams, View};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

use crate::out::outln;
use clothlab::backend::{Api, Backend};
use gfx::{EguiFrame, Gfx, Shot};
use input::{Action, Panel, Tool};
use sim::Sim;

/// The frames the shown frame rate averages over.
const FPS_FRAMES: usize = 30;

/// How `clothlab run` starts.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Graphics API.
    pub api: Api,
    /// Solver.
    pub backend: Backend,
    /// Quit after this many frames (tests, screenshots).
    pub frames: Option<u64>,
    /// Save a picture of the window when quitting after `frames`.
    pub screenshot: Option<PathBuf>,
    /// Window size, pixels.
    pub size: (u32, u32),
    /// Drag the cloth by script (a test of picking and dragging).
    pub drag_test: bool,
    /// Switch to the other API halfway through `frames` (a test).
    pub switch_api: bool,
    /// Drop this file on the window at frame 3, as a user would (a test).
    pub drop_file: Option<PathBuf>,
    /// The scene and parameters to start with (`--scene`, `--n`, `--set`, `--integrator`).
    pub setup: clothlab::setup::Setup,
}

/// Everything the panels show and change.
pub struct UiState {
    /// Mouse tool.
    pub tool: Tool,
    /// Cloth drawing.
    pub mode: RenderMode,
    /// Simulation paused.
    pub paused: bool,
    /// Camera.
    pub camera: OrbitCamera,
    /// Light position, m.
    pub light: [f32; 3],
    /// Which panels show.
    pub panels: Vec<Panel>,
    /// Wind on.
    pub wind_on: bool,
    /// Wind speed, m/s.
    pub wind_speed: f32,
    /// Wind direction, degrees about +y (0 = +x).
    pub wind_azimuth: f32,
    /// Gusts: the speed varies by up to this fraction.
    pub gusts: f32,
    /// Grid size the slider holds (applied on release).
    pub grid_n: u32,
    /// Parameters being edited (applied when valid).
    pub params: SimParams,
    /// The scene's colliders and floor being edited (applied with the panel's Apply).
    pub scene: clothlab::core::Scene,
    /// The scene's title (the file's), or its file name.
    pub scene_title: String,
    /// The Open scene window is open.
    pub open_dialog: bool,
    /// The path typed into the Open scene window.
    pub open_path: String,
    /// The About window is open.
    pub about: bool,
    /// The last message for the status bar (errors, saved files).
    pub message: String,
    /// Frames per second over the last [`FPS_FRAMES`] frames (0 before the second).
    pub fps: f32,
}

/// A request from the UI that needs the app (solver, renderer, window).
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// A menu or shortcut action.
    Action(Action),
    /// Another solver, keeping the cloth.
    Backend(Backend),
    /// Another variant of the running GPU solver, keeping the cloth.
    Variant(clothlab::engine::Variant),
    /// Another grid size.
    Grid(u32),
    /// New parameters.
    Params(SimParams),
    /// New colliders and floor under the same cloth (the Scene panel's Apply).
    Scene(Box<clothlab::core::Scene>),
    /// Open a scene file (File → Open scene, or a file dropped on the window).
    OpenScene(PathBuf),
    /// Draw through the other API (the solver follows where it is a GPU solver).
    Api(Api),
}

struct Running {
    window: Arc<Window>,
    gfx: Gfx,
    sim: Sim,
    ui: UiState,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    /// When the last frames began, the newest last: the frame rate is the frames between
    /// the first and the last over the time between them (an average of the rates of
    /// single frames is not one: a frame that follows its predecessor at once would count
    /// as thousands of frames a second).
    frame_starts: std::collections::VecDeque<Instant>,
    drawn: u64,
    /// Grabbed particle and where it was when grabbed.
    dragging: Option<(u32, glam::Vec3)>,
    /// File → Exit was chosen.
    quit: bool,
    /// Where the scripted drag pressed.
    script_at: Option<[f32; 2]>,
}

struct App {
    opts: RunOptions,
    running: Option<Running>,
    error: Option<anyhow::Error>,
}

/// Runs the app until the window closes (or `frames` frames are drawn).
pub fn run(opts: RunOptions) -> Result<ExitCode> {
    if opts.screenshot.is_some() && opts.frames.is_none() {
        bail!("--screenshot needs --frames N (the picture is taken after N frames)");
    }
    if opts.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    let (w, h) = opts.size;
    if !(64..=8192).contains(&w) || !(64..=8192).contains(&h) {
        bail!("invalid window size {w}×{h}: each side must be in 64 ..= 8192");
    }
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        bail!(
            "no display to open a window on (DISPLAY and WAYLAND_DISPLAY are unset): for headless use, \
             `clothlab render` draws to a PNG and `clothlab sim` simulates"
        );
    }
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!("cannot open a window ({e}): for headless use, `clothlab render` draws to a PNG and `clothlab sim` simulates")
    })?;
    let mut app = App { opts, running: None, error: None };
    event_loop.run_app(&mut app).context("the window's event loop failed")?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(ExitCode::SUCCESS),
    }
}

impl UiState {
    /// Shows a new scene: its cloth size, parameters, colliders, the file's camera and
    /// light (or the defaults), and its wind in the wind panel (steady: no gusts).
    fn take_setup(&mut self, setup: &clothlab::setup::Setup, title: String) {
        self.grid_n = setup.scene.cloth.n;
        self.params = setup.params.clone();
        self.scene = setup.scene.clone();
        self.scene_title = title;
        self.camera = setup.camera.clone().unwrap_or_default();
        self.light = setup.light.unwrap_or([2.0, 5.5, 3.0]);
        let [wx, _, wz] = setup.params.wind;
        let speed = (wx * wx + wz * wz).sqrt();
        self.wind_on = speed > 0.0;
        if speed > 0.0 {
            self.wind_speed = speed;
            self.wind_azimuth = wz.atan2(wx).to_degrees().rem_euclid(360.0);
            self.gusts = 0.0;
        }
    }
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<Running> {
        let (w, h) = self.opts.size;
        let attrs = Window::default_attributes()
            .with_title("clothlab")
            .with_inner_size(PhysicalSize::new(w, h))
            .with_min_inner_size(PhysicalSize::new(64, 64));
        let window = Arc::new(event_loop.create_window(attrs).context("cannot open a window")?);
        let setup = self.opts.setup.clone();
        let params = setup.params.clone();
        let gfx = Gfx::new(self.opts.api, &window, &setup.scene, &params)?;
        let sim = Sim::new(self.opts.backend, setup.scene.clone(), params.clone(), &gfx.shared())?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        log::info!("window on {}", gfx.adapter());
        let mut ui = UiState {
            tool: Tool::RotateFree,
            mode: RenderMode::Triangles,
            paused: false,
            camera: OrbitCamera::default(),
            light: [2.0, 5.5, 3.0],
            panels: Panel::ALL.to_vec(),
            wind_on: false,
            wind_speed: 3.0,
            wind_azimuth: 200.0,
            gusts: 0.3,
            grid_n: setup.scene.cloth.n,
            params,
            scene: setup.scene.clone(),
            scene_title: String::new(),
            open_dialog: false,
            open_path: String::new(),
            about: false,
            message: String::new(),
            fps: 0.0,
        };
        ui.take_setup(&setup, setup.title.clone().unwrap_or_else(|| "default scene".into()));
        Ok(Running {
            window,
            gfx,
            sim,
            ui,
            egui_ctx,
            egui_state,
            frame_starts: std::collections::VecDeque::with_capacity(FPS_FRAMES + 1),
            drawn: 0,
            dragging: None,
            quit: false,
            script_at: None,
        })
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(r) => {
                r.window.request_redraw();
                self.running = Some(r);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(r) = self.running.as_mut() else { return };
        let _ = r.egui_state.on_window_event(&r.window, &event);
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => r.gfx.resize(size.width, size.height),
            WindowEvent::DroppedFile(path) => r.command(Command::OpenScene(path)),
            WindowEvent::RedrawRequested => {
                let limit = self.opts.frames;
                let shot_path = self.opts.screenshot.clone();
                if self.opts.drag_test
                    && let Err(e) = r.scripted_drag(limit)
                {
                    self.fail(event_loop, e);
                    return;
                }
                if let Some(path) = self.opts.drop_file.clone().filter(|_| r.drawn == 3) {
                    if let Err(e) = r.command(Command::OpenScene(path)) {
                        self.fail(event_loop, e);
                        return;
                    }
                    outln!("dropped: {}", r.ui.message).ok();
                }
                if self.opts.switch_api && limit.is_some_and(|l| r.drawn == l / 2) {
                    let other = r.gfx.api().next();
                    if let Err(e) = r.command(Command::Api(other)) {
                        self.fail(event_loop, e);
                        return;
                    }
                    outln!("switched to {other:?}, solver {}", r.sim.backend.name()).ok();
                }
                match r.frame(limit, shot_path.as_deref()) {
                    Ok(true) => {
                        // What the status bar showed last, and the wall clock beside it.
                        if let (Some(t), Some(wall)) = (r.sim.substep_time(), r.sim.wall_substep_ns) {
                            outln!(
                                "status: {} | wall {:.3} ms per substep | {:.1} fps at {} substeps a frame",
                                ui::substep_label(&t),
                                wall / 1e6,
                                r.ui.fps,
                                r.sim.solver.get_ref().params().substeps
                            )
                            .ok();
                        }
                        event_loop.exit();
                        Ok(())
                    }
                    Ok(false) => {
                        r.window.request_redraw();
                        Ok(())
                    }
                    Err(e) => Err(e),
                }
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn exiting(&mut self, _: &ActiveEventLoop) {
        // Solver and renderers go before the window they draw into.
        self.running = None;
    }
}

impl Running {
    fn view(&self) -> View {
        View { camera: self.ui.camera.clone(), light: self.ui.light, mode: self.ui.mode }
    }

    /// One frame: simulate, lay out the panels, act on what they asked, draw. Returns
    /// whether to quit.
    fn frame(&mut self, limit: Option<u64>, shot_path: Option<&std::path::Path>) -> Result<bool> {
        self.frame_starts.push_back(Instant::now());
        if self.frame_starts.len() > FPS_FRAMES + 1 {
            self.frame_starts.pop_front();
        }
        self.ui.fps = match (self.frame_starts.front(), self.frame_starts.back()) {
            (Some(first), Some(last)) if last > first => {
                (self.frame_starts.len() - 1) as f32 / (*last - *first).as_secs_f32()
            }
            _ => 0.0,
        };
        if !self.ui.paused {
            self.apply_wind();
            self.sim.step()?;
        }
        let raw = self.egui_state.take_egui_input(&self.window);
        let scene_tex = self.gfx.scene_texture();
        let mut commands = Vec::new();
        let mut drag = None;
        let (sw, sh) = self.gfx.scene_size();
        let out = self.egui_ctx.run_ui(raw, |root| {
            let info = ui::Info {
                backend: self.sim.backend,
                variant: self.sim.solver.variant().zip(self.sim.solver.caps().map(|(c, _)| c)),
                api: self.gfx.api(),
                adapter: self.gfx.adapter(),
                solver_adapter: (self.sim.backend.api() != Some(self.gfx.api())).then(|| self.sim.solver.adapter()),
                substep: self.sim.substep_time(),
                history: &self.sim.history,
                frames: self.sim.frames,
                scene_tex,
                scene_size: (sw, sh),
            };
            let view = ui::draw(root, &mut self.ui, &info, &mut commands);
            drag = view;
        });
        self.egui_state.handle_platform_output(&self.window, out.platform_output);
        for c in commands {
            self.command(c)?;
        }
        if let Some(d) = drag {
            self.drag(d)?;
        }
        let primitives = self.egui_ctx.tessellate(out.shapes, out.pixels_per_point);
        let last = limit.is_some_and(|l| self.drawn + 1 >= l);
        let capture = last && shot_path.is_some();
        let view = self.view();
        let frame = EguiFrame {
            primitives: &primitives,
            textures: &out.textures_delta,
            pixels_per_point: out.pixels_per_point,
        };
        let shot = self.gfx.draw(&mut self.sim.solver, &view, frame, capture)?;
        self.drawn += 1;
        if let (true, Some(path)) = (capture, shot_path) {
            let shot = shot.context("the last frame was not drawn (window minimised?): no screenshot")?;
            save_png(path, &shot)?;
        }
        Ok(last || self.quit)
    }

    /// Wind from the panel, with gusts: a slow sine of the frame count.
    fn apply_wind(&mut self) {
        let u = &self.ui;
        let speed = if u.wind_on {
            u.wind_speed
                * (1.0 + u.gusts * (self.sim.frames as f32 * 0.07).sin() * (self.sim.frames as f32 * 0.013).cos())
        } else {
            0.0
        };
        let a = u.wind_azimuth.to_radians();
        let wind = [speed * a.cos(), 0.0, speed * a.sin()];
        let solver = self.sim.solver.get();
        if solver.params().wind != wind {
            let p = SimParams { wind, ..solver.params().clone() };
            if let Err(e) = solver.set_params(p) {
                self.ui.message = format!("wind refused: {e}");
            }
        }
    }

    fn command(&mut self, c: Command) -> Result<()> {
        match c {
            Command::Action(a) => self.action(a)?,
            Command::Backend(b) => match self.sim.switch(b, &self.gfx.shared()) {
                Ok(()) => self.ui.message = format!("switched to {}", b.name()),
                Err(e) => self.ui.message = format!("cannot switch to {}: {e:#}", b.name()),
            },
            Command::Variant(v) => match self.sim.set_variant(v, &self.gfx.shared()) {
                Ok(()) => self.ui.message = format!("variant {}", v.label()),
                Err(e) => self.ui.message = format!("variant refused: {e:#}"),
            },
            Command::Grid(n) => {
                // A grid the parameters cannot run (physical stiffness needing more
                // substeps at this n) is refused, the old cloth kept.
                if let Err(e) = self.sim.regrid(n, &self.gfx.shared()) {
                    self.ui.message = format!("grid {n}×{n} refused: {e:#}");
                    self.ui.grid_n = self.sim.solver.get_ref().scene().cloth.n;
                    return Ok(());
                }
                let scene = self.sim.solver.get_ref().scene().clone();
                // The parameters as the new grid took them (a thickness brought within
                // its bound).
                self.ui.params = self.sim.solver.get_ref().params().clone();
                self.gfx.rebuild(&scene, &self.ui.params)?;
                // The Scene panel edits colliders under this cloth from now on.
                self.ui.scene = scene;
                self.dragging = None;
                self.ui.message = format!("new cloth: {n}×{n}");
            }
            Command::Api(api) => self.switch_api(api)?,
            Command::Scene(scene) => match self.sim.set_scene(*scene, &self.gfx.shared()) {
                Ok(()) => {
                    let scene = self.sim.solver.get_ref().scene().clone();
                    self.gfx.rebuild(&scene, &self.ui.params)?;
                    self.ui.message = format!(
                        "scene: {} spheres, {} boxes, {} rods, {} bodies, {}",
                        scene.spheres.len(),
                        scene.boxes.len(),
                        scene.rods.len(),
                        scene.bodies.len(),
                        scene.floor_y.map_or("no floor".into(), |y| format!("floor at {y} m"))
                    );
                }
                Err(e) => {
                    self.ui.message = format!("scene refused: {e:#}");
                    self.ui.scene = self.sim.solver.get_ref().scene().clone();
                }
            },
            Command::OpenScene(path) => self.open_scene(&path)?,
            Command::Params(p) => match self.sim.solver.get().set_params(p.clone()) {
                Ok(()) => {}
                Err(e) => {
                    self.ui.message = format!("parameters refused: {e}");
                    // The panels show what runs.
                    self.ui.params = self.sim.solver.get_ref().params().clone();
                }
            },
        }
        Ok(())
    }

    /// Opens a scene file: a new cloth, colliders, parameters and view on the same
    /// backend. A file that is refused (unreadable, malformed, a refused value, a cloth the
    /// app does not take) changes nothing and says why in the status bar.
    fn open_scene(&mut self, path: &std::path::Path) -> Result<()> {
        let file = match clothlab::core::SceneFile::load(path) {
            Ok(f) => f,
            Err(e) => {
                self.ui.message = e.to_string();
                return Ok(());
            }
        };
        let n = file.scene.cloth.n;
        if !file.scene.cloth.is_mesh() && !(10..=1024).contains(&n) {
            self.ui.message = format!("{}: the app takes 10 ..= 1024 particles per side, not {n}", path.display());
            return Ok(());
        }
        let mut setup = clothlab::setup::Setup::from_file(file);
        // A file of several worlds shows its first (its values of the per-world lists).
        match setup.params_of_world(0) {
            Ok(p) => setup.params = p,
            Err(e) => {
                self.ui.message = format!("{}: {e:#}", path.display());
                return Ok(());
            }
        }
        let sim = match Sim::new(self.sim.backend, setup.scene.clone(), setup.params.clone(), &self.gfx.shared()) {
            Ok(sim) => sim,
            Err(e) => {
                self.ui.message = format!("{}: {e:#}", path.display());
                return Ok(());
            }
        };
        self.sim = sim;
        self.gfx.rebuild(&setup.scene, &setup.params)?;
        self.dragging = None;
        let name = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
        let title = setup.title.clone().unwrap_or(name);
        self.ui.take_setup(&setup, title.clone());
        self.ui.open_dialog = false;
        self.ui.message = format!("opened {title} ({})", path.display());
        Ok(())
    }

    /// Draws through `api` from now on. The window's surface belongs to one API at a time,
    /// so the cloth is parked on the CPU solver, the old graphics (and any device holding
    /// the surface) dropped, the new ones made, and the solver moved onto them; egui starts
    /// afresh so that its textures reach the new renderer.
    fn switch_api(&mut self, api: Api) -> Result<()> {
        if api == self.gfx.api() {
            return Ok(());
        }
        let backend = self.sim.backend;
        let variant = self.sim.solver.variant();
        self.sim.switch(Backend::Cpu, &clothlab::backend::Shared::None)?;
        let scene = self.sim.solver.get_ref().scene().clone();
        let params = self.sim.solver.get_ref().params().clone();
        // The old surface must be gone before the new one is made.
        let placeholder = Gfx::new_placeholder();
        drop(std::mem::replace(&mut self.gfx, placeholder));
        self.gfx = Gfx::new(api, &self.window, &scene, &params)?;
        // A GPU backend moves to the same recipe on the new API (its buffers drawn with
        // no copy); a CPU backend stays.
        let target = match backend.preset() {
            Some("naive") => api.naive(),
            Some(_) => api.optimized(),
            None => backend,
        };
        self.sim.switch(target, &self.gfx.shared())?;
        // The same variant on the other API, where it has every switch of it.
        if let Some(v) = variant.filter(|v| Some(*v) != self.sim.solver.variant())
            && let Err(e) = self.sim.set_variant(v, &self.gfx.shared())
        {
            self.ui.message = format!("variant {} not kept: {e:#}", v.label());
        }
        self.egui_ctx = egui::Context::default();
        self.egui_state = egui_winit::State::new(
            self.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &self.window,
            Some(self.window.scale_factor() as f32),
            None,
            None,
        );
        self.ui.message = format!("drawing through {api:?}, solver {}", target.name());
        Ok(())
    }

    fn action(&mut self, a: Action) -> Result<()> {
        match a {
            Action::Reset => {
                let n = self.sim.solver.get_ref().scene().cloth.n;
                self.sim.regrid(n, &self.gfx.shared())?;
                self.dragging = None;
                self.ui.message = "reset".into();
            }
            Action::SaveImage => {
                let view = self.view();
                let shot = self.gfx.scene_image(&mut self.sim.solver, &view)?;
                let secs = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map(|d| d.as_secs())
                    .unwrap_or_default();
                let path = PathBuf::from(format!("clothlab-{secs}.png"));
                match save_png(&path, &shot) {
                    Ok(()) => self.ui.message = format!("saved {}", path.display()),
                    Err(e) => self.ui.message = format!("cannot save: {e:#}"),
                }
            }
            Action::Exit => self.window_close(),
            Action::Tool(t) => self.ui.tool = t,
            Action::ZoomIn => input::zoom(&mut self.ui.camera, 1.0),
            Action::ZoomOut => input::zoom(&mut self.ui.camera, -1.0),
            Action::Mode(m) => self.ui.mode = m,
            Action::TogglePlay => self.ui.paused = !self.ui.paused,
            Action::TogglePanel(p) => {
                if let Some(k) = self.ui.panels.iter().position(|q| *q == p) {
                    self.ui.panels.remove(k);
                } else {
                    self.ui.panels.push(p);
                }
            }
            Action::About => self.ui.about = true,
        }
        Ok(())
    }

    fn window_close(&mut self) {
        self.quit = true;
    }

    /// The `--drag-test` script: at frame 5 press on the particle a third of the way down
    /// the middle of the cloth, then move up 4 px a frame; report at the last frame.
    fn scripted_drag(&mut self, limit: Option<u64>) -> Result<()> {
        let (w, h) = self.gfx.scene_size();
        if self.drawn == 5 {
            self.ui.tool = Tool::Cursor;
            // A grid's particle a third down its middle column; a mesh's a third down its list.
            let cloth = &self.sim.solver.get_ref().scene().cloth;
            let (n, mesh) = (cloth.n as usize, cloth.is_mesh());
            let pos = self.sim.solver.get().state()?.pos;
            let p = pos[if mesh { pos.len() / 3 } else { (n / 3) * n + n / 2 }];
            let [x, y] =
                self.ui.camera.project(glam::Vec3::new(p[0], p[1], p[2]), w, h).context("cloth behind the camera")?;
            self.drag(ui::Drag::Start { x, y })?;
            let (id, at) = self.dragging.context("drag test: nothing grabbed under the cloth's middle")?;
            outln!("drag: grabbed particle {id} at y={:.4} (pixel {x:.0}, {y:.0})", at.y).ok();
            self.script_at = Some([x, y]);
        } else if let Some([x, y]) = self.script_at {
            let k = self.drawn.saturating_sub(5) as f32;
            self.drag(ui::Drag::Move { x, y: (y - 4.0 * k).max(0.0) })?;
            if limit.is_some_and(|l| self.drawn + 1 >= l)
                && let Some((id, _)) = self.dragging
            {
                let now = self.sim.solver.get().state()?.pos[id as usize];
                let target = self.sim.grab.map(|g| g.target[1]).unwrap_or(f32::NAN);
                outln!("drag: particle {id} now at y={:.4} (target y={target:.4})", now[1]).ok();
            }
        }
        Ok(())
    }

    /// Grabs, drags or lets go of the cloth with the cursor tool.
    fn drag(&mut self, d: ui::Drag) -> Result<()> {
        let view = self.view();
        let (w, h) = self.gfx.scene_size();
        match d {
            ui::Drag::Start { x, y } => {
                if let Some(id) = self.gfx.pick(&mut self.sim.solver, &view, x as u32, y as u32)? {
                    let state = self.sim.solver.get().state()?;
                    let p = state.pos[id as usize];
                    let at = glam::Vec3::new(p[0], p[1], p[2]);
                    self.dragging = Some((id, at));
                    self.sim.grab = Some(clothlab::core::Grab { particle: id, target: [p[0], p[1], p[2]] });
                    self.ui.message = format!("grabbed particle {id}");
                }
            }
            ui::Drag::Move { x, y } => {
                if let Some((id, at)) = self.dragging {
                    let floor = self.sim.solver.get_ref().scene().floor_height();
                    let target = input::drag_target(&view.camera, at, x, y, w, h, floor);
                    self.sim.grab = Some(clothlab::core::Grab { particle: id, target });
                }
            }
            ui::Drag::End => {
                self.dragging = None;
                self.sim.grab = None;
            }
        }
        Ok(())
    }
}

fn save_png(path: &std::path::Path, shot: &Shot) -> Result<()> {
    clothlab::files::write_png(path, &shot.rgba, shot.width, shot.height)
}
