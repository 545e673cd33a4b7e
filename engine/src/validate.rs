//! Checking a backend against the twins: every kernel alone on the same input
//! ([`validate_kernels`]), and the bisection of a rollout between the CPU engine and a
//! GPU backend ([`bisect`]). Used by the cross-backend tests and by `clothlab validate`.

use clothlab_core::build;
use clothlab_core::grid::Grab;
use clothlab_core::step_params::StepParams;
use clothlab_core::{Scene, SimParams, SolverError};
use clothlab_cpu::Exec;
use clothlab_cpu::validate::{Check, ROLLOUT_BOUND_PER_SUBSTEP, compare, disturbed_state};

use crate::cpu::CpuEngine;
use crate::kernels::{self, ConstantsHome, HostBuffers, KernelRef};
use crate::recipe::Command;
pub use crate::recipe::KernelRunner;
use crate::variant::{Caps, Variant};

/// The scene, parameters, disturbed buffers and constants every kernel check starts from:
/// an `n × n` cloth draped for 15 frames, then disturbed (seeded), wind on, a particle
/// grabbed.
pub struct KernelInput {
    /// The CPU engine of that cloth.
    pub engine: CpuEngine,
    /// The disturbed buffers, face normals of the disturbed positions.
    pub bufs: HostBuffers,
    /// The step constants.
    pub p: StepParams,
}

impl KernelInput {
    /// The input for an `n × n` cloth, disturbed with `seed`.
    pub fn new(n: u32, seed: u64) -> Result<Self, SolverError> {
        Self::with_params(n, seed, &SimParams::default())
    }

    /// The input for an `n × n` cloth of the default scene with `params` (the spring
    /// constants a runner built with them has), disturbed with `seed`; wind on if `params`
    /// have none.
    pub fn with_params(n: u32, seed: u64, params: &SimParams) -> Result<Self, SolverError> {
        Self::for_scene(&Scene::with_n(n), seed, params)
    }

    /// The input for `scene` (the colliders a runner built with it has) and `params`,
    /// disturbed with `seed`; wind on if `params` have none. Some free particles are then
    /// put inside every collider and under the floor, so that the collision code of every
    /// collider the scene has runs in every kernel that collides.
    pub fn for_scene(scene: &Scene, seed: u64, params: &SimParams) -> Result<Self, SolverError> {
        let scene = scene.clone();
        let wind = if params.wind == [0.0; 3] { [1.5, 0.3, -2.0] } else { params.wind };
        let params = SimParams { wind, ..params.clone() };
        let (mut st, topo, mut faces) = disturbed_state(&scene, &params, seed)?;
        if sink_into_colliders(&scene, &mut st.pos) {
            clothlab_cpu::tri_normals(Exec::Serial, &topo.triangles, &st.pos, &mut faces);
        }
        let grab = Some(Grab { particle: st.pos.len() as u32 / 2 + 3, target: [0.1, 1.2, 0.3] });
        let p = StepParams::new(&params, &scene, grab);
        let mut bufs = HostBuffers::new(&st, faces);
        // The integrators' scratch state, made from the disturbed cloth so that every
        // kernel of every integrator sees values of the sizes it meets in a substep: a
        // saved x₀ and v₀ (w: a preconditioner's diagonal, positive), stage sums, a wind
        // force, and CG scalars.
        for (i, (x, u)) in st.pos.iter().zip(&st.vel).enumerate() {
            let f = st.force[i];
            bufs.aux[0][i] = *x;
            bufs.aux[1][i] = [0.9 * u[0], 0.9 * u[1], 0.9 * u[2], p.particle_mass * (2.0 + (i % 7) as f32 * 0.1)];
            bufs.aux[2][i] = [0.5 * u[0] - 1e-4, 0.5 * u[1], 0.5 * u[2] + 1e-4, 0.0];
            bufs.aux[3][i] = [-0.3 * u[1], 0.2 * u[0], 0.1 * u[2], 0.0];
            bufs.aux[4][i] = [f[0], f[1], f[2], 0.0];
        }
        bufs.scalars[0] = [2e-6, 3e-6, 0.6, 0.25];
        if !topo.pins.slots.is_empty() {
            // The moving pins' poses at a time by which every group has turned and moved.
            let poses = clothlab_core::pins::frame_poses(
                &scene.pins,
                &topo.pins.pivots,
                params.integrator,
                0.3,
                params.dt() as f64,
                1,
            );
            bufs.pin_poses = bytemuck::cast_slice(&poses).to_vec();
        }
        Ok(Self { engine: CpuEngine::new(Exec::Serial, scene, topo), bufs, p })
    }

    /// The input of `kernel`: the disturbed buffers, plus what its row sets up.
    pub fn for_kernel(&self, kernel: KernelRef) -> HostBuffers {
        let mut b = self.bufs.clone();
        if let Some(setup) = kernel.def.test_input {
            setup(&self.engine.args(&self.p, 0), &mut b);
        }
        b
    }
}

/// Moves a few free particles of `pos` into each collider of `scene` (and under its floor):
/// every 97th free particle, taking the colliders in turn, to a point just inside the
/// surface below it (2 % of a sphere's radius deep, 1 cm into a box's top, above a rod's
/// centre by half its smallest size, half a cell behind a body's triangle, 1 cm under
/// the floor), its velocity kept. Returns whether any moved.
fn sink_into_colliders(scene: &Scene, pos: &mut [[f32; 4]]) -> bool {
    let (spheres, boxes) = (scene.spheres.len(), scene.boxes.len());
    let rods = scene.rods.len();
    let targets = spheres + boxes + rods + scene.bodies.len() + usize::from(scene.floor_y.is_some());
    if targets == 0 {
        return false;
    }
    let mut k = 0;
    for (i, p) in pos.iter_mut().enumerate() {
        if p[3] == 0.0 || i % 97 != 13 {
            continue;
        }
        let t = k % targets;
        k += 1;
        if let Some(s) = scene.spheres.get(t) {
            let d = [p[0] - s.center[0], p[2] - s.center[2]];
            let len = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-6);
            // On the upper half, towards the particle's side.
            let r = 0.98 * s.radius;
            let (dx, dz) = (0.5 * r * d[0] / len, 0.5 * r * d[1] / len);
            let dy = (r * r - dx * dx - dz * dz).max(0.0).sqrt();
            *p = [s.center[0] + dx, s.center[1] + dy, s.center[2] + dz, p[3]];
        } else if let Some(b) = scene.boxes.get(t - scene.spheres.len()) {
            let clamp = |v: f32, lo: f32, hi: f32| v.clamp(lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo));
            let depth = 0.01f32.min(0.25 * (b.max[1] - b.min[1]));
            *p = [clamp(p[0], b.min[0], b.max[0]), b.max[1] - depth, clamp(p[2], b.min[2], b.max[2]), p[3]];
        } else if let Some(c) = scene.rods.get(t - spheres - boxes) {
            let m = c.center();
            *p = [m[0], m[1] + 0.5 * c.size(), m[2], p[3]];
        } else if let Some(body) = scene.bodies.get(t - spheres - boxes - rods) {
            // A triangle (a different one each time), half a cell behind its centroid.
            let m = &body.mesh;
            let [a, b, c] = m.triangles[(i * 7919) % m.triangles.len()].map(|v| m.positions[v as usize]);
            let (e, f) = ([0, 1, 2].map(|k| b[k] - a[k]), [0, 1, 2].map(|k| c[k] - a[k]));
            let n = [e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt().max(1e-12);
            let x = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0 - n[k] / len * (0.5 * body.sdf.h));
            *p = [x[0], x[1], x[2], p[3]];
        } else if let Some(y) = scene.floor_y {
            p[1] = y - 0.01;
        }
    }
    k > 0
}

/// The buffers [`validate_kernels`] compares after each kernel: the positions,
/// velocities, forces, normals, face normals, the five integrator scratch buffers, the
/// CG scalars, and the contact between triangles' starts, integers and pairs (the last
/// two exactly: integers, with the scalars' f32 values as their bits).
pub const COMPARED_BUFFERS: usize = 20;

/// `words` (u32s four to an element) as elements whose compared components (xyz) hold
/// each word's two 16-bit halves, exact in f32: an exact comparison of these compares the
/// words.
fn halves(words: &[[f32; 4]]) -> Vec<[f32; 4]> {
    words
        .iter()
        .flat_map(|v| v.map(|x| [(x.to_bits() & 0xffff) as f32, (x.to_bits() >> 16) as f32, 0.0, 0.0]))
        .collect()
}

/// The adjoint's planes `planes` of `np` particles (each partials' plane with its w in
/// the compared xyz: [`with_w`]); nothing where a kernel left it empty.
fn adjoint_planes(adjoint: &[[f32; 4]], np: usize, planes: std::ops::Range<usize>) -> Vec<[f32; 4]> {
    if adjoint.is_empty() {
        return Vec::new();
    }
    let v = &adjoint[planes.start * np..planes.end * np];
    if planes.start >= 3 { with_w(v) } else { v.to_vec() }
}

/// `v`'s w components in the compared xyz (after xyz): the contact's bounds.
fn with_w(v: &[[f32; 4]]) -> Vec<[f32; 4]> {
    v.iter().flat_map(|x| [*x, [x[3], 0.0, 0.0, 0.0]]).collect()
}

/// How far a contact through the distance-field image (`sdf=image`) may move a particle
/// from its twin's, in cells of the coarsest body's grid: φ comes from the texture unit,
/// whose weights have a few bits (`subTexelPrecisionBits`: at least 4 by Vulkan's rules,
/// 8 on NVIDIA), so it is within 3 h·2^-(bits+1) of the interpolant — 0.094 h at 4 bits,
/// 0.006 h at 8 — and the push is along the interpolant's own gradient from the same
/// texels (the twin's normal). Measured on llvmpipe: 6e-8 m (its weights are finer).
pub const SDF_IMAGE_CELLS: f32 = 0.1;

/// The velocities' bound of the image's flavors in `scene`, m/s: a contact leaves the
/// particle the surface's velocity at its pushed position, which the image may put
/// [`sdf_image_bound`] off the twin's: ω × that for the fastest-turning body at time 0
/// (the kernel checks' colliders).
pub fn sdf_image_vel_bound(scene: &Scene) -> f32 {
    let spin = scene.bodies.iter().map(|b| {
        let s = b.head_at(0.0, 0).spin;
        (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt()
    });
    sdf_image_bound(scene) * spin.fold(0.0, f32::max)
}

/// [`SDF_IMAGE_CELLS`] of the coarsest body's cell in `scene`, m (0 without bodies): how
/// far the image's contacts may put a particle from the twins', and the rollouts' bound
/// with `sdf=image` (a resting contact's error does not add up: every substep pushes the
/// particle to the level the image gives).
pub fn sdf_image_bound(scene: &Scene) -> f32 {
    SDF_IMAGE_CELLS * scene.bodies.iter().map(|b| b.sdf.h).fold(0.0, f32::max)
}

/// Runs each of `kernels` alone on `runner` and on the CPU engine, from the same disturbed
/// `n × n` cloth, and compares every buffer; the kernel's pure outputs are poisoned with
/// NaN on the runner's side first, so an element it fails to write shows. Kernels whose
/// row says they are checked by a test of their own are left out.
pub fn validate_kernels(
    runner: &mut dyn KernelRunner,
    kernels: &[KernelRef],
    n: u32,
    seed: u64,
) -> Result<Vec<Check>, SolverError> {
    validate_kernels_with(runner, kernels, &Scene::with_n(n), seed, &SimParams::default())
}

/// [`validate_kernels`] for a runner built with `scene` and `params` (its colliders are
/// the scene's, its spring tables hold the parameters' constants).
pub fn validate_kernels_with(
    runner: &mut dyn KernelRunner,
    kernels: &[KernelRef],
    scene: &Scene,
    seed: u64,
    params: &SimParams,
) -> Result<Vec<Check>, SolverError> {
    let input = KernelInput::for_scene(scene, seed, params)?;
    let topo = input.engine.topology();
    let mut checks = Vec::new();
    for &k in kernels {
        let kernels::Check::Bound { relative, .. } = k.def.check else { continue };
        if !k.def.cloths.run_on(topo) {
            continue;
        }
        // The adjoint's kernels on a cloth a solver makes their planes for.
        if kernels::ADJOINT_KERNELS.contains(&k.def) && !crate::solver::has_adjoint(topo) {
            continue;
        }
        // The kernel's dispatches on the cloth as a recipe makes them (its row's
        // `Dispatches`): every colour of one VBD sweep, the tiles, every pass of a mesh's
        // XPBD iteration (its λ cleared first, as the recipe does once a substep).
        let mut expander = crate::recipe::Expander::new(topo, input.p.strain_passes, input.p.tile_substeps, 0.9);
        let commands = match k.def.dispatches {
            // The acceleration's first sweep (ω = 1: the set-up) and a second (ω > 1).
            kernels::Dispatches::Chebyshev => (1..=2)
                .flat_map(|sweep| {
                    expander.sweeps = sweep;
                    expander.run(k)
                })
                .collect(),
            // One colour's terms and solves: the next colour's terms are found at the
            // positions this one moved, where a pair at the thickness's edge may count on
            // one side and not on the other (its block jumps by k w n nᵀ), so over a sweep
            // a last bit of the solve on a GPU whose division or square root is not the
            // CPU's may grow to a step. The sweep is the rollouts' to check
            // (tests/tests/suite/tri_contact.rs: the CPU's bits on llvmpipe).
            kernels::Dispatches::ColoursWithContact => {
                let all = expander.run(k);
                let first = all.iter().position(|c| c.kernel() == Some(k)).map_or(all.len(), |i| i + 1);
                all[..first].to_vec()
            }
            kernels::Dispatches::MeshPasses => {
                let mut v = crate::recipe::lambda_clears().to_vec();
                v.extend(expander.run(k));
                v
            }
            _ => expander.run(k),
        };
        let mut want = input.for_kernel(k);
        let mut got = want.clone();
        for &buf in k.def.pure {
            if let Some(v) = got.get_mut(buf) {
                v.iter_mut().for_each(|x| *x = [f32::NAN; 4]);
            }
        }
        input.engine.run(&commands, &input.p, 0, &mut want);
        runner.run_commands(&commands, &input.p, &mut got)?;
        if let Some(from_output) = k.def.from_output {
            from_output(&input.p, &got, &mut want);
        }
        let what = k.report_name();
        type Pair<'a> = (&'static str, &'a Vec<[f32; 4]>, &'a Vec<[f32; 4]>);
        // The adjoint: the state's, the force's gradients, then each plane of partials
        // alone (their magnitudes differ by orders: a spring's stiffness times its
        // partial beside gravity's).
        let np = topo.num_particles();
        let adj = |b: &HostBuffers| -> Vec<Vec<[f32; 4]>> {
            std::iter::once(adjoint_planes(&b.adjoint, np, 0..3))
                .chain((3..clothlab_core::layout::ADJ_ROWS as usize).map(|r| adjoint_planes(&b.adjoint, np, r..r + 1)))
                .collect()
        };
        let (adj_got, adj_want) = (adj(&got), adj(&want));
        let compared: [Pair; COMPARED_BUFFERS] = [
            ("pos", &got.pos, &want.pos),
            ("vel", &got.vel, &want.vel),
            ("force", &got.force, &want.force),
            ("normal", &got.normal, &want.normal),
            ("faces", &got.faces, &want.faces),
            ("aux0", &got.aux[0], &want.aux[0]),
            ("aux1", &got.aux[1], &want.aux[1]),
            ("aux2", &got.aux[2], &want.aux[2]),
            ("aux3", &got.aux[3], &want.aux[3]),
            ("aux4", &got.aux[4], &want.aux[4]),
            ("scalars", &got.scalars, &want.scalars),
            ("tri_floats", &with_w(&got.tri_floats), &with_w(&want.tri_floats)),
            ("tri_ints", &halves(&got.tri_ints), &halves(&want.tri_ints)),
            ("tri_pairs", &halves(&got.tri_pairs), &halves(&want.tri_pairs)),
            ("adjoint", &adj_got[0], &adj_want[0]),
            ("adjoint 3", &adj_got[1], &adj_want[1]),
            ("adjoint 4", &adj_got[2], &adj_want[2]),
            ("adjoint 5", &adj_got[3], &adj_want[3]),
            ("adjoint 6", &adj_got[4], &adj_want[4]),
            ("adjoint 7", &adj_got[5], &adj_want[5]),
        ];
        // The image's flavors: positions within `sdf_image_bound` of the twin's and
        // velocities within `sdf_image_vel_bound` (in metres and m/s, so relative to the
        // buffer's largest value).
        let image = if k.flavor.sdf_image { [sdf_image_bound(scene), sdf_image_vel_bound(scene)] } else { [0.0; 2] };
        for (name, g, w) in compared {
            let exact = matches!(name, "tri_ints" | "tri_pairs");
            let mut c = compare(&what, name, g, w, !exact, if exact { 0.0 } else { relative });
            let extra = match name {
                "pos" => image[0],
                "vel" => image[1],
                _ => 0.0,
            };
            if extra > 0.0 {
                let scale = w.iter().flat_map(|v| v[..3].iter()).fold(0.0f32, |m, x| m.max(x.abs()));
                c.bound = c.bound.max(extra / scale.max(f32::MIN_POSITIVE));
            }
            checks.push(c);
        }
    }
    Ok(checks)
}

/// Every flavor of every built-in kernel of the step (the statistics kernels have their
/// own test) that a solver with `caps` runs: immediates and float atomics where it has
/// them, the table image only with `table_image` (a solver uploads the image only for
/// `table=image`). What `clothlab validate` checks, so that every switch is covered.
pub fn flavors(caps: &Caps, table_image: bool) -> Vec<KernelRef> {
    checked_flavors(caps, table_image).filter(|k| !k.flavor.sdf_image).collect()
}

/// The flavors of [`flavors`] that sample the bodies' fields from the image (`_si`), for
/// a solver with `sdf=image` (the only one that uploads it); none where `caps` lack it.
pub fn image_flavors(caps: &Caps) -> Vec<KernelRef> {
    checked_flavors(caps, false).filter(|k| k.flavor.sdf_image && caps.sdf_image).collect()
}

fn checked_flavors(caps: &Caps, table_image: bool) -> impl Iterator<Item = KernelRef> {
    // The contact between triangles' kernels are checked with a scene that has it
    // (tests/tests/suite/tri_contact.rs; `validate --scene` of such a scene checks its
    // recipe's): with other scenes' constants they have no thickness to act on.
    kernels::ALL
        .iter()
        .filter(|d| matches!(d.check, kernels::Check::Bound { .. }) && !kernels::TRI_CONTACT_KERNELS.contains(d))
        .flat_map(|d| d.flavors())
        .filter(move |k| {
            let f = k.flavor;
            (caps.immediates || f.constants != ConstantsHome::Immediates)
                // A batch's `_w` twin as one world: its plain flavor (the others add to it
                // the switches their uniform-constants twins are checked with).
                && (f.constants != ConstantsHome::Worlds
                    || !(f.table_image || f.float_atomics || f.colliders_uniform || f.shuffle || f.sdf_image))
                && (caps.float_atomics || !f.float_atomics)
                && (table_image || !f.table_image)
                && (caps.subgroups || !f.shuffle)
        })
}

/// Kernel checks of `validate --every-switch` on one solver: which solver, which kernels,
/// and the label their rows carry.
#[derive(Debug, Clone)]
pub struct KernelChecks {
    /// The switches of the solver they run on, over the `optimized` preset; `None`: the
    /// backend's own solver.
    pub switches: Option<Vec<String>>,
    /// The kernels, each in its flavor.
    pub kernels: Vec<KernelRef>,
    /// What the rows say after the kernel's name, e.g. ` (table=uniform)`.
    pub label: String,
}

/// What `validate --every-switch` covers on one API with `caps`: every flavor of every
/// kernel against its twin, on the solvers that upload what the flavors read, then a
/// rollout of each variant of [`crate::variant::covering`]. The command runs the plan
/// and prints it.
#[derive(Debug, Clone)]
pub struct SwitchPlan {
    /// The kernel checks, in order.
    pub kernel_checks: Vec<KernelChecks>,
    /// The variants rolled out against the CPU.
    pub rollouts: Vec<Variant>,
}

/// [`SwitchPlan`] for an API with `caps` (`api` its name) on `scene`: every flavor on the
/// backend's solver (the table as uniform constants on the regular grid); the table's
/// flavors on a solver reading it from the image (storage where the API's engine has
/// none); the bodies' fields from the image (`sdf=image`) where the engine has it and the
/// scene has bodies; and the covering variants, less temporal blocking where the scene
/// moves (it poses the colliders and pins once per dispatch: such a scene refuses it).
pub fn every_switch_plan(caps: &Caps, api: &str, scene: &Scene) -> SwitchPlan {
    let mut kernel_checks =
        vec![KernelChecks { switches: None, kernels: flavors(caps, false), label: " (table=uniform)".into() }];
    let table = if caps.table_image { "image" } else { "storage" };
    kernel_checks.push(KernelChecks {
        switches: Some(vec![format!("table={table}")]),
        kernels: flavors(caps, caps.table_image).into_iter().filter(|k| k.def.variants.table_image).collect(),
        label: format!(" (table={table})"),
    });
    let image = image_flavors(caps);
    if !image.is_empty() && !scene.bodies.is_empty() {
        kernel_checks.push(KernelChecks {
            switches: Some(vec!["sdf=image".into()]),
            kernels: image,
            label: " (sdf=image)".into(),
        });
    }
    let rollouts = crate::variant::covering(caps, api)
        .into_iter()
        .filter(|v| !(scene.animated() && v.temporal == crate::variant::Temporal::On))
        .collect();
    SwitchPlan { kernel_checks, rollouts }
}

/// The bound of a rollout of `variant` (`None`: a solver without one) on `scene`, whose
/// own bound is `bound` and whose rounding alone moves it `spread` ([`rounding_spread`]):
/// at least [`SPREAD_FACTOR`] times the spread, and with `sdf=image` at least
/// [`sdf_image_bound`] (through the image a contact may sit a little off the twin's: the
/// filter's weights).
pub fn rollout_bound(bound: f32, variant: Option<&Variant>, scene: &Scene, spread: f32) -> f32 {
    let bound = bound.max(SPREAD_FACTOR * spread);
    if variant.is_some_and(|v| v.sdf == crate::variant::Sdf::Image) { bound.max(sdf_image_bound(scene)) } else { bound }
}

/// How many times [`rounding_spread`] a rollout may differ: a GPU's atomics add in any
/// order, the CPU engine's naive recipe in list order, so on a scene that amplifies
/// rounding the two spreads are draws of one size, not equal (measured on lavapipe, the
/// skirt over 208 substeps: CPU 6.3e-2 m, the GPUs' naive recipes 5.4–6.1e-2 m).
pub const SPREAD_FACTOR: f32 = 4.0;

/// How far rounding alone carries `scene` in `frames` frames: the largest position
/// difference, over the frames, from the CPU solver of two runs that differ in rounding
/// only — the CPU engine running the naive recipe (the same arithmetic but the springs'
/// forces scattered, summed in another order), and the CPU solver started with every free
/// particle moved by one ulp (what any integrator's kernels differ by where a driver
/// rounds or fuses otherwise: XPBD's recipes scatter nothing). A draped grid keeps it near
/// a few ulps per substep; a scene that buckles or flaps (a skirt falling over a sphere, a
/// flag in the wind) amplifies a last bit to centimetres within a few frames, and no
/// rollout can be held closer than that.
pub fn rounding_spread(scene: &Scene, params: &SimParams, frames: u32) -> Result<f32, SolverError> {
    use clothlab_core::Solver;
    let caps = Caps {
        float_atomics: true,
        immediates: true,
        table_image: true,
        subgroups: true,
        grid: !scene.cloth.is_mesh(),
        tile: true,
        sdf_image: true,
        cpu: false,
    };
    let naive = crate::variant::Variant::NAIVE.fit(&caps);
    let mut a = crate::cpu::RecipeSolver::new(Exec::Parallel, naive, scene.clone(), params.clone())?;
    let mut b = clothlab_cpu::CpuSolver::new(Exec::Parallel, scene.clone(), params.clone())?;
    let mut c = clothlab_cpu::CpuSolver::new(Exec::Parallel, scene.clone(), params.clone())?;
    let mut nudged = c.state()?;
    for x in nudged.pos.iter_mut().filter(|x| x[3] != 0.0) {
        x[..3].iter_mut().for_each(|v| *v = v.next_up());
    }
    c.set_state(&nudged)?;
    let mut worst = 0.0f32;
    for _ in 0..frames {
        a.step_frame()?;
        b.step_frame()?;
        c.step_frame()?;
        let reference = &b.state_ref().pos;
        for other in [a.state()?.pos, c.state()?.pos] {
            worst = worst.max(compare("", "pos", &other, reference, false, 0.0).max_abs);
        }
    }
    Ok(worst)
}

/// One split of a bisected rollout.
#[derive(Debug, Clone)]
pub struct Split {
    /// Dispatches of each substep run on the CPU engine (the rest on the GPU).
    pub cpu_dispatches: usize,
    /// The first command run on the GPU, if any.
    pub first_gpu: Option<String>,
    /// Largest position difference from the CPU engine's rollout over the run, m.
    pub check: Check,
}

/// What [`bisect`] found.
#[derive(Debug, Clone)]
pub struct Bisection {
    /// One row per split, from everything on the GPU (0 dispatches on the CPU) to all but
    /// the last on the CPU.
    pub splits: Vec<Split>,
    /// The kernel after which the GPU leaves its bound: the first GPU kernel of the split
    /// with the most CPU dispatches that still fails (running it on the CPU instead
    /// brings the rollout back within its bound). `None` when every split passes.
    pub culprit: Option<String>,
}

/// A rollout of `substeps` substeps of `scene` in which every substep runs its first k
/// dispatches of `commands` on the CPU engine and the rest on `runner`, for every k,
/// against the CPU engine running all of them; see [`Bisection`].
pub fn bisect(
    runner: &mut dyn KernelRunner,
    commands: &[Command],
    scene: &Scene,
    params: &SimParams,
    substeps: u32,
) -> Result<Bisection, SolverError> {
    let (state, topo) = build(scene, params)?;
    let engine = CpuEngine::new(Exec::Serial, scene.clone(), topo);
    let p = StepParams::new(params, scene, None);
    let start = crate::cpu::start_buffers(Exec::Serial, &p, engine.topology(), &state);
    // The reference: every command on the CPU engine, positions after every substep.
    let mut reference = Vec::with_capacity(substeps as usize);
    let mut bufs = start.clone();
    for s in 0..substeps {
        engine.run(commands, &p, s, &mut bufs);
        reference.push(bufs.pos.clone());
    }
    // Split points: before each dispatch (a clear goes with the dispatch after it, a swap
    // with the one before).
    let mut points: Vec<usize> = Vec::new();
    for (i, c) in commands.iter().enumerate() {
        if c.kernel().is_some() {
            let mut at = i;
            while at > 0 && matches!(commands[at - 1], Command::Clear(_)) {
                at -= 1;
            }
            points.push(at);
        }
    }
    let bound = ROLLOUT_BOUND_PER_SUBSTEP * substeps as f32;
    let mut splits = Vec::new();
    for (k, &at) in points.iter().enumerate() {
        let (cpu, gpu) = commands.split_at(at);
        let mut bufs = start.clone();
        let mut worst = compare("", "pos", &[], &[], false, 0.0);
        for (s, want) in reference.iter().enumerate() {
            engine.run(cpu, &p, s as u32, &mut bufs);
            runner.run_commands(gpu, &p, &mut bufs)?;
            let c = compare("", "pos", &bufs.pos, want, false, 0.0);
            // (compare() counts NaN as infinite, so max_abs is ordered.)
            if c.max_abs > worst.max_abs {
                worst = c;
            }
        }
        let first_gpu = gpu.iter().find_map(Command::kernel).map(|k| k.report_name());
        let what = format!("bisect {k}: {} on GPU", first_gpu.as_deref().unwrap_or("-"));
        splits.push(Split {
            cpu_dispatches: k,
            first_gpu,
            check: Check { what, bound, error: worst.max_abs, ..worst },
        });
    }
    let culprit = splits.iter().rev().find(|s| !s.check.passed()).and_then(|s| s.first_gpu.clone());
    Ok(Bisection { splits, culprit })
}
