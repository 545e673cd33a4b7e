//! clothlab-tests: tests that span backends (GPU vs CPU, golden images, soak runs).
//!
//! GPU tests run wherever an adapter exists (Mesa's lavapipe counts). Without one they
//! print why and pass, unless `CLOTHLAB_REQUIRE_GPU=1` (CI sets it), which makes a
//! missing adapter a failure. The comparisons themselves live in
//! `clothlab_cpu::validate`, shared with `clothlab validate`.
//!
//! How it fits: it depends on every other crate and is depended on by none; this library
//! holds what the test files share (solver factories that skip or fail without an
//! adapter, the backends to loop over, the test view). Where each test lives and
//! what it checks: docs/testing.md.
#![forbid(unsafe_code)]

use clothlab_core::{OrbitCamera, RenderMode, Scene, SimParams, Solver, View};
use clothlab_cpu::validate::Check;
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::{Variant, VariantSpec};
use clothlab_gl::gl_solver;
use clothlab_vulkan::vulkan_solver;
use clothlab_wgpu::{SolverOptions, wgpu_solver};

/// The view the picture tests draw: the default camera, the light up and to the side.
pub fn test_view(mode: RenderMode) -> View {
    View { camera: OrbitCamera::default(), light: [2.0, 5.5, 3.0], mode }
}

/// Whether GPU tests must fail rather than skip without an adapter.
pub fn gpu_required() -> bool {
    std::env::var("CLOTHLAB_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// `Some(value)`, or `None` with the reason printed when there is no GPU adapter (or no
/// Vulkan loader) and `CLOTHLAB_REQUIRE_GPU` is not set; any other error panics.
pub fn or_skip<T, E: std::fmt::Display>(r: Result<T, E>, what: &str) -> Option<T> {
    match r {
        Ok(v) => Some(v),
        Err(e) => {
            let msg = e.to_string();
            if !gpu_required() && (msg.contains("no GPU adapter") || msg.contains("no Vulkan loader")) {
                eprintln!("skipped: {msg}");
                None
            } else {
                panic!("{what}: {msg}")
            }
        }
    }
}

/// An adapter and a grid with everything (`Caps` all true): to resolve a variant spec
/// without a device.
pub const EVERY_CAP: clothlab_engine::recipe::Caps = clothlab_engine::recipe::Caps {
    float_atomics: true,
    immediates: true,
    table_image: true,
    subgroups: true,
    grid: true,
    tile: true,
    sdf_image: true,
    cpu: true,
};

/// The flavors of `kernels` one switch away from the plain one: every home of the step
/// constants with the other switches off, and each other switch alone with the uniform
/// constants (`table_image` counts as off where `base_image`: the table test's base).
///
/// What wgpu's rows of the every-flavor tests check. wgpu and raw Vulkan compile the
/// same WGSL through the same naga to SPIR-V for the same driver; what wgpu adds is its
/// binding model and its bounds checks, which each switch's value on each kernel shows.
/// The switches' combinations are checked on raw Vulkan (under the validation layer) and
/// on GL. Each flavor is a pipeline for llvmpipe to compile (0.5–1 s apiece: on a cold
/// shader cache most of these tests' time): the subset took wgpu's every-flavor row from
/// 85 to 48 s, cold and alone on the 2-vCPU dev VM.
pub fn one_switch_at_a_time(
    kernels: Vec<clothlab_engine::kernels::KernelRef>,
    base_image: bool,
) -> Vec<clothlab_engine::kernels::KernelRef> {
    use clothlab_engine::kernels::ConstantsHome;
    kernels
        .into_iter()
        .filter(|k| {
            let f = k.flavor;
            let on = [f.table_image && !base_image, f.float_atomics, f.colliders_uniform, f.shuffle, f.sdf_image]
                .into_iter()
                .filter(|&b| b)
                .count();
            on == 0 || (on == 1 && f.constants == ConstantsHome::Uniform)
        })
        .collect()
}

/// The GPU APIs the cross-API tests run on, listed once: a test loops over
/// [`Api::ALL`] (GL included unless the test says why not) and asks each for a solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Api {
    /// wgpu on its primary backend (Vulkan here).
    Wgpu,
    /// Raw Vulkan through ash.
    Vulkan,
    /// Raw OpenGL 4.5 through glow.
    Gl,
}

impl std::fmt::Display for Api {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

impl Api {
    /// Every API, in the order the tests report them.
    pub const ALL: [Api; 3] = [Api::Wgpu, Api::Vulkan, Api::Gl];

    /// Its name in test labels and backend names (`wgpu`, `vulkan`, `gl`).
    pub fn name(self) -> &'static str {
        match self {
            Api::Wgpu => "wgpu",
            Api::Vulkan => "vulkan",
            Api::Gl => "gl",
        }
    }

    /// A fresh batch of `worlds` (each world's parameters) of `spec` on this API
    /// (`GpuSolver::new_worlds`), what it refused, or `None` where there is no adapter and
    /// none is required ([`or_skip`]). Vulkan runs under the validation layer.
    pub fn batch(
        self,
        spec: impl Into<VariantSpec>,
        sc: &Scene,
        worlds: Vec<SimParams>,
    ) -> Option<Result<Box<dyn AnyGpuBatch>, clothlab_core::SolverError>> {
        use clothlab_engine::GpuSolver;
        let (spec, sc, o) = (spec.into(), sc.clone(), SolverOptions::default());
        Some(match self {
            Api::Wgpu => GpuSolver::new_worlds(or_skip(clothlab_wgpu::WgpuEngine::new(), "wgpu")?, spec, sc, worlds, o)
                .map(|s| Box::new(s) as _),
            Api::Vulkan => {
                GpuSolver::new_worlds(or_skip(clothlab_vulkan::VulkanEngine::new(true), "vulkan")?, spec, sc, worlds, o)
                    .map(|s| Box::new(s) as _)
            }
            Api::Gl => GpuSolver::new_worlds(or_skip(clothlab_gl::GlEngine::new(), "gl")?, spec, sc, worlds, o)
                .map(|s| Box::new(s) as _),
        })
    }

    /// A fresh solver of `spec` on this API, or `None` (the reason printed) where there
    /// is no adapter and none is required ([`or_skip`]). Vulkan runs under the Khronos
    /// validation layer: a message fails the next step, or [`assert_api_clean`].
    pub fn solver(self, spec: impl Into<VariantSpec>, sc: &Scene, params: &SimParams) -> Option<Box<dyn AnyGpuSolver>> {
        let (spec, sc, params, o) = (spec.into(), sc.clone(), params.clone(), SolverOptions::default());
        match self {
            Api::Wgpu => or_skip(wgpu_solver(spec, sc, params, o), "wgpu").map(|s| Box::new(s) as _),
            Api::Vulkan => or_skip(vulkan_solver(spec, sc, params, true, o), "vulkan").map(|s| Box::new(s) as _),
            Api::Gl => or_skip(gl_solver(spec, sc, params, o), "gl").map(|s| Box::new(s) as _),
        }
    }
}

/// The API whose naive recipe the physics tests run. The naive recipe is the same WGSL
/// kernels on every API (each API's flavors are checked against their twins, and its naive
/// rollouts against the CPU, in api_vs_cpu.rs); what a physics test adds is the recipe's
/// physics, which one API shows as well as three. Raw Vulkan, under the validation layer,
/// also checks the recipe's barriers.
pub const NAIVE_ON: Api = Api::Vulkan;

/// The API whose optimized recipe the physics tests run. On llvmpipe the optimized recipes
/// compute the CPU solver's bits on every API: every scene file's recipe (its integrator,
/// colliders, motions, pins, friction, self-collision, meshes) in scenes.rs, every kernel
/// flavor in api_vs_cpu.rs, every integrator in integrators.rs, each feature's recipe in
/// its own "follows the CPU" test. So a physics test's bound, met by the CPU solver, holds
/// on each API's optimized recipe alike, and one API runs it: wgpu, the app's.
pub const OPTIMIZED_ON: Api = Api::Wgpu;

/// The physics tests' backends, by name: the two CPU solvers, the naive recipe on
/// [`NAIVE_ON`] and the optimized one on [`OPTIMIZED_ON`].
pub fn physics_backend(name: &str) -> bool {
    PHYSICS_BACKENDS.contains(&name)
}

/// The physics tests' backends by name, in the order the rows run: the two CPU solvers,
/// the naive recipe on [`NAIVE_ON`], the optimized one on [`OPTIMIZED_ON`]
/// ([`physics_backend`] accepts exactly these).
pub const PHYSICS_BACKENDS: [&str; 4] = ["cpu", "cpu-par", "vulkan naive", "wgpu optimized"];

/// The solver of one of [`PHYSICS_BACKENDS`] (or any name [`backends`] builds) on `scene`,
/// or `None` where it is a GPU one and there is no adapter and none is required
/// ([`or_skip`]): what a test row of [`per_backend!`] runs.
pub fn backend(name: &str, scene: &Scene, params: &SimParams) -> Option<Box<dyn Solver>> {
    let mut all = backends(scene, params, |b| b == name);
    assert!(all.len() <= 1, "{name}: {} backends", all.len());
    let s = all.pop();
    assert!(s.is_some() || !gpu_required(), "{name}: no such backend");
    s.map(|(_, s)| s)
}

/// One `#[test]` per physics backend, so that a failing backend names itself
/// (`name::vulkan_naive`) and the others still run: `per_backend!(name)` makes a module
/// `name` whose rows call the function `name(backend)` beside it with each name of
/// [`PHYSICS_BACKENDS`] (which builds its solver with [`backend`]).
#[macro_export]
macro_rules! per_backend {
    ($($name:ident),* $(,)?) => {$(
        mod $name {
            #[test]
            fn cpu() {
                super::$name("cpu")
            }
            #[test]
            fn cpu_par() {
                super::$name("cpu-par")
            }
            #[test]
            fn vulkan_naive() {
                super::$name("vulkan naive")
            }
            #[test]
            fn wgpu_optimized() {
                super::$name("wgpu optimized")
            }
        }
    )*};
}

/// One `#[test]` per GPU API ([`Api::ALL`]), so that a failing API names itself
/// (`name::gl`) and the others still run: `per_api!(name)` makes a module `name` whose
/// rows call the function `name(api)` beside it.
#[macro_export]
macro_rules! per_api {
    ($($name:ident),* $(,)?) => {$(
        mod $name {
            #[test]
            fn wgpu() {
                super::$name($crate::Api::Wgpu)
            }
            #[test]
            fn vulkan() {
                super::$name($crate::Api::Vulkan)
            }
            #[test]
            fn gl() {
                super::$name($crate::Api::Gl)
            }
        }
    )*};
}

/// The backends whose names `keep` accepts (`cpu`, `cpu-par`, `vulkan naive`,
/// `wgpu optimized`, `vulkan optimized`, `gl optimized`); the others are not built. A
/// test across the APIs keeps every optimized recipe; a physics test, [`physics_backend`].
pub fn backends(scene: &Scene, params: &SimParams, keep: impl Fn(&str) -> bool) -> Vec<(String, Box<dyn Solver>)> {
    let mut out: Vec<(String, Box<dyn Solver>)> = Vec::new();
    for exec in [Exec::Serial, Exec::Parallel] {
        let name = if exec == Exec::Serial { "cpu" } else { "cpu-par" };
        if keep(name) {
            let s = CpuSolver::new(exec, scene.clone(), params.clone()).expect("a CPU solver of a checked scene");
            out.push((name.to_owned(), Box::new(s)));
        }
    }
    let recipes = std::iter::once((NAIVE_ON, Variant::NAIVE)).chain(Api::ALL.map(|api| (api, Variant::OPTIMIZED)));
    for (api, v) in recipes {
        let name = format!("{} {}", api.name(), v.label());
        if keep(&name)
            && let Some(s) = api.solver(v, scene, params)
        {
            out.push((name, s.into_solver()));
        }
    }
    out
}

/// Steps `v` three frames and checks its last substep's GPU statistics against the CPU
/// twin's: the largest strain within 1e-6 (a max of the same f32 values: a length and a
/// division, within 4 ulps of ~1.1) and the kinetic energy within `energy_bound` relative
/// (a sum in another order than the twin's f64 sum; the callers give the bound's reason).
pub fn assert_stats_match_twin<E: clothlab_engine::Engine>(v: &mut clothlab_engine::GpuSolver<E>, energy_bound: f32) {
    for _ in 0..3 {
        v.step_frame().unwrap();
    }
    let stats_gpu = v.substep_stats();
    let substeps = v.params().substeps as usize;
    assert_eq!(stats_gpu.len(), substeps, "one entry per substep");
    // Every substep wrote its own entry (zeroed at the frame's start): the cloth is
    // falling, so each has energy.
    assert!(stats_gpu.iter().all(|s| s.kinetic_energy > 0.0 && s.max_strain.is_finite()), "{stats_gpu:?}");
    let state = v.state().unwrap();
    let (_, topo) = clothlab_core::build(v.scene(), v.params()).unwrap();
    let sp = clothlab_core::step_params::StepParams::new(v.params(), v.scene(), None);
    let want = clothlab_cpu::substep_stats(&sp, &topo.slots, &state.pos, &state.vel);
    let got = stats_gpu[substeps - 1];
    let strain_err = (got.max_strain - want.max_strain).abs();
    let energy_err = ((got.kinetic_energy - want.kinetic_energy) / want.kinetic_energy).abs();
    println!(
        "{}: strain {} vs {} ({strain_err:.1e}), energy {} vs {} ({energy_err:.1e} rel)",
        v.name(),
        got.max_strain,
        want.max_strain,
        got.kinetic_energy,
        want.kinetic_energy
    );
    assert!(want.kinetic_energy > 0.0 && want.max_strain > 0.0, "{want:?}");
    assert!(strain_err <= 1e-6, "max strain {got:?} vs {want:?}");
    assert!(energy_err <= energy_bound, "kinetic energy {got:?} vs {want:?}");
}

/// Runs each of `kernels` on `runner` against its CPU twin (a disturbed cloth of n × n,
/// see `clothlab_engine::validate::validate_kernels`) and fails on the first buffer over
/// its kernel's bound; checks that every kernel with a bound was compared (one check per
/// compared buffer) and that at least `min_bounded` were — so that a recipe or flavor
/// list that lost kernels fails here instead of passing on fewer.
pub fn assert_kernels_match_twins(
    runner: &mut dyn clothlab_engine::validate::KernelRunner,
    kernels: &[clothlab_engine::KernelRef],
    n: u32,
    seed: u64,
    min_bounded: usize,
    label: &str,
) {
    use clothlab_engine::kernels::Check as KernelCheck;
    let checks = clothlab_engine::validate::validate_kernels(runner, kernels, n, seed).unwrap();
    // Those with a bound that run on a grid (a mesh's XPBD pass does not).
    let on_grid = |k: &&clothlab_engine::KernelRef| k.def.cloths != clothlab_engine::kernels::Cloths::Mesh;
    let bounded = kernels.iter().filter(on_grid).filter(|k| matches!(k.def.check, KernelCheck::Bound { .. })).count();
    let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
    assert!(bounded >= min_bounded, "{label}: only {bounded} kernels with a bound: {names:?}");
    assert_eq!(checks.len(), clothlab_engine::validate::COMPARED_BUFFERS * bounded, "{label}");
    assert_checks(label, &checks);
}

/// Prints every check and fails on the first one over its bound.
pub fn assert_checks(label: &str, checks: &[Check]) {
    for c in checks {
        println!(
            "{label:10} {:24} {:7} max {:.2e}  rms {:.2e}  error {:.2e}  bound {:.0e}",
            c.what, c.buffer, c.max_abs, c.rms, c.error, c.bound
        );
    }
    for c in checks {
        assert!(
            c.passed(),
            "{label}: {} {} differs from the CPU by {:e} (bound {:e})",
            c.what,
            c.buffer,
            c.error,
            c.bound
        );
    }
}

/// Mean absolute difference per channel (0–255) of two RGBA8 images and the fraction of
/// pixels whose largest channel difference exceeds 48: the golden-image measure.
pub fn image_diff(a: &[u8], b: &[u8]) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let sum: u64 = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y) as u64).sum();
    let px = a.len() / 4;
    let bad =
        a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 48)).count();
    (sum as f64 / a.len() as f64, bad as f64 / px as f64)
}

/// A scene of nothing but the mesh `scenes/meshes/NAME` placed by `placement`: no pins,
/// no floor, no colliders (add them as a test needs).
pub fn free_mesh_scene(name: &str, placement: clothlab_core::mesh::Placement) -> Scene {
    use clothlab_core::mesh::{PlacedMesh, load_obj};
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes").join(name);
    let mesh = load_obj(&file).unwrap_or_else(|e| panic!("{e}"));
    let mut s =
        Scene { floor_y: None, spheres: Vec::new(), boxes: Vec::new(), motions: Vec::new(), ..Scene::default() };
    s.cloth.mesh = Some(name.into());
    s.cloth.pinning = clothlab_core::Pinning::None;
    (s.cloth.scale, s.cloth.rotate_deg, s.cloth.translate) =
        (placement.scale, placement.rotate_deg, placement.translate);
    s.cloth.mesh_data = Some(std::sync::Arc::new(PlacedMesh::new(&mesh, &placement).unwrap_or_else(|e| panic!("{e}"))));
    s
}

/// Rolls each of `solvers` out `frames` frames against the CPU solver
/// (`validate_rollout`) and asserts each within its bound, and exactly (0 m) where its
/// flag says it computes the CPU's bits (the optimized recipes on llvmpipe).
pub fn assert_rollouts(solvers: Vec<(String, Box<dyn Solver>, bool)>, frames: u32) {
    let mut bad = Vec::new();
    for (name, mut s, exact) in solvers {
        let c = clothlab_cpu::validate::validate_rollout(&mut *s, frames).unwrap();
        println!("{name:18} {} max {:.2e} (bound {:.0e})", c.what, c.max_abs, c.bound);
        if (exact && c.max_abs != 0.0) || c.error > c.bound {
            bad.push(format!("{name}: {:.2e} (exact: {exact})", c.max_abs));
        }
    }
    assert!(bad.is_empty(), "{bad:?}");
}

/// Every kernel of each API's optimized recipe (wgpu, Vulkan, GL: a solver each, built
/// for `sc` and `params`) against its CPU twin on the disturbed input of `sc` with `seed`
/// (`validate_kernels_with`); an API without an adapter is skipped as [`or_skip`] says.
/// Vulkan under the validation layer. The solvers are not stepped after: a rollout needs fresh ones
/// ([`optimized_rollout_solvers`]).
pub fn optimized_kernel_checks(sc: &Scene, params: &SimParams, seed: u64) -> Vec<Check> {
    kernel_checks_of(&Variant::OPTIMIZED.into(), sc, params, seed)
}

/// [`optimized_kernel_checks`] for the recipe `spec` gives on each API.
pub fn kernel_checks_of(spec: &VariantSpec, sc: &Scene, params: &SimParams, seed: u64) -> Vec<Check> {
    use clothlab_engine::validate::validate_kernels_with;
    let mut checks = Vec::new();
    for (_, mut s) in gpu_solvers_of(spec, sc, params) {
        let k = s.recipe_kernels();
        checks.extend(validate_kernels_with(s.runner(), &k, sc, seed, params).unwrap());
        assert_api_clean(&mut *s);
    }
    checks
}

/// Fails if the API reported anything to `s` since the last check ([`AnyGpuSolver::api_check`]:
/// the Vulkan validation layer where it is on, GL's errors).
pub fn assert_api_clean(s: &mut dyn AnyGpuSolver) {
    if let Err(e) = s.api_check() {
        panic!("{}: {e}", s.name());
    }
}

/// The CPU engine's optimized recipe and each API's, fresh, for [`assert_rollouts`]: each
/// flagged exact where it runs on llvmpipe (the optimized recipes compute the CPU
/// solver's bits there: tests/tests/suite/bit_identity.rs) and the CPU engine always.
pub fn optimized_rollout_solvers(sc: &Scene, params: &SimParams) -> Vec<(String, Box<dyn Solver>, bool)> {
    let cpu = clothlab_engine::RecipeSolver::new(Exec::Serial, Variant::OPTIMIZED, sc.clone(), params.clone()).unwrap();
    let mut solvers: Vec<(String, Box<dyn Solver>, bool)> = vec![("cpu engine".into(), Box::new(cpu), true)];
    for (name, s) in gpu_solvers_of(&Variant::OPTIMIZED.into(), sc, params) {
        let exact = s.adapter().contains("llvmpipe");
        solvers.push((name, s.into_solver(), exact));
    }
    solvers
}

/// A GPU solver of some API, for what the tests ask of every one.
pub trait AnyGpuSolver: Solver {
    /// Its adapter's name.
    fn adapter(&self) -> String;
    /// The kernels of its recipe, in order.
    fn recipe_kernels(&self) -> Vec<clothlab_engine::KernelRef>;
    /// The kernels it built: its recipe's and the plain flavor of each.
    fn kernels(&self) -> Vec<clothlab_engine::KernelRef>;
    /// Steps three frames and checks the GPU statistics against the CPU twin's
    /// ([`assert_stats_match_twin`]).
    fn stats_match_twin(&mut self, energy_bound: f32);
    /// What its adapter and scene allow (which kernel flavors run).
    fn caps(&self) -> clothlab_engine::recipe::Caps;
    /// As a kernel runner, for the kernel checks.
    fn runner(&mut self) -> &mut dyn clothlab_engine::validate::KernelRunner;
    /// What the API reported since the last call: the Vulkan validation layer's messages,
    /// GL's errors and debug messages of medium or high severity (`Engine::check`).
    fn api_check(&mut self) -> Result<(), clothlab_core::SolverError>;
    /// As a plain solver.
    fn into_solver(self: Box<Self>) -> Box<dyn Solver>;
}

impl<E: clothlab_engine::Engine + 'static> AnyGpuSolver for clothlab_engine::GpuSolver<E> {
    fn adapter(&self) -> String {
        clothlab_engine::GpuSolver::adapter(self)
    }
    fn recipe_kernels(&self) -> Vec<clothlab_engine::KernelRef> {
        clothlab_engine::GpuSolver::recipe_kernels(self)
    }
    fn kernels(&self) -> Vec<clothlab_engine::KernelRef> {
        clothlab_engine::validate::KernelRunner::kernels(self)
    }
    fn stats_match_twin(&mut self, energy_bound: f32) {
        assert_stats_match_twin(self, energy_bound)
    }
    fn caps(&self) -> clothlab_engine::recipe::Caps {
        clothlab_engine::GpuSolver::caps(self)
    }
    fn runner(&mut self) -> &mut dyn clothlab_engine::validate::KernelRunner {
        self
    }
    fn api_check(&mut self) -> Result<(), clothlab_core::SolverError> {
        self.check("the test")
    }
    fn into_solver(self: Box<Self>) -> Box<dyn Solver> {
        self
    }
}

/// A GPU solver of a batch of worlds ([`Api::batch`]).
pub trait AnyGpuBatch: AnyGpuSolver + clothlab_engine::Batch {}

impl<E: clothlab_engine::Engine + 'static> AnyGpuBatch for clothlab_engine::GpuSolver<E> {}

/// The recipe `spec` gives on wgpu, Vulkan (under the validation layer) and GL, fresh, by
/// API name; an API without an adapter is skipped as [`or_skip`] says.
pub fn gpu_solvers_of(spec: &VariantSpec, sc: &Scene, params: &SimParams) -> Vec<(String, Box<dyn AnyGpuSolver>)> {
    let solver = |api: Api| Some((api.name().to_owned(), api.solver(spec.clone(), sc, params)?));
    Api::ALL.into_iter().filter_map(solver).collect()
}

/// The speed along x of [`moving_table`]'s table, m/s.
pub const TABLE_V: f32 = 0.5;

/// A 0.4 m cloth of 16 × 16 at rest lying `gap` m above the margin over a 1 m table that
/// moves at [`TABLE_V`] along x (no floor, no spheres): the moving-contact scenes of
/// tests/tests/suite/motion.rs and friction.rs.
pub fn moving_table(gap: f32) -> Scene {
    use clothlab_core::scene::{Aabb, ColliderId, Pinning};
    let margin = SimParams::default().collision_margin;
    let mut sc = Scene::with_n(16);
    sc.cloth.size = 0.4;
    sc.cloth.pinning = Pinning::None;
    sc.cloth.top_center = [0.0, 0.5 + margin + gap, -0.2];
    sc.floor_y = None;
    sc.spheres.clear();
    sc.boxes = vec![Aabb::new([-0.5, 0.0, -0.5], [0.5, 0.5, 0.5])];
    let motion = clothlab_core::Motion { velocity: [TABLE_V, 0.0, 0.0], ..clothlab_core::Motion::default() };
    sc.motions = vec![(ColliderId::Box(0), motion)];
    sc
}

/// Contacts alone act along a surface: no drag, wind or damping, no strain passes (they
/// would move velocities after the contacts); `friction` as given.
pub fn still_air(friction: f32) -> SimParams {
    SimParams { friction, damping: 0.0, air_drag: 0.0, wind: [0.0; 3], strain_iterations: 0, ..SimParams::default() }
}

/// The mean over the particles of `st` of `f(index)`, in f64.
pub fn mean(st: &clothlab_core::ClothState, f: impl Fn(usize) -> f64) -> f64 {
    (0..st.pos.len()).map(f).sum::<f64>() / st.pos.len() as f64
}

/// The particles' mean speed, m/s.
pub fn speed(st: &clothlab_core::ClothState) -> f64 {
    mean(st, |i| st.vel[i][..3].iter().map(|&v| (v as f64).powi(2)).sum::<f64>().sqrt())
}

#[cfg(test)]
mod rows {
    #[test]
    fn the_physics_rows_are_the_cpu_solvers_and_the_recipes_the_constants_name() {
        let want = [
            "cpu".to_owned(),
            "cpu-par".to_owned(),
            format!("{} naive", super::NAIVE_ON.name()),
            format!("{} optimized", super::OPTIMIZED_ON.name()),
        ];
        assert_eq!(super::PHYSICS_BACKENDS.map(String::from), want);
    }
}
