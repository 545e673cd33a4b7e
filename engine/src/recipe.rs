//! Recipes: the commands of one substep for each variant, as data — dispatches that name
//! their kernel (whose row names its bindings), explicit clears and ping-pong swaps. Every
//! engine executes the same recipe, so two backends running one variant differ only in
//! the API and how it is driven; barriers follow from the rows' reads and writes
//! ([`Hazards`]).

use clothlab_core::layout::Buf;
use clothlab_core::step_params::StepParams;
pub use clothlab_core::substep::Integration;
use clothlab_core::substep::Stage;
use clothlab_core::{Integrator, SolverError};
use clothlab_cpu as cpu;

use crate::kernels::{self as k, Dispatches, Flavor, HostBuffers, KernelDef, KernelRef};

use crate::variant::{Accumulate, Fusion, Normals, StrainCounts, Temporal};
pub use crate::variant::{Caps, Variant};

/// One command of a recipe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// Run a kernel over its [`k::Count`].
    Dispatch(KernelRef),
    /// Run a kernel of [`k::Count::Range`] over `count` invocations, `first` and `count`
    /// in its immediates ([`k::Immediates::Range`]): one XPBD pass of a mesh, springs
    /// `first .. first + count` of the list.
    Range {
        /// The kernel.
        kernel: KernelRef,
        /// The first element of the range.
        first: u32,
        /// Its length.
        count: u32,
    },
    /// Zero a buffer (before a kernel that accumulates into it).
    Clear(Buf),
    /// Swap the position pair: [`Buf::PosOut`] becomes [`Buf::Pos`] (after a kernel that
    /// writes the other buffer).
    Swap,
}

impl Command {
    /// The kernel it dispatches, if it is a dispatch.
    pub fn kernel(&self) -> Option<KernelRef> {
        match self {
            Command::Dispatch(k) | Command::Range { kernel: k, .. } => Some(*k),
            _ => None,
        }
    }
}

/// A backend that runs commands on buffers given from the host: what the kernel checks
/// and the bisection need of a GPU solver.
pub trait KernelRunner {
    /// Every shader it can run.
    fn kernels(&self) -> Vec<KernelRef>;
    /// Uploads `bufs` (and `p` as the step constants), runs `commands`, and reads the
    /// buffers back into `bufs` (after a [`Command::Swap`], `bufs.pos` is what was
    /// `pos_out`).
    fn run_commands(&mut self, commands: &[Command], p: &StepParams, bufs: &mut HostBuffers)
    -> Result<(), SolverError>;
    /// The adapter, in one line.
    fn adapter(&self) -> String;
    /// Builds a kernel that is not built in (WGSL compiled now), so that it can be run;
    /// an error says what the compiler said.
    fn add_kernel(&mut self, kernel: KernelRef) -> Result<(), SolverError> {
        Err(SolverError::Shader {
            kernel: kernel.shader_name(),
            reason: format!("{} takes no extra kernels", self.adapter()),
        })
    }
}

/// The commands that run `kernel` once: clears of what it accumulates into, the
/// dispatch, and a swap if it writes the other position buffer.
pub fn run(kernel: KernelRef) -> Vec<Command> {
    let mut v: Vec<Command> = kernel.def.accumulates.iter().map(|b| Command::Clear(*b)).collect();
    v.push(Command::Dispatch(kernel));
    if kernel.def.swaps() {
        v.push(Command::Swap);
    }
    v
}

/// The kernels of one substep with `strain_passes` strain passes, integrated by `how`:
/// the stages of [`Integration::stages`] (the order, written once) each as the variant's
/// kernels — the force evaluation in the variant's form (fused with `fusion=clothlab`,
/// the springs scattered with `springs=scatter`), Verlet's force, update and colliders
/// fused as `fusion` says (the thesis's fusion is Verlet's own; the tiles run the strain
/// passes too), the last strain pass counting for the self-collision's hash, and the
/// normals left to the frame's end with `normals=frame`.
fn stage_kernels(variant: &Variant, how: Integration, strain_passes: u32) -> Vec<&'static KernelDef> {
    let springs: &'static KernelDef = match variant.springs {
        Accumulate::Scatter => &k::SPRINGS_SCATTER,
        Accumulate::Gather => &k::SPRINGS,
    };
    let eval: Vec<&'static KernelDef> = match variant.fusion {
        Fusion::IntoGather | Fusion::Tile => vec![&k::FORCES_SPRINGS],
        _ => vec![&k::FORCES, springs],
    };
    let tile = tiled(variant, how, strain_passes);
    let frame_normals = normals_at_frame_end(variant, how);
    // Self-collision after a strain limit: its count fused into the last pass (one
    // dispatch and one read of the positions fewer).
    let fused_count = how.self_collision && strain_passes > 0 && !tile;
    let stages = how.stages(strain_passes);
    let mut v: Vec<&'static KernelDef> = Vec::new();
    let mut rest = &stages[..];
    while let Some((stage, tail)) = rest.split_first() {
        // The force, the update and the colliders of Verlet (the one integrator whose
        // stages these three are), fused as the variant says.
        if let ([Stage::Eval, Stage::Integrate, Stage::Collide, after @ ..], false) =
            (rest, variant.fusion == Fusion::None)
        {
            v.extend(match variant.fusion {
                Fusion::IntoIntegrate => vec![springs, &k::FORCES_INTEGRATE_COLLIDE],
                Fusion::Tile if tile => vec![&k::SUBSTEP_TILE, &k::TILE_VEL],
                _ if frame_normals => vec![&k::FORCES_SPRINGS_WIND, &k::INTEGRATE_COLLIDE],
                _ => vec![&k::FORCES_SPRINGS, &k::INTEGRATE_COLLIDE],
            });
            rest = after;
            continue;
        }
        rest = tail;
        match *stage {
            Stage::Eval => v.extend(&eval),
            Stage::Forces => v.push(&k::FORCES),
            Stage::Integrate => v.push(&k::INTEGRATE),
            Stage::Euler => v.push(&k::EULER),
            Stage::RkBegin => v.push(&k::RK_BEGIN),
            Stage::Rk { order: 2, stage } => v.push([&k::RK2_1, &k::RK2_2][stage as usize]),
            Stage::Rk { stage, .. } => v.push([&k::RK4_1, &k::RK4_2, &k::RK4_3, &k::RK4_4][stage as usize]),
            Stage::CgBegin => v.extend([&k::CG_BEGIN, &k::CG_REDUCE_RZ]),
            Stage::CgIteration => {
                v.extend([&k::CG_MATVEC, &k::CG_REDUCE_PQ, &k::CG_STEP, &k::CG_REDUCE_RZ, &k::CG_DIRECTION])
            }
            Stage::ImplicitFinish => v.push(&k::IMPLICIT_FINISH),
            Stage::XpbdIteration => v.extend(cpu::XPBD_ORDER.iter().map(|&pass| &k::XPBD[pass])),
            // One `vbd_colour` per sweep here; `recipe_for` makes it a dispatch per colour
            // of the cloth's colouring (core::cpu::vbd).
            // With the contact between triangles its terms go inside the solves: found
            // at the iterate, which the positions hold from the prediction on.
            Stage::VbdBegin if how.triangles => v.extend([&k::VBD_BEGIN, &k::VBD_POSITIONS]),
            Stage::VbdBegin => v.push(&k::VBD_BEGIN),
            Stage::VbdSweep if how.triangles => v.push(&k::VBD_COLOUR_TRI),
            Stage::VbdSweep => v.push(&k::VBD_COLOUR),
            Stage::VbdAccelerate if how.triangles => v.extend([&k::VBD_ACCELERATE, &k::VBD_POSITIONS]),
            Stage::VbdAccelerate => v.push(&k::VBD_ACCELERATE),
            Stage::VbdFinish => v.push(&k::VBD_FINISH),
            Stage::Collide => v.push(&k::COLLIDE),
            // The tiles run the strain passes themselves.
            Stage::StrainPass(_) if tile => {}
            // Each pass after the counts it divides by (core::cpu::strain_limit), or
            // counting them itself.
            Stage::StrainPass(pass) => {
                let hashed = fused_count && pass + 1 == strain_passes;
                match variant.strain_counts {
                    StrainCounts::Dispatch => {
                        v.extend([&k::STRAIN_COUNT, if hashed { &k::STRAIN_LIMIT_COUNT } else { &k::STRAIN_LIMIT }])
                    }
                    StrainCounts::Inline => {
                        v.push(if hashed { &k::STRAIN_LIMIT_INLINE_COUNT } else { &k::STRAIN_LIMIT_INLINE })
                    }
                    StrainCounts::Strip => {
                        v.push(if hashed { &k::STRAIN_LIMIT_STRIP_COUNT } else { &k::STRAIN_LIMIT_STRIP })
                    }
                }
            }
            Stage::SelfCollision => {
                v.extend(k::SELF_COLLISION.iter().copied().filter(|&d| !(fused_count && d == &k::HASH_COUNT)).map(
                    |d| match d.with_friction {
                        Some(f) if how.self_friction => f,
                        _ => d,
                    },
                ))
            }
            // The contact between triangles (core::cpu::tri_contact's twins).
            Stage::TriangleBounds => v.extend(k::TRI_BEGIN),
            Stage::TriangleSeparate => {
                for _ in 0..clothlab_core::tri_contact::SEPARATION_PASSES {
                    v.extend(k::TRI_SEPARATE);
                }
            }
            Stage::TriangleClamp => v.extend(k::TRI_CLAMP_STAGE),
            Stage::Normals if frame_normals => {}
            Stage::Normals => v.extend(normals_kernels(variant)),
        }
    }
    v
}

/// Whether `variant` integrated by `how` computes the normals once per frame
/// (`normals=frame` where the forces gather computes the wind itself: Verlet and
/// symplectic Euler fused by clothlab, without the contact between triangles; the other
/// integrators' force kernels read the wind that the normals kernels leave in the force
/// buffer every substep).
fn normals_at_frame_end(variant: &Variant, how: Integration) -> bool {
    // The contact between triangles' separation sits between Verlet's update and its
    // colliders, so the gather that computes the wind itself is not fused in: the forces
    // read the wind the normals leave every substep.
    !how.triangles
        && variant.normals == Normals::Frame
        && matches!(variant.fusion, Fusion::IntoGather | Fusion::Tile)
        && matches!(how.integrator, Integrator::Verlet | Integrator::SymplecticEuler)
}

/// The most strain passes the tiled substep takes: each deepens its halo by 2, and at 4
/// passes a 32 × 32 region's tile is 12 × 12 (14 % of the points it loads and computes);
/// with more, `fusion=tile` runs clothlab's fusion.
pub const TILE_MAX_PASSES: u32 = 4;

/// Whether `variant` integrated by `how` with `strain_passes` runs the tiled substep
/// (`fusion=tile`: Verlet or symplectic Euler, at most [`TILE_MAX_PASSES`]; the variant's
/// check has made sure of the grid, the gathers, the wind and the adapter).
pub fn tiled(variant: &Variant, how: Integration, strain_passes: u32) -> bool {
    variant.fusion == Fusion::Tile && normals_at_frame_end(variant, how) && strain_passes <= TILE_MAX_PASSES
}

/// The side of the tiled substep's tiles with `strain_passes` passes and `substeps`
/// substeps per dispatch: the region less the halo on both sides (2 + 2 per pass, per
/// substep); 0 where no tile is left.
pub fn tile_side(strain_passes: u32, substeps: u32) -> u32 {
    let halo = (2 + 2 * strain_passes) * substeps.max(1);
    k::TILE_REGION.saturating_sub(2 * halo)
}

/// The tiles of an `n × n` grid: their side and halo. A grid that fits one region is one
/// tile without a halo (nothing lies outside it), whatever the substeps per dispatch.
pub fn tile_geometry(n: u32, strain_passes: u32, substeps: u32) -> (u32, u32) {
    if n <= k::TILE_REGION {
        return (k::TILE_REGION, 0);
    }
    let side = tile_side(strain_passes, substeps);
    (side, (k::TILE_REGION - side) / 2)
}

/// The smallest tile side temporal blocking accepts: below it a tile computes more than
/// 16 region points per point it keeps.
pub const TILE_MIN_SIDE: u32 = 8;

/// Substeps per dispatch of `variant` (`temporal=on` with the tiles running: the most
/// that divide the frame's substeps and leave tiles of at least [`TILE_MIN_SIDE`]; a
/// whole frame where the cloth fits one region), 1 otherwise.
pub fn dispatch_substeps(
    variant: &Variant,
    how: Integration,
    strain_passes: u32,
    topo: &clothlab_core::ClothTopology,
) -> u32 {
    if variant.temporal != Temporal::On || topo.mesh.is_some() || !tiled(variant, how, strain_passes) {
        return 1;
    }
    let substeps = how.substeps.max(1);
    if topo.n <= k::TILE_REGION {
        return substeps;
    }
    (1..=substeps)
        .rev()
        .find(|&g| substeps.is_multiple_of(g) && tile_side(strain_passes, g) >= TILE_MIN_SIDE)
        .unwrap_or(1)
}

/// The points the tiled substep's workgroups load on `topo` (every tile's region on the
/// grid, halos counted again by each tile that loads them): what its reads of the
/// positions and velocities move, against `n²` for a kernel without a halo.
pub fn tile_loaded_points(topo: &clothlab_core::ClothTopology, strain_passes: u32, substeps: u32) -> u64 {
    let (side, halo) = tile_geometry(topo.n, strain_passes, substeps);
    let (side, halo) = (side.max(1) as i64, halo as i64);
    let n = topo.n as i64;
    // Separable: the region's columns on the grid, summed over the tiles of a row.
    let per_axis: i64 = (0..(n + side - 1) / side)
        .map(|t| {
            let lo = (t * side - halo).max(0);
            let hi = (t * side - halo + k::TILE_REGION as i64).min(n);
            (hi - lo).max(0)
        })
        .sum();
    (per_axis * per_axis) as u64
}

/// The bytes `kernel` moves at least per dispatch on `topo` ([`k::compulsory_bytes`]),
/// the tiled substep's halo counted: its positions and velocities are read once per tile
/// that loads them ([`tile_loaded_points`]).
pub fn bytes_moved(
    kernel: KernelRef,
    topo: &clothlab_core::ClothTopology,
    table_uniform: bool,
    strain_passes: u32,
    substeps: u32,
) -> u64 {
    let bytes = k::compulsory_bytes(kernel, topo, table_uniform);
    if kernel.def.dispatches != Dispatches::Tiles {
        return bytes;
    }
    let extra = tile_loaded_points(topo, strain_passes, substeps).saturating_sub(topo.num_particles() as u64);
    bytes + extra * 32
}

/// Bytes of state a substep must read and write at least: positions and velocities,
/// 16 bytes each, read once and written once per particle.
pub const STATE_BYTES: u64 = 64;

/// The dispatch of `kernel` (`substep_tile`) over `topo`'s tiles: a workgroup per tile
/// (a range of that many workgroups' invocations; the kernel reads no range).
pub fn tile_command(
    kernel: KernelRef,
    topo: &clothlab_core::ClothTopology,
    strain_passes: u32,
    substeps: u32,
) -> Command {
    let side = tile_geometry(topo.n, strain_passes, substeps).0.max(1);
    let per_row = topo.n.div_ceil(side);
    Command::Range { kernel, first: 0, count: per_row * per_row * clothlab_core::layout::WORKGROUP }
}

/// The normals kernels of `variant`: scattered, or gathered.
fn normals_kernels(variant: &Variant) -> [&'static KernelDef; 2] {
    match variant.normals {
        Normals::Scatter => [&k::TRI_NORMALS_SCATTER, &k::VERTEX_NORMALS_NAIVE],
        Normals::Gather | Normals::Frame => [&k::TRI_NORMALS, &k::VERTEX_NORMALS],
    }
}

/// [`recipe`] for the cloth `topo`: each kernel as its row's dispatches on the cloth
/// ([`Expander`]: VBD's colours, the tiles, a mesh's XPBD passes), on a mesh each grid
/// kernel as its row's mesh kernel ([`k::OnMesh`]: the mesh's XPBD passes in an
/// iteration's place, `self_collide_mesh` for the response), and the moving pins first.
pub fn recipe_for(
    variant: &Variant,
    strain_passes: u32,
    how: Integration,
    topo: &clothlab_core::ClothTopology,
) -> Vec<Command> {
    let tile_substeps = dispatch_substeps(variant, how, strain_passes, topo);
    let mut expander = Expander::new(topo, strain_passes, tile_substeps, f32::from_bits(how.vbd_rho_bits));
    // Moving pins first: every kernel of the substep sees them at their poses.
    let pins = (!topo.pins.slots.is_empty()).then(|| Command::Dispatch(k::PINS.plain()));
    pins.into_iter()
        .chain(recipe(variant, strain_passes, how))
        .flat_map(|c| match c {
            Command::Dispatch(kr) => match (&topo.mesh, kr.def.on_mesh) {
                (Some(_), k::OnMesh::Nothing) => Vec::new(),
                (Some(_), k::OnMesh::Kernel(mesh)) => expander.expand(mesh.flavor(kr.flavor)),
                _ => expander.expand(kr),
            },
            c => vec![c],
        })
        .collect()
}

/// How kernels become dispatches on a cloth ([`k::Dispatches`], each row's): the
/// recipe's and the kernel tests' one expansion.
pub struct Expander<'a> {
    topo: &'a clothlab_core::ClothTopology,
    strain_passes: u32,
    tile_substeps: u32,
    rho: f32,
    /// VBD sweeps expanded so far: the Chebyshev step after sweep `k` takes ω(k).
    pub sweeps: u32,
}

impl<'a> Expander<'a> {
    /// For `topo` with `strain_passes` strain passes, `tile_substeps` substeps per tiled
    /// dispatch and VBD's ρ `rho`.
    pub fn new(topo: &'a clothlab_core::ClothTopology, strain_passes: u32, tile_substeps: u32, rho: f32) -> Self {
        Self { topo, strain_passes, tile_substeps, rho, sweeps: 0 }
    }

    /// [`run`] with the dispatch expanded: the clears of what `kernel` adds into, its
    /// dispatches, the swap after a kernel that writes the other position buffer.
    pub fn run(&mut self, kernel: KernelRef) -> Vec<Command> {
        run(kernel)
            .into_iter()
            .flat_map(|c| if c == Command::Dispatch(kernel) { self.expand(kernel) } else { vec![c] })
            .collect()
    }

    /// The dispatches of `kernel` on the cloth, by its row's [`k::Dispatches`].
    pub fn expand(&mut self, kernel: KernelRef) -> Vec<Command> {
        let topo = self.topo;
        match kernel.def.dispatches {
            Dispatches::Once => vec![Command::Dispatch(kernel)],
            Dispatches::Colours => {
                self.sweeps += 1;
                vbd_sweep(kernel, topo)
            }
            Dispatches::ColoursWithContact => {
                self.sweeps += 1;
                let terms = k::TRI_VBD.flavor(kernel.flavor);
                let terms = KernelRef { uses: kernel.uses, ..terms };
                contact_colours(terms, topo)
                    .into_iter()
                    .zip(vbd_sweep(kernel, topo))
                    .flat_map(|(a, b)| [a, b])
                    .collect()
            }
            Dispatches::ContactColours => contact_colours(kernel, topo),
            Dispatches::Chebyshev => vec![vbd_acceleration(kernel, topo, self.sweeps, self.rho)],
            Dispatches::Tiles => vec![tile_command(kernel, topo, self.strain_passes, self.tile_substeps)],
            Dispatches::MeshPasses => {
                let passes = topo.mesh.as_ref().map_or(&[][..], |m| &m.xpbd_passes[..]);
                passes.windows(2).map(|w| Command::Range { kernel, first: w[0], count: w[1] - w[0] }).collect()
            }
        }
    }
}

/// XPBD's λ cleared ([`k::LAMBDA`]): it starts from zero every substep, before the first
/// pass of the first iteration.
pub fn lambda_clears() -> [Command; 2] {
    k::LAMBDA.map(Command::Clear)
}

/// One VBD sweep of `topo`'s colours: `kernel` (`vbd_colour` in some flavor) over each
/// colour's range of the colouring's list, in colour order.
pub fn vbd_sweep(kernel: KernelRef, topo: &clothlab_core::ClothTopology) -> Vec<Command> {
    topo.colours.ranges().map(|(first, count)| Command::Range { kernel, first, count }).collect()
}

/// `kernel` (`tri_vbd`) over the contact between triangles' owners once per colour of
/// `topo`'s colouring, the colour's index as the range's `first`.
pub fn contact_colours(kernel: KernelRef, topo: &clothlab_core::ClothTopology) -> Vec<Command> {
    let owners = cpu::tri_contact::TriLayout::of(topo).num_owners() as u32;
    (0..topo.colours.len() as u32).map(|c| Command::Range { kernel, first: c, count: owners }).collect()
}

/// VBD's Chebyshev step after sweep `k` (from 1) with ρ `rho`: `kernel`
/// (`vbd_accelerate`) over every particle, ω's bits as the range's `first`.
pub fn vbd_acceleration(kernel: KernelRef, topo: &clothlab_core::ClothTopology, k: u32, rho: f32) -> Command {
    let omega = cpu::vbd::chebyshev_omega(k, rho);
    Command::Range { kernel, first: omega.to_bits(), count: topo.num_particles() as u32 }
}

/// The commands of one substep for `variant` with `strain_passes` strain passes,
/// integrated by `how`, each kernel in the flavor the variant's switches pick (see
/// [`Variant::flavor`]), on a grid ([`recipe_for`] any cloth, and VBD's sweeps, which
/// stand here as one `vbd_colour` dispatch per iteration). What runs once after a
/// frame's last substep is [`frame_end`].
pub fn recipe(variant: &Variant, strain_passes: u32, how: Integration) -> Vec<Command> {
    let flavor = variant.flavor();
    let mut commands: Vec<Command> =
        stage_kernels(variant, how, strain_passes).into_iter().flat_map(|d| run(d.flavor(flavor))).collect();
    // XPBD's λ (aux0, aux1) starts from zero every substep: cleared before its first pass.
    if let Some(first) = commands.iter().position(|c| c.kernel().is_some_and(|k| k.def == &k::XPBD[cpu::XPBD_ORDER[0]]))
    {
        commands.splice(first..first, lambda_clears());
    }
    commands
}

/// The commands that run once after the last substep of a frame: the normals with
/// `normals=frame` (for drawing, and the state a frame leaves: normals and the wind force
/// of the final positions, as every other recipe leaves them); nothing otherwise.
pub fn frame_end(variant: &Variant, how: Integration) -> Vec<Command> {
    if !normals_at_frame_end(variant, how) {
        return Vec::new();
    }
    let flavor = variant.flavor();
    normals_kernels(variant).iter().flat_map(|d| run(d.flavor(flavor))).collect()
}

/// The shaders a solver of `variant` offers to a validation: what its recipe dispatches,
/// and the plain flavor of every kernel of the step (so that each can be validated). A
/// solver builds its own recipe's when it starts and the others when first run.
pub fn kernels_for(variant: &Variant) -> Vec<KernelRef> {
    let mut commands = recipe(variant, 1, Integration::VERLET);
    commands.extend(frame_end(variant, Integration::VERLET));
    let mut v = kernels_of(&commands);
    // (The contact between triangles' kernels only where the recipe has them: with a
    // scene's constants without that contact they have no thickness to act on.)
    for def in k::ALL.iter().filter(|d| d.immediates == k::Immediates::None && !k::TRI_CONTACT_KERNELS.contains(d)) {
        if !v.contains(&def.plain()) {
            v.push(def.plain());
        }
    }
    v
}

/// How a substep's statistics (max strain, kinetic energy) are reduced on the GPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StatsMode {
    /// Not computed.
    #[default]
    Off,
    /// Every invocation adds into the substep's entry with atomics (`stats_atomic`).
    Atomics,
    /// Subgroup and workgroup reductions, one partial per workgroup, then one workgroup
    /// folds the partials (`stats` + `stats_reduce`): no atomics.
    Subgroups,
}

/// The commands that compute a substep's statistics at its end.
pub fn stats_commands(mode: StatsMode, caps: Caps) -> Vec<Command> {
    let f32 = Flavor { float_atomics: caps.float_atomics, ..Flavor::default() };
    let kernels: &[&'static KernelDef] = match mode {
        StatsMode::Off => &[],
        StatsMode::Atomics => &[&k::STATS_ATOMIC],
        StatsMode::Subgroups => &[&k::STATS, &k::STATS_REDUCE],
    };
    kernels.iter().flat_map(|d| run(d.flavor(f32))).collect()
}

/// The dispatches of `commands`.
pub fn dispatches(commands: &[Command]) -> impl Iterator<Item = KernelRef> + '_ {
    commands.iter().filter_map(Command::kernel)
}

/// The distinct kernels of a recipe, in order.
pub fn kernels_of(commands: &[Command]) -> Vec<KernelRef> {
    let mut v: Vec<KernelRef> = Vec::new();
    for d in dispatches(commands) {
        if !v.contains(&d) {
            v.push(d);
        }
    }
    v
}

/// The buffers a frame's commands read and write, as bits, the position pair by physical
/// buffer (the tables, written only between frames, are left out).
pub mod res {
    /// Position buffer 0 of the pair.
    pub const POS0: u32 = 1 << 0;
    /// Position buffer 1 of the pair.
    pub const POS1: u32 = 1 << 1;
    /// Velocities.
    pub const VEL: u32 = 1 << 2;
    /// Forces.
    pub const FORCE: u32 = 1 << 3;
    /// Vertex normals.
    pub const NORMAL: u32 = 1 << 4;
    /// Face normals.
    pub const FACES: u32 = 1 << 5;
    /// Step constants.
    pub const PARAMS: u32 = 1 << 6;
    /// The per-substep statistics.
    pub const STATS: u32 = 1 << 7;
    /// The statistics' per-workgroup partials.
    pub const PARTIALS: u32 = 1 << 8;
    /// The integrators' scratch buffers (all five: one bit).
    pub const AUX: u32 = 1 << 9;
    /// The conjugate-gradient scalars.
    pub const SCALARS: u32 = 1 << 10;
    /// The contact between triangles' start, integers and pairs (one bit).
    pub const TRI: u32 = 1 << 11;
    /// The adjoint's planes.
    pub const ADJOINT: u32 = 1 << 12;
    /// Everything.
    pub const ALL: u32 = (1 << 13) - 1;
}

/// The hazard bits of `buf` when the current positions are `pos[cur]`.
pub fn bits(buf: Buf, cur: usize) -> u32 {
    use res::*;
    match buf.data() {
        Buf::Pos if cur == 0 => POS0,
        Buf::Pos => POS1,
        Buf::PosOut if cur == 0 => POS1,
        Buf::PosOut => POS0,
        Buf::Vel => VEL,
        Buf::Force => FORCE,
        Buf::Normal => NORMAL,
        Buf::Faces => FACES,
        Buf::Params => PARAMS,
        Buf::StatsMax | Buf::StatsEnergy => STATS,
        Buf::Partials => PARTIALS,
        Buf::Aux0 | Buf::Aux1 | Buf::Aux2 | Buf::Aux3 | Buf::Aux4 => AUX,
        Buf::Scalars => SCALARS,
        Buf::TriFloats | Buf::TriInts | Buf::TriPairs => TRI,
        Buf::Adjoint => ADJOINT,
        // Tables: written only between frames, with a full barrier.
        _ => 0,
    }
}

/// What `kernel` reads and writes when the current positions are `pos[cur]`.
pub fn access(kernel: &KernelDef, cur: usize) -> (u32, u32) {
    let mask = |bufs: &[Buf]| bufs.iter().fold(0, |m, b| m | bits(*b, cur));
    (mask(kernel.reads), mask(kernel.writes))
}

/// Tracks what was read and written since the last barrier, so that a recorder places a
/// barrier only before an access that depends on an earlier one: a read or write of
/// something written (read-after-write, write-after-write) or a write of something read
/// (write-after-read). A global memory barrier clears both sets.
#[derive(Debug, Clone, Copy, Default)]
pub struct Hazards {
    read: u32,
    written: u32,
}

impl Hazards {
    /// Whether an access reading `reads` and writing `writes` must wait for a barrier.
    pub fn conflicts(&self, reads: u32, writes: u32) -> bool {
        (reads | writes) & self.written != 0 || writes & self.read != 0
    }

    /// Notes an access (after any barrier it needed).
    pub fn add(&mut self, reads: u32, writes: u32) {
        self.read |= reads;
        self.written |= writes;
    }

    /// Notes a barrier.
    pub fn clear(&mut self) {
        *self = Self::default();
    }

    /// Notes an access the tracker cannot see (an upload): everything is suspect.
    pub fn dirty(&mut self) {
        self.written = res::ALL;
    }

    /// Notes `command` at parity `*cur` (a swap flips it); returns whether a barrier must
    /// come before it.
    pub fn command(&mut self, command: &Command, cur: &mut usize) -> bool {
        let (r, w) = match command {
            Command::Dispatch(k) | Command::Range { kernel: k, .. } => access(k.def, *cur),
            Command::Clear(b) => (0, bits(*b, *cur)),
            Command::Swap => {
                *cur ^= 1;
                return false;
            }
        };
        let before = self.conflicts(r, w);
        if before {
            self.clear();
        }
        self.add(r, w);
        before
    }

    /// The number of barriers `commands` need from parity `cur`.
    pub fn plan(&mut self, commands: &[Command], mut cur: usize) -> usize {
        commands.iter().filter(|c| self.command(c, &mut cur)).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The optimized preset with the normals every substep, colliders in storage,
    /// neighbours loaded and the strain counts dispatched: the six-kernel fused step these
    /// tests count (the preset itself is the ladder's top, tested in
    /// `normals_once_per_frame…` and `a_strain_pass_that_counts…`).
    fn gathered() -> Variant {
        let mut v = Variant::OPTIMIZED;
        let switches =
            [("normals", "gather"), ("colliders", "storage"), ("neighbours", "load"), ("strain_counts", "dispatch")];
        for (k, val) in switches {
            v.set(k, val).unwrap();
        }
        v
    }

    const CAPS: Caps = Caps {
        float_atomics: false,
        immediates: true,
        table_image: false,
        subgroups: false,
        grid: true,
        tile: true,
        sdf_image: false,
        cpu: false,
    };

    fn barriers_per_substep(r: &[Command]) -> usize {
        // Two substeps, counted in the second (the first also pays for the frame start).
        let mut h = Hazards::default();
        let first = h.plan(r, 0);
        assert!(first >= 1);
        // Parity after one substep: flipped once per swap.
        let cur = r.iter().filter(|c| **c == Command::Swap).count() % 2;
        h.plan(r, cur)
    }

    #[test]
    fn every_dependent_dispatch_gets_a_barrier_and_no_other() {
        let count = |r: &[Command]| dispatches(r).count();
        // Optimized: each of its six kernels reads what the one before wrote (the strain
        // pass the counts before it).
        let opt = recipe(&gathered(), 1, Integration::VERLET);
        assert_eq!(count(&opt), 6);
        assert_eq!(barriers_per_substep(&opt), count(&opt));
        // Statistics read only the positions: they need no barrier after the normals,
        // and the reduction's barrier also covers the next substep's force write, so
        // they cost no barrier at all.
        let mut with_stats = opt.clone();
        with_stats.extend(stats_commands(StatsMode::Subgroups, CAPS));
        assert_eq!(barriers_per_substep(&with_stats), count(&opt));
        let mut with_atomics = opt.clone();
        with_atomics.extend(stats_commands(StatsMode::Atomics, CAPS));
        // stats_atomic writes the substep's own entry: the next substep's forces depend
        // on the normals' force write, so one barrier covers both.
        assert_eq!(barriers_per_substep(&with_atomics), count(&opt));
        // Naive: every dispatch waits for the one before; the normal clear needs none (the
        // normals were last read several barriers ago), the scatter after it does.
        let naive = recipe(&Variant::NAIVE, 1, Integration::VERLET);
        assert!(naive.contains(&Command::Clear(Buf::Normal)));
        assert_eq!(barriers_per_substep(&naive), count(&naive));
        // Two strain passes: the second reads the first's output.
        let two_passes = recipe(&gathered(), 2, Integration::VERLET);
        assert_eq!(barriers_per_substep(&two_passes), count(&two_passes));
        // The thesis's: the springs scatter, then the fused Verlet kernel; two strain
        // passes of two dispatches each (counts, pass).
        let thesis = recipe(&Variant::THESIS, 2, Integration::VERLET);
        assert_eq!(count(&thesis), 8);
        assert_eq!(barriers_per_substep(&thesis), count(&thesis));
        assert_eq!(barriers_per_substep(&two_passes), count(&two_passes));
    }

    #[test]
    fn a_mesh_runs_its_xpbd_passes_as_ranges_where_a_grid_runs_its_twelve() {
        use clothlab_core::mesh::{PlacedMesh, Placement, grid_mesh};
        let mut scene = clothlab_core::Scene::with_n(8);
        scene.cloth.mesh = Some("grid.obj".into());
        scene.cloth.pinning = clothlab_core::Pinning::Vertices(vec![0, 7]);
        let placed = PlacedMesh::new(&grid_mesh(8, 1.0), &Placement::default()).unwrap();
        scene.cloth.mesh_data = Some(std::sync::Arc::new(placed));
        let params = clothlab_core::SimParams::default();
        let (_, topo) = clothlab_core::build(&scene, &params).unwrap();
        let passes = topo.mesh.as_ref().unwrap().xpbd_passes.clone();
        let how = Integration { integrator: Integrator::Xpbd, xpbd_iterations: 2, ..Integration::VERLET };
        let r = recipe_for(&Variant::NAIVE, 1, how, &topo);
        let ranges: Vec<(u32, u32)> = r
            .iter()
            .filter_map(|c| match c {
                Command::Range { kernel, first, count } if kernel.def == &k::XPBD_MESH => Some((*first, *count)),
                _ => None,
            })
            .collect();
        // Two iterations of every pass, in order, covering the spring list once each.
        let one: Vec<(u32, u32)> = passes.windows(2).map(|w| (w[0], w[1] - w[0])).collect();
        assert_eq!(ranges, [one.clone(), one].concat());
        assert_eq!(passes.last().copied(), Some(topo.springs.len() as u32));
        assert!(!dispatches(&r).any(|k| k::XPBD.iter().any(|d| d == k.def)), "no grid pass on a mesh");
        // λ cleared once, before the first pass; every pass waits for the one before.
        let first = r.iter().position(|c| matches!(c, Command::Range { .. })).unwrap();
        assert_eq!(r[first - 2..first], [Command::Clear(Buf::Aux0), Command::Clear(Buf::Aux1)]);
        let mut h = Hazards::default();
        let mut cur = 0;
        let waits = r.iter().filter(|c| h.command(c, &mut cur) && matches!(c, Command::Range { .. })).count();
        assert_eq!(waits, ranges.len());
        // A grid keeps its 12 passes.
        let grid = clothlab_core::build(&clothlab_core::Scene::with_n(8), &params).unwrap().1;
        assert_eq!(recipe_for(&Variant::NAIVE, 1, how, &grid), recipe(&Variant::NAIVE, 1, how));
    }

    #[test]
    fn a_read_after_a_write_always_waits() {
        let mut h = Hazards::default();
        assert!(!h.conflicts(res::POS0, res::FORCE));
        h.add(res::POS0, res::FORCE);
        assert!(h.conflicts(res::FORCE, 0), "read after write");
        assert!(h.conflicts(0, res::FORCE), "write after write");
        assert!(h.conflicts(0, res::POS0), "write after read");
        assert!(!h.conflicts(res::POS0 | res::VEL, res::FACES), "reads of unwritten buffers");
        h.clear();
        assert!(!h.conflicts(res::FORCE, res::FORCE));
        h.dirty();
        assert!(h.conflicts(res::VEL, 0));
    }

    #[test]
    fn recipes_swap_after_each_strain_pass_and_pick_the_flavors_of_the_switches() {
        let mut v = gathered();
        v.set("table", "image").unwrap();
        let r = recipe(&v, 3, Integration::VERLET);
        assert_eq!(r.iter().filter(|c| **c == Command::Swap).count(), 3);
        let names: Vec<String> = dispatches(&r).map(|k| k.shader_name()).collect();
        assert_eq!(
            names,
            [
                "forces_springs_tex_imm",
                "integrate_collide_imm",
                "strain_count_tex_imm",
                "strain_limit_tex_imm",
                "strain_count_tex_imm",
                "strain_limit_tex_imm",
                "strain_count_tex_imm",
                "strain_limit_tex_imm",
                "tri_normals_imm",
                "vertex_normals_imm"
            ]
        );
        let names =
            |v: &Variant| dispatches(&recipe(v, 1, Integration::VERLET)).map(|k| k.shader_name()).collect::<Vec<_>>();
        assert_eq!(
            names(&Variant::NAIVE),
            [
                "forces_sto",
                "springs_scatter_f32_sto",
                "integrate_sto",
                "collide_sto",
                "strain_count_sto",
                "strain_limit_sto",
                "tri_normals_scatter_f32_sto",
                "vertex_normals_naive_sto"
            ]
        );
        assert_eq!(
            names(&Variant::THESIS),
            [
                "springs_scatter_f32",
                "forces_integrate_collide_cu",
                "strain_count_tex",
                "strain_limit_tex",
                "tri_normals",
                "vertex_normals"
            ]
        );
    }

    #[test]
    fn a_strain_pass_that_counts_for_itself_replaces_the_count_dispatch() {
        assert_eq!(Variant::OPTIMIZED.strain_counts, StrainCounts::Strip, "the optimized preset counts in the pass");
        let mut inline = gathered();
        inline.set("strain_counts", "inline").unwrap();
        let names =
            |how: Integration| -> Vec<&str> { dispatches(&recipe(&inline, 2, how)).map(|k| k.def.name).collect() };
        let normals = ["tri_normals", "vertex_normals"];
        let step = ["forces_springs", "integrate_collide", "strain_limit_inline", "strain_limit_inline"];
        assert_eq!(names(Integration::VERLET), [&step[..], &normals].concat());
        // With self-collision the last pass counts into the hash, as the dispatched one does,
        // after the same clears.
        let sc = Integration { self_collision: true, ..Integration::VERLET };
        let hash = ["hash_scan_top", "hash_scan_blocks", "hash_scatter", "self_collide"];
        let head = ["forces_springs", "integrate_collide", "strain_limit_inline", "strain_limit_inline_count"];
        assert_eq!(names(sc), [&head[..], &hash, &normals].concat());
        let r = recipe(&inline, 1, sc);
        let at = r.iter().position(|c| c.kernel().is_some_and(|k| k.def == &k::STRAIN_LIMIT_INLINE_COUNT)).unwrap();
        assert_eq!(r[at - 2..at], [Command::Clear(Buf::Aux2), Command::Clear(Buf::Aux3)]);
        // Each pass still follows what it reads: one barrier per dispatch.
        let plain = recipe(&inline, 1, Integration::VERLET);
        assert_eq!(barriers_per_substep(&plain), dispatches(&plain).count());
    }

    #[test]
    fn self_collision_counts_in_the_last_strain_pass_and_alone_without_one() {
        let sc = Integration { self_collision: true, ..Integration::VERLET };
        let names = |passes: u32| -> Vec<String> {
            dispatches(&recipe(&gathered(), passes, sc)).map(|k| k.def.name.to_owned()).collect()
        };
        let hash = ["hash_scan_top", "hash_scan_blocks", "hash_scatter", "self_collide"];
        let with = |head: &[&str]| -> Vec<String> {
            let mut v: Vec<String> = ["forces_springs", "integrate_collide"].iter().map(|s| s.to_string()).collect();
            v.extend(head.iter().chain(&hash).chain(&["tri_normals", "vertex_normals"]).map(|s| s.to_string()));
            v
        };
        assert_eq!(names(2), with(&["strain_count", "strain_limit", "strain_count", "strain_limit_count"]));
        assert_eq!(names(0), with(&["hash_count"]));
        // The fused pass clears the counts before it, as hash_count's recipe does.
        let r = recipe(&gathered(), 1, sc);
        let at = r.iter().position(|c| c.kernel().is_some_and(|k| k.def == &k::STRAIN_LIMIT_COUNT)).unwrap();
        assert_eq!(r[at - 2..at], [Command::Clear(Buf::Aux2), Command::Clear(Buf::Aux3)]);
    }

    #[test]
    fn normals_once_per_frame_leave_the_substep_to_the_wind_gather_where_the_integrator_allows() {
        let v = Variant::OPTIMIZED;
        assert_eq!(v.normals, Normals::Frame, "the optimized preset draws normals once per frame");
        let mut v = gathered();
        v.set("normals", "frame").unwrap();
        let names = |c: &[Command]| dispatches(c).map(|k| k.shader_name()).collect::<Vec<_>>();
        let r = recipe(&v, 1, Integration::VERLET);
        assert_eq!(
            names(&r),
            ["forces_springs_wind_imm", "integrate_collide_imm", "strain_count_imm", "strain_limit_imm"]
        );
        assert_eq!(names(&frame_end(&v, Integration::VERLET)), ["tri_normals_imm", "vertex_normals_imm"]);
        // Four dependent kernels, four barriers; the frame's end reads the last pass.
        assert_eq!(barriers_per_substep(&r), 4);
        // RK4's stages read the wind the normals kernels leave: normals every substep.
        let rk4 = Integration { integrator: Integrator::Rk4, ..Integration::VERLET };
        assert!(frame_end(&v, rk4).is_empty());
        let r = recipe(&v, 1, rk4);
        assert!(names(&r).ends_with(&["tri_normals_imm".to_string(), "vertex_normals_imm".to_string()]));
        assert!(!names(&r).iter().any(|k| k.starts_with("forces_springs_wind")));
        // Normals every substep: nothing at the frame's end.
        assert!(frame_end(&gathered(), Integration::VERLET).is_empty());
    }
}
