//! The kernel registry: one [`KernelDef`] per kernel says everything about it — its WGSL,
//! its CPU twin, what it runs over, the bindings it reads and writes, its pure outputs
//! (poisoned before a kernel test), the buffers it accumulates into (cleared before it),
//! its validation bound with the reason, its timing label and its variants. Recipes,
//! barriers, validation, the CLI's listings and the backends read this table; nothing
//! else matches on a kernel's name.
//!
//! The rows live by family, each beside the adapters that make its CPU twins: `forces`
//! (forces, springs, integration, colliders and their fusions), `strain`, `normals`,
//! `stats`, `rk` (explicit Euler and Runge–Kutta), `xpbd`, `vbd`, `cg` (implicit Euler),
//! `self_collision` and `tile`. Each family lists its kernels in `ROWS`; [`ALL`] joins
//! them. This module holds what the rows are made of (the types, the shared bounds and
//! binding lists) and [`compulsory_bytes`].
//!
//! A kernel from outside the crate is a `static KernelDef` with [`Source::Wgsl`]: its WGSL
//! is compiled when a backend first needs it (see `tests/tests/suite/custom_kernel.rs`).

use std::borrow::Cow;
use std::hash::{Hash, Hasher};

use clothlab_core::grid::{ClothTopology, V4};
use clothlab_core::layout::{BLOCK, Buf, STRIP_ROWS, Uses, WORKGROUP};
use clothlab_core::params::MAX_SUBSTEPS;
use clothlab_core::pins::{MAX_PIN_GROUPS, PinPose};
use clothlab_core::step_params::StepParams;
use clothlab_core::timing;
use clothlab_cpu as cpu;
use clothlab_cpu::{Exec, SubstepStats};

use crate::EngineError;

/// What a dispatch runs over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// One invocation per particle.
    Particles,
    /// One per [`BLOCK`] consecutive particles of a row: `n · ⌈n / BLOCK⌉` on a grid, a
    /// mesh's particles as one row (`⌈particles / BLOCK⌉`).
    Blocks,
    /// One per [`BLOCK`] consecutive columns of [`STRIP_ROWS`] rows (the strain limit's
    /// pass down strips): `⌈n / STRIP_ROWS⌉ · ⌈n / BLOCK⌉` on a grid; on a mesh, as
    /// [`Count::Blocks`] (its particles are one row).
    Strips,
    /// One per quad of the grid (two triangles); on a mesh, one per two triangles of the
    /// list.
    Quads,
    /// One per spring of the flat list.
    Springs,
    /// One per triangle.
    Triangles,
    /// One workgroup (a final reduction).
    Workgroup,
    /// One per [`WORKGROUP`] buckets of the self-collision hash (`hash_scan_blocks`).
    HashBlocks,
    /// One per pair of neighbours in a row (`n · ⌈n / 2⌉`: `self_collide`); on a mesh, of
    /// consecutive particles (`⌈particles / 2⌉`).
    Pairs,
    /// One per moving pin (`topo.pins.slots`).
    Pins,
    /// One per primitive of the contact between triangles: the triangles, then the edges.
    Primitives,
    /// One per bucket of the contact between triangles' two grids.
    TriBuckets,
    /// One per owner of the contact between triangles' pairs: the vertices, then the
    /// edges.
    TriOwners,
    /// As many as the dispatch's range says ([`crate::recipe::Command::Range`]: a mesh's
    /// XPBD pass); of the topology, the whole spring list.
    Range,
}

impl Count {
    /// How many invocations this is on `topo`.
    pub fn of(self, topo: &ClothTopology) -> u32 {
        match self {
            Count::Particles => topo.num_particles() as u32,
            Count::Blocks if topo.n == 0 => (topo.num_particles() as u32).div_ceil(BLOCK),
            Count::Blocks => topo.n * topo.n.div_ceil(BLOCK),
            Count::Strips if topo.n == 0 => (topo.num_particles() as u32).div_ceil(BLOCK),
            Count::Strips => topo.n.div_ceil(STRIP_ROWS) * topo.n.div_ceil(BLOCK),
            Count::Quads => topo.triangles.len().div_ceil(2) as u32,
            Count::Springs => topo.springs.len() as u32,
            Count::Triangles => topo.triangles.len() as u32,
            Count::Workgroup => WORKGROUP,
            Count::HashBlocks => cpu::self_collide::hash_blocks(topo.num_particles()),
            Count::Pairs if topo.n == 0 => (topo.num_particles() as u32).div_ceil(2),
            Count::Pairs => topo.n * topo.n.div_ceil(2),
            Count::Range => topo.springs.len() as u32,
            Count::Pins => topo.pins.slots.len() as u32,
            Count::Primitives => (topo.triangles.len() + topo.edges().len()) as u32,
            Count::TriBuckets => 2 * cpu::tri_contact::TriLayout::of(topo).grid_buckets() as u32,
            Count::TriOwners => (topo.num_particles() + topo.edges().len()) as u32,
        }
    }
}

/// Workgroups for `count` invocations, as a 2-D grid (x ≤ 65535).
pub fn groups(count: u32) -> (u32, u32) {
    let g = count.div_ceil(WORKGROUP).max(1);
    let x = g.min(65535);
    (x, g.div_ceil(x))
}

/// Where a kernel's WGSL comes from.
#[derive(Debug, Clone, Copy)]
pub enum Source {
    /// `shaders/wgsl/<name>.wgsl`, validated and compiled to SPIR-V when clothlab-shaders
    /// builds.
    Builtin,
    /// WGSL given at run time: `body` after `shared/types.wgsl`, the generated constants
    /// and the shared files named in `includes` (e.g. `["state"]`); compiled (naga to
    /// SPIR-V for Vulkan) when a backend first builds it.
    Wgsl {
        /// Shared files to put before the body.
        includes: &'static [&'static str],
        /// The kernel itself, entry point `main`.
        body: &'static str,
    },
}

/// Which twins `shaders/build.rs` generates for a kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Variants {
    /// `<name>_imm` and `<name>_sto`: the step constants from immediates (push
    /// constants), or from a storage buffer, instead of the uniform block.
    pub immediates: bool,
    /// `<name>_tex`: the spring table from a sampled image.
    pub table_image: bool,
    /// `<name>_f32`: float atomics instead of compare-exchange loops.
    pub float_atomics: bool,
    /// `<name>_cu`: the colliders from uniform blocks instead of storage buffers.
    pub colliders_uniform: bool,
    /// `<name>_sh`: the window's neighbours passed by subgroup shuffles.
    pub shuffle: bool,
    /// `<name>_si`: the bodies' distance fields sampled from a 3-D image (`sdf=image`).
    pub sdf_image: bool,
    /// `<name>_w`: every world of a batch in one dispatch ([`ConstantsHome::Worlds`];
    /// `//! worlds` in the kernel's WGSL).
    pub worlds: bool,
}

impl Variants {
    /// No generated twins: the kernel as written only.
    pub const NONE: Variants = PLAIN;
}

/// Where a shader reads the step constants from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ConstantsHome {
    /// The uniform block (`var<uniform>`, binding [`Buf::Params`]).
    #[default]
    Uniform,
    /// Immediates (push constants): the `_imm` twins.
    Immediates,
    /// A read-only storage buffer ([`Buf::ParamsStorage`]): the `_sto` twins.
    Storage,
    /// One element a world of an array in [`Buf::ParamsStorage`], the world the
    /// dispatch's z: the `_w` twins, which run every world of a batch in one dispatch
    /// (each world's particles, world after world, in the per-particle buffers). A single
    /// world's dispatch of it computes what the uniform block's shader computes (checked
    /// against the twin like every flavor).
    Worlds,
}

/// One concrete shader of a kernel: which of its variants it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Flavor {
    /// Where the step constants come from.
    pub constants: ConstantsHome,
    /// Spring table from an image.
    pub table_image: bool,
    /// Float atomics.
    pub float_atomics: bool,
    /// Colliders from uniform blocks.
    pub colliders_uniform: bool,
    /// Neighbours by subgroup shuffles.
    pub shuffle: bool,
    /// The bodies' fields from the 3-D image.
    pub sdf_image: bool,
}

impl Flavor {
    /// Every flavor there is (the registry keeps those a kernel has).
    pub fn all() -> Vec<Flavor> {
        let mut v = Vec::new();
        for constants in
            [ConstantsHome::Uniform, ConstantsHome::Immediates, ConstantsHome::Storage, ConstantsHome::Worlds]
        {
            for bits in 0..32u8 {
                v.push(Flavor {
                    constants,
                    table_image: bits & 1 != 0,
                    float_atomics: bits & 2 != 0,
                    colliders_uniform: bits & 4 != 0,
                    shuffle: bits & 8 != 0,
                    sdf_image: bits & 16 != 0,
                });
            }
        }
        v
    }
}

/// What a kernel's immediates (push constants) hold, apart from the `_imm` twins' step
/// constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Immediates {
    /// Nothing.
    None,
    /// The substep's index in the frame, a `u32` (the statistics kernels).
    Substep,
    /// The dispatch's range, `first` and `count` as two `u32`
    /// ([`crate::recipe::Command::Range`]).
    Range,
}

/// How a kernel named in a substep's order becomes dispatches on a cloth: the recipe
/// ([`crate::recipe::recipe_for`]) and the kernel tests ([`crate::validate`]) both expand
/// it by [`crate::recipe::Expander`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dispatches {
    /// One dispatch over its [`Count`].
    Once,
    /// A range per colour of the cloth's colouring, in colour order (VBD's sweep).
    Colours,
    /// Per colour, in colour order: `tri_vbd` over the contact's owners for the colour
    /// (its index as the range's `first`), then the kernel over the colour's range (VBD's
    /// sweep with the contact between triangles inside its solves).
    ColoursWithContact,
    /// A range over the contact's owners per colour, the colour's index as the range's
    /// `first` (`tri_vbd`).
    ContactColours,
    /// One range over every particle, the sweep's ω as the range's `first` (VBD's
    /// Chebyshev step after a sweep).
    Chebyshev,
    /// A workgroup per tile of the grid (the tiled substep).
    Tiles,
    /// A range per pass of a mesh's spring list sorted by pass
    /// (`MeshTables::xpbd_passes`).
    MeshPasses,
}

/// What a grid's kernel of a substep's order is on a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnMesh {
    /// Itself (it reads no grid coordinates).
    Same,
    /// This kernel in its place.
    Kernel(&'static KernelDef),
    /// Nothing: another's replacement runs its work (an XPBD pass after the first of an
    /// iteration: the mesh's passes run in the first's place).
    Nothing,
}

/// Which cloths a kernel runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cloths {
    /// Grids and meshes.
    Any,
    /// Only an n × n grid (it computes neighbours or colours from grid coordinates).
    Grid,
    /// Only a mesh.
    Mesh,
}

impl Cloths {
    /// Whether a kernel of this kind runs on `topo`.
    pub fn run_on(self, topo: &ClothTopology) -> bool {
        match self {
            Cloths::Any => true,
            Cloths::Grid => topo.mesh.is_none(),
            Cloths::Mesh => topo.mesh.is_some(),
        }
    }
}

/// How a kernel is checked against its twin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Check {
    /// Every buffer within `relative` of the largest magnitude in it, for `reason`.
    Bound {
        /// The bound, relative to the buffer's largest magnitude.
        relative: f32,
        /// Why this bound.
        reason: &'static str,
    },
    /// Checked by a test of its own (named), not by the kernel loop.
    Own(&'static str),
}

/// What a twin sees besides the buffers.
#[derive(Debug, Clone, Copy)]
pub struct TwinArgs<'a> {
    /// Serial or rayon loops (both give the same bits).
    pub exec: Exec,
    /// The step constants.
    pub p: &'a StepParams,
    /// Connectivity and spring tables.
    pub topo: &'a ClothTopology,
    /// The scene's spheres, boxes and bodies.
    pub colliders: cpu::Colliders<'a>,
    /// The substep's index in the frame.
    pub substep: u32,
    /// The dispatch's range (`first`, `count`) for a kernel of [`Count::Range`].
    pub range: (u32, u32),
}

/// The buffers the step writes, on the host: what the CPU engine runs on and what a GPU
/// runner uploads before and reads back after the commands it is given.
#[derive(Debug, Clone, PartialEq)]
pub struct HostBuffers {
    /// Current positions ([`Buf::Pos`]).
    pub pos: Vec<V4>,
    /// The other buffer of the pair ([`Buf::PosOut`]).
    pub pos_out: Vec<V4>,
    /// [`Buf::Vel`].
    pub vel: Vec<V4>,
    /// [`Buf::Force`].
    pub force: Vec<V4>,
    /// [`Buf::Normal`].
    pub normal: Vec<V4>,
    /// [`Buf::Faces`].
    pub faces: Vec<V4>,
    /// Per-substep statistics ([`Buf::StatsMax`] and [`Buf::StatsEnergy`]), by substep.
    pub stats: Vec<SubstepStats>,
    /// The integrators' scratch buffers ([`Buf::AUX`]), one element per particle.
    pub aux: Vec<Vec<V4>>,
    /// The conjugate-gradient scalars ([`Buf::Scalars`]): one element.
    pub scalars: Vec<V4>,
    /// The frame's pin poses ([`Buf::PinPoses`]): `clothlab_core::pins::frame_poses` as
    /// [`V4`]s, a block of `MAX_PIN_GROUPS` poses per substep (identities to start).
    pub pin_poses: Vec<V4>,
    /// The contact between triangles' start positions and bounds ([`Buf::TriFloats`]):
    /// empty until a kernel of that contact runs ([`HostBuffers::tri_sized`]).
    pub tri_floats: Vec<V4>,
    /// Its integers ([`Buf::TriInts`]), u32 words four to an element.
    pub tri_ints: Vec<V4>,
    /// Its pairs ([`Buf::TriPairs`]), u32 words four to an element.
    pub tri_pairs: Vec<V4>,
    /// The adjoint's planes ([`Buf::Adjoint`]): empty until an adjoint kernel runs
    /// ([`HostBuffers::adjoint_sized`]).
    pub adjoint: Vec<V4>,
}

impl HostBuffers {
    /// The buffers of `state` (`pos_out` a copy of `pos`) with face normals `faces`.
    pub fn new(state: &clothlab_core::ClothState, faces: Vec<V4>) -> Self {
        Self {
            pos: state.pos.clone(),
            pos_out: state.pos.clone(),
            vel: state.vel.clone(),
            force: state.force.clone(),
            normal: state.normal.clone(),
            faces,
            stats: Vec::new(),
            aux: vec![vec![[0.0; 4]; state.pos.len()]; Buf::AUX.len()],
            scalars: vec![[0.0; 4]],
            pin_poses: bytemuck::cast_slice(&clothlab_core::pins::frame_poses(
                &[],
                &[],
                Default::default(),
                0.0,
                0.0,
                1,
            ))
            .to_vec(),
            tri_floats: Vec::new(),
            tri_ints: Vec::new(),
            tri_pairs: Vec::new(),
            adjoint: Vec::new(),
        }
    }

    /// The adjoint's planes sized for `np` particles (zeroed where their size changes).
    pub fn adjoint_sized(&mut self, np: usize) {
        let len = clothlab_core::layout::ADJ_ROWS as usize * np;
        if self.adjoint.len() != len {
            self.adjoint = vec![[0.0; 4]; len];
        }
    }

    /// The contact between triangles' buffers sized for `l` (zeroed where their size
    /// changes): what its kernels and their twins run on.
    pub fn tri_sized(&mut self, l: cpu::tri_contact::TriLayout) {
        let sizes = [
            (&mut self.tri_floats, l.np),
            (&mut self.tri_ints, l.words().div_ceil(4)),
            (&mut self.tri_pairs, l.pair_words().div_ceil(4)),
        ];
        for (v, n) in sizes {
            if v.len() != n {
                *v = vec![[0.0; 4]; n];
            }
        }
    }

    /// The per-particle or per-face buffer `buf`, if it is one of these.
    pub fn get(&self, buf: Buf) -> Option<&Vec<V4>> {
        Some(match buf {
            Buf::Pos => &self.pos,
            Buf::PosOut => &self.pos_out,
            Buf::Vel => &self.vel,
            Buf::Force => &self.force,
            Buf::Normal => &self.normal,
            Buf::Faces => &self.faces,
            Buf::Scalars => &self.scalars,
            Buf::PinPoses => &self.pin_poses,
            Buf::TriFloats => &self.tri_floats,
            Buf::TriInts => &self.tri_ints,
            Buf::TriPairs => &self.tri_pairs,
            Buf::Adjoint => &self.adjoint,
            b => return Buf::AUX.iter().position(|a| *a == b).map(|k| &self.aux[k]),
        })
    }

    /// As [`HostBuffers::get`], mutably.
    pub fn get_mut(&mut self, buf: Buf) -> Option<&mut Vec<V4>> {
        Some(match buf {
            Buf::Pos => &mut self.pos,
            Buf::PosOut => &mut self.pos_out,
            Buf::Vel => &mut self.vel,
            Buf::Force => &mut self.force,
            Buf::Normal => &mut self.normal,
            Buf::Faces => &mut self.faces,
            Buf::Scalars => &mut self.scalars,
            Buf::PinPoses => &mut self.pin_poses,
            Buf::TriFloats => &mut self.tri_floats,
            Buf::TriInts => &mut self.tri_ints,
            Buf::TriPairs => &mut self.tri_pairs,
            Buf::Adjoint => &mut self.adjoint,
            b => return Buf::AUX.iter().position(|a| *a == b).map(|k| &mut self.aux[k]),
        })
    }

    /// Refuses buffers or constants of another grid than `topo`'s, or more colliders than
    /// a backend binds (what a GPU runner checks before uploading them).
    pub fn check(&self, topo: &ClothTopology, p: &StepParams) -> Result<(), clothlab_core::SolverError> {
        use clothlab_core::scene::MAX_COLLIDERS;
        if p.n != topo.n
            || p.num_spheres as usize > MAX_COLLIDERS
            || p.num_boxes as usize > MAX_COLLIDERS
            || p.num_rods as usize > clothlab_core::sdf::MAX_RODS
        {
            return Err(clothlab_core::SolverError::Invalid(
                "step constants for another grid or too many colliders".into(),
            ));
        }
        let np = topo.num_particles();
        let particles = [&self.pos, &self.pos_out, &self.vel, &self.force, &self.normal];
        if self.faces.len() != topo.triangles.len()
            || particles.into_iter().chain(&self.aux).any(|v| v.len() != np)
            || self.aux.len() != Buf::AUX.len()
            || self.scalars.len() != 1
            || self.pin_poses.is_empty()
            || !self.pin_poses.len().is_multiple_of(PinPose::V4S * MAX_PIN_GROUPS)
            || self.pin_poses.len() > PinPose::V4S * MAX_PIN_GROUPS * MAX_SUBSTEPS as usize
        {
            return Err(clothlab_core::SolverError::GridMismatch {
                want: topo.n,
                got: (self.pos.len() as f64).sqrt() as u32,
            });
        }
        Ok(())
    }

    /// The state these buffers hold.
    pub fn state(&self, n: u32) -> clothlab_core::ClothState {
        clothlab_core::ClothState {
            n,
            pos: self.pos.clone(),
            vel: self.vel.clone(),
            force: self.force.clone(),
            normal: self.normal.clone(),
        }
    }
}

/// A kernel's CPU twin: reads and writes the buffers as the kernel does.
pub type Twin = fn(&TwinArgs, &mut HostBuffers);

/// Recomputes, after a kernel test, the expected values of outputs that the kernel
/// derives from another output of its own (`got`, the runner's), into `want`.
pub type FromOutput = fn(&StepParams, &HostBuffers, &mut HostBuffers);

/// Everything about one kernel.
#[derive(Debug)]
pub struct KernelDef {
    /// File stem and shader name, e.g. `forces_springs`.
    pub name: &'static str,
    /// Where its WGSL comes from.
    pub source: Source,
    /// Its CPU twin.
    pub twin: Twin,
    /// What one dispatch runs over.
    pub count: Count,
    /// The bindings it reads (atomic read-modify-writes count as reads and writes).
    pub reads: &'static [Buf],
    /// The bindings it writes.
    pub writes: &'static [Buf],
    /// The outputs it writes in full without reading: poisoned with NaN before a kernel
    /// test, so an element it fails to write shows.
    pub pure: &'static [Buf],
    /// The buffers it adds into: a recipe clears them before it.
    pub accumulates: &'static [Buf],
    /// How it is checked against its twin.
    pub check: Check,
    /// Its row in the timing table.
    pub label: &'static str,
    /// Its generated variants.
    pub variants: Variants,
    /// What its immediates hold (besides the `_imm` twins' step constants).
    pub immediates: Immediates,
    /// Sets up a kernel test's input beyond the disturbed state (the naive normals kernel
    /// starts from the scatter's sums).
    pub test_input: Option<Twin>,
    /// Which cloths it runs on.
    pub cloths: Cloths,
    /// How it becomes dispatches on a cloth.
    pub dispatches: Dispatches,
    /// What it is on a mesh.
    pub on_mesh: OnMesh,
    /// For a kernel whose outputs depend on another of its outputs (counts of the
    /// positions it wrote): those expected from the runner's output, not the twin's (a
    /// last bit of a position may move a count by a whole particle).
    pub from_output: Option<FromOutput>,
    /// What it is where the contacts have Coulomb friction (the kernel with the friction
    /// terms), or `None`: itself.
    pub with_friction: Option<&'static KernelDef>,
}

impl PartialEq for KernelDef {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl Eq for KernelDef {}

impl KernelDef {
    /// Whether the kernel has the shader `flavor`.
    pub fn has(&self, f: Flavor) -> bool {
        let v = self.variants;
        (match f.constants {
            ConstantsHome::Uniform => true,
            ConstantsHome::Immediates | ConstantsHome::Storage => v.immediates,
            ConstantsHome::Worlds => v.worlds,
        }) && (!f.table_image || v.table_image)
            && (!f.float_atomics || v.float_atomics)
            && (!f.colliders_uniform || v.colliders_uniform)
            && (!f.shuffle || v.shuffle)
            && (!f.sdf_image || v.sdf_image)
            && !(f.table_image && f.float_atomics)
    }

    /// The closest flavor to `want` that the kernel has: each variant it lacks is left
    /// out, and a table image wins over float atomics (no kernel has both at once).
    pub fn flavor(&'static self, want: Flavor) -> KernelRef {
        let v = self.variants;
        let table_image = want.table_image && v.table_image;
        let flavor = Flavor {
            constants: match want.constants {
                ConstantsHome::Immediates | ConstantsHome::Storage if v.immediates => want.constants,
                ConstantsHome::Worlds if v.worlds => ConstantsHome::Worlds,
                _ => ConstantsHome::Uniform,
            },
            table_image,
            float_atomics: want.float_atomics && v.float_atomics && !table_image,
            colliders_uniform: want.colliders_uniform && v.colliders_uniform,
            shuffle: want.shuffle && v.shuffle,
            sdf_image: want.sdf_image && v.sdf_image,
        };
        KernelRef { def: self, flavor, uses: Uses::ALL }
    }

    /// The kernel in its plain flavor.
    pub fn plain(&'static self) -> KernelRef {
        KernelRef { def: self, flavor: Flavor::default(), uses: Uses::ALL }
    }

    /// Every flavor the kernel has.
    pub fn flavors(&'static self) -> Vec<KernelRef> {
        Flavor::all()
            .into_iter()
            .filter(|f| self.has(*f))
            .map(|flavor| KernelRef { def: self, flavor, uses: Uses::ALL })
            .collect()
    }

    /// Whether it writes the other buffer of the position pair (a recipe swaps the pair
    /// after it).
    pub fn swaps(&self) -> bool {
        self.writes.contains(&Buf::PosOut)
    }
}

/// One shader: a kernel in one flavor. What recipes dispatch and backends build pipelines
/// for.
#[derive(Debug, Clone, Copy)]
pub struct KernelRef {
    /// The kernel.
    pub def: &'static KernelDef,
    /// Which of its variants.
    pub flavor: Flavor,
    /// What of the collider walk's code it keeps (`specialize=on`: the scene's
    /// [`Uses::of`]; [`Uses::ALL`], the built shader, otherwise).
    pub uses: Uses,
}

impl PartialEq for KernelRef {
    fn eq(&self, other: &Self) -> bool {
        self.def.name == other.def.name && self.flavor == other.flavor && self.uses == other.uses
    }
}

impl Eq for KernelRef {}

impl Hash for KernelRef {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.def.name.hash(state);
        self.flavor.hash(state);
        self.uses.hash(state);
    }
}

impl std::fmt::Display for KernelRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.shader_name())
    }
}

impl KernelRef {
    /// The shader's name: `<name>[_f32][_tex][_cu][_si][_sh][_imm|_sto|_w]`, as
    /// shaders/build.rs names the twins.
    pub fn shader_name(&self) -> String {
        let f = self.flavor;
        format!(
            "{}{}{}{}{}{}{}",
            self.def.name,
            if f.float_atomics { "_f32" } else { "" },
            if f.table_image { "_tex" } else { "" },
            if f.colliders_uniform { "_cu" } else { "" },
            if f.sdf_image { "_si" } else { "" },
            if f.shuffle { "_sh" } else { "" },
            match f.constants {
                ConstantsHome::Uniform => "",
                ConstantsHome::Immediates => "_imm",
                ConstantsHome::Storage => "_sto",
                ConstantsHome::Worlds => "_w",
            }
        )
    }

    /// The name reports give it: [`KernelRef::shader_name`], and for a kernel specialised
    /// to a scene what it keeps (`integrate_collide_imm[uses: motion]`, `[uses: none]`),
    /// so that a validation's rows tell the built kernel and its specialisation apart.
    pub fn report_name(&self) -> String {
        if self.uses == Uses::ALL {
            return self.shader_name();
        }
        format!("{}[uses: {}]", self.shader_name(), self.uses.kept())
    }

    /// Whether the shader reads the step constants from immediates.
    pub fn step_immediates(&self) -> bool {
        self.flavor.constants == ConstantsHome::Immediates
    }

    /// This kernel specialised to `uses` (see [`KernelRef::uses`]).
    pub fn with_uses(self, uses: Uses) -> KernelRef {
        KernelRef { uses, ..self }
    }

    /// Whether its shader is compiled when it is built (a kernel given as WGSL at run
    /// time, or one specialised to a scene), not taken from what the build compiled.
    fn compiled_at_run_time(&self) -> bool {
        matches!(self.def.source, Source::Wgsl { .. }) || self.uses != Uses::ALL
    }

    /// The complete WGSL (specialised: the prelude's `USES_*` constants set to
    /// [`KernelRef::uses`]).
    pub fn wgsl(&self) -> Result<Cow<'static, str>, EngineError> {
        let general = match self.def.source {
            Source::Builtin => Cow::Borrowed(self.builtin()?.wgsl),
            Source::Wgsl { includes, body } => {
                Cow::Owned(clothlab_shaders::compose(includes, body).map_err(|e| self.error(e))?)
            }
        };
        if self.uses == Uses::ALL {
            return Ok(general);
        }
        let all = Uses::ALL.wgsl();
        if !general.contains(&all) {
            return Err(self.error("its WGSL lacks the prelude's USES_* constants to specialise".into()));
        }
        Ok(Cow::Owned(general.replacen(&all, &self.uses.wgsl(), 1)))
    }

    /// SPIR-V 1.3, little-endian words as bytes.
    pub fn spirv(&self) -> Result<Cow<'static, [u8]>, EngineError> {
        match self.def.source {
            Source::Builtin if !self.compiled_at_run_time() => Ok(Cow::Borrowed(self.builtin()?.spirv)),
            _ => {
                let wgsl = self.wgsl()?;
                let words = clothlab_shaders::compile_spirv(self.def.name, &wgsl).map_err(|e| self.error(e))?;
                Ok(Cow::Owned(words.iter().flat_map(|w| w.to_le_bytes()).collect()))
            }
        }
    }

    /// GLSL 4.50 core for OpenGL with where its bindings go and its immediates' uniforms
    /// (see [`clothlab_shaders::Kernel::gl_points`] and `gl_uniforms`).
    pub fn glsl(&self) -> Result<Glsl, EngineError> {
        match self.def.source {
            Source::Builtin if !self.compiled_at_run_time() => {
                let k = self.builtin()?;
                Ok(Glsl {
                    text: Cow::Borrowed(k.glsl),
                    points: k.gl_points.to_vec(),
                    uniforms: k.gl_uniforms.iter().map(|&(n, o, c, w)| (n.to_string(), o, c, w)).collect(),
                })
            }
            _ => {
                let wgsl = self.wgsl()?;
                let (text, points, uniforms) =
                    clothlab_shaders::compile_glsl(self.def.name, &wgsl).map_err(|e| self.error(e))?;
                Ok(Glsl { text: Cow::Owned(text), points, uniforms })
            }
        }
    }

    fn builtin(&self) -> Result<&'static clothlab_shaders::Kernel, EngineError> {
        clothlab_shaders::kernel(&self.shader_name())
            .ok_or_else(|| self.error(format!("no shader {} in clothlab-shaders", self.shader_name())))
    }

    fn error(&self, reason: String) -> EngineError {
        EngineError::Shader { kernel: self.shader_name(), reason }
    }
}

/// A kernel's GLSL for OpenGL ([`KernelRef::glsl`]).
#[derive(Debug, Clone)]
pub struct Glsl {
    /// The GLSL 4.50 core text.
    pub text: Cow<'static, str>,
    /// `(@binding, GL binding point)`, each kind numbered from 0.
    pub points: Vec<(u32, u8)>,
    /// The immediates as uniforms: `(name, byte offset, 'u' | 'i' | 'f', components)`.
    pub uniforms: Vec<(String, u32, char, u8)>,
}

/// The bytes `k` must move at least once per dispatch on `topo` (its compulsory
/// traffic): every buffer its row reads or writes, once, at its size — the spring table
/// from the image in a `_tex` flavor, from the storage buffers otherwise, and not at all
/// when `table_uniform` (the regular grid's constants in the uniform block). Neighbour
/// loads that a cache serves are not counted: what `clothlab bench --ladder` divides by
/// a kernel's time to say how close it runs to the memory's bandwidth.
pub fn compulsory_bytes(k: KernelRef, topo: &ClothTopology, table_uniform: bool) -> u64 {
    use clothlab_core::grid::{SLOTS, STRAIN_SLOTS, TETHER_SLOTS};
    let np = topo.num_particles() as u64;
    let tris = topo.triangles.len() as u64;
    let springs = topo.springs.len() as u64;
    let entries = topo.slots.entries().len() as u64;
    let table = |b: Buf| match b {
        Buf::Slots | Buf::BendSlots if k.flavor.table_image || table_uniform => 0,
        // A mesh's self-collision response reads the table only for the few particles in
        // contact.
        Buf::Slots | Buf::BendSlots if k.def == &SELF_COLLIDE_MESH => 0,
        Buf::Table if !k.flavor.table_image => 0,
        // A mesh's table: its rows split between the two bindings.
        Buf::Slots if topo.mesh.is_some() => crate::tables::mesh_split(topo) as u64 * 16,
        Buf::BendSlots if topo.mesh.is_some() => (entries - crate::tables::mesh_split(topo) as u64) * 16,
        Buf::Slots => np * STRAIN_SLOTS as u64 * 16,
        Buf::BendSlots => np * (SLOTS - STRAIN_SLOTS) as u64 * 16,
        Buf::Table => entries * 16,
        _ => 0,
    };
    let size = |b: Buf| -> u64 {
        match b {
            Buf::Pos | Buf::PosOut | Buf::Vel | Buf::Force | Buf::Normal => np * 16,
            Buf::Aux0 | Buf::Aux1 | Buf::Aux2 | Buf::Aux3 | Buf::Aux4 => np * 16,
            Buf::Scalars => 16,
            Buf::Faces => tris * 16,
            Buf::Triangles => tris * 12,
            Buf::FaceSlots => topo.face_slots.entries().len() as u64 * 4,
            // A grid's kernels never read it; a mesh's read their particle's and the next.
            Buf::Adjacency if topo.mesh.is_some() => (np + 1) * 16,
            Buf::Colours => np * 4,
            Buf::Pins => topo.pins.slots.len() as u64 * 32,
            Buf::PinPoses => MAX_PIN_GROUPS as u64 * 96,
            Buf::Tethers => np * TETHER_SLOTS as u64 * 8,
            Buf::Springs | Buf::SpringsB => springs / 2 * 24,
            Buf::Slots | Buf::BendSlots | Buf::Table => table(b),
            _ => 0,
        }
    };
    k.def.reads.iter().chain(k.def.writes).map(|&b| size(b)).sum()
}

/// The reduction's work is done by `stats`' twin, which reduces on the spot.
fn nothing(_: &TwinArgs, _: &mut HostBuffers) {}

// ---- what the rows are made of ----------------------------------------------------------

use Buf::*;

// The scratch buffers by role, as the rows name them: each is one of `Aux0..Aux4`, and
// the roles that share a buffer never hold live data at once (`Buf::Aux0`'s doc).
/// The strain limit's counts of stretched springs per particle.
const STRAIN_COUNTS: Buf = Aux0;
/// XPBD's λ per spring, in two buffers (cleared before an iteration's first pass of a
/// substep: [`crate::recipe::lambda_clears`]).
pub const LAMBDA: [Buf; 2] = [Aux0, Aux1];
/// The self-collision hash: per-cell counts, then the cells' starts.
const HASH_CELLS: Buf = Aux2;
/// The hash: the blocks' totals of the counts.
const HASH_TOTALS: Buf = Aux3;
/// The hash: the particles sorted by cell.
const HASH_SLOTS: Buf = Aux4;
/// The velocities' copy for self-collision's friction.
const VEL_COPY: Buf = Aux0;
/// The tiled substep's new velocities.
const TILE_NEW_VEL: Buf = Aux0;
/// VBD: the predicted velocity v′, the substep's start x⁰, the displacement D, and the
/// Chebyshev step's last two displacements.
const VBD_PREDICTED: Buf = Aux0;
const VBD_START: Buf = Aux1;
const VBD_DISPLACEMENT: Buf = Aux2;
const VBD_LAST: Buf = Aux3;
const VBD_BEFORE: Buf = Aux4;
/// RK: x₀, v₀, Σ bₛvₛ, Σ bₛaₛ·dt, the substep's wind force.
const RK_X0: Buf = Aux0;
const RK_V0: Buf = Aux1;
const RK_SUM_V: Buf = Aux2;
const RK_SUM_A: Buf = Aux3;
const RK_WIND: Buf = Aux4;
/// Implicit Euler's CG: Δv, r, p, q = A p, and the reductions' sums per workgroup.
const CG_DV: Buf = Aux0;
const CG_R: Buf = Aux1;
const CG_P: Buf = Aux2;
const CG_Q: Buf = Aux3;
const CG_SUMS: Buf = Aux4;

/// Per-element kernels: a handful of f32 operations, each within the few ulps Vulkan
/// allows for division and square root (2.5–3 ulp), plus FMA contraction.
const ELEMENT: Check = Check::Bound {
    relative: 1e-5,
    reason: "a handful of f32 operations per element, each within Vulkan's 2.5–3 ulp, plus FMA contraction",
};
/// Gathers over up to 12 springs (and the tethers): more operations per element.
const GATHER: Check = Check::Bound { relative: 2e-5, reason: "a gather over up to 12 springs: more operations" };
/// The spring gather plus the wind of six faces computed in it: a few dozen more
/// operations per particle, no more cancellation (measured on lavapipe: exact).
const WIND_GATHER: Check = Check::Bound {
    relative: 2e-5,
    reason: "a gather over up to 12 springs plus six faces' wind computed in it (lavapipe: exact)",
};
/// The tiled substep: six stages from a disturbed state, where most springs are over the
/// strain limit: a spring a last bit over its limit on one side and under on the other is
/// corrected by its whole excess in one of them, and the second pass divides by counts
/// that moved (the H100, 2026-11-26: 1.0e-7 with no pass, 1.5e-7 with one, 2.2e-4 with
/// two; a rollout from the scene stays within 2.4e-7 m). Exact on lavapipe
/// (tests/tests/suite/tile.rs).
const TILE_CHECK: Check = Check::Bound {
    relative: 1e-3,
    reason: "forces, integrate and strain passes fused from a disturbed state: a spring's limit decided otherwise in a last bit moves a whole correction (H100, two passes: 2.2e-4; one: 1.5e-7; lavapipe: exact)",
};
/// Atomic scatters: any summation order, and spring forces cancel, so rounding is
/// amplified (measured on lavapipe: ≤ 1.4e-7).
const SCATTER: Check = Check::Bound {
    relative: 1e-5,
    reason: "atomic adds in any order over cancelling spring forces (lavapipe: ≤ 1.4e-7)",
};
const STATS_TEST: Check = Check::Own("gpu_statistics_match_the_cpu_twin_by_subgroups_and_by_atomics");

const STATE: &[Buf] = &[Params, Pos, Vel, Force];
/// The gathers' reads: the state and the spring table (storage buffers, or the image in
/// the `_tex` twins, or the uniform block for the regular grid).
const TABLE: &[Buf] = &[Params, Pos, Vel, Force, Slots, BendSlots, Adjacency, Interior, Table];
const COLLIDERS: &[Buf] = &[Params, Pos, Vel, Spheres, Boxes, Shapes];
const NONE: &[Buf] = &[];

impl KernelDef {
    /// A row of built-in WGSL (`shaders/wgsl/{name}.wgsl`) whose other fields take their
    /// plainest values: checked element by element, its own timing row, the `_imm` twin
    /// only, no immediates, on any cloth, one dispatch over `count`, nothing in another's
    /// place. A row writes what differs and takes the rest from here
    /// (`KernelDef { check: …, ..KernelDef::new(…) }`), so that a field added to the row
    /// later leaves it as it was.
    pub const fn new(
        name: &'static str,
        twin: Twin,
        count: Count,
        reads: &'static [Buf],
        writes: &'static [Buf],
    ) -> KernelDef {
        KernelDef {
            name,
            source: Source::Builtin,
            twin,
            count,
            reads,
            writes,
            pure: NONE,
            accumulates: NONE,
            check: ELEMENT,
            label: name,
            variants: Variants { immediates: true, ..PLAIN },
            immediates: Immediates::None,
            test_input: None,
            cloths: Cloths::Any,
            dispatches: Dispatches::Once,
            on_mesh: OnMesh::Same,
            with_friction: None,
            from_output: None,
        }
    }
}

const PLAIN: Variants = Variants {
    immediates: false,
    table_image: false,
    float_atomics: false,
    colliders_uniform: false,
    shuffle: false,
    sdf_image: false,
    worlds: false,
};
const IMM_TEX: Variants = Variants { immediates: true, table_image: true, ..PLAIN };
const IMM_F32: Variants = Variants { immediates: true, float_atomics: true, ..PLAIN };
const IMM_CU: Variants = Variants { immediates: true, colliders_uniform: true, sdf_image: true, ..PLAIN };
/// The blocked gathers: the table's homes, and shuffles for the window.
const BLOCKED: Variants = Variants { shuffle: true, ..IMM_TEX };

/// `v` and the `_w` twins (a kernel whose WGSL says `//! worlds`).
const fn worlds(v: Variants) -> Variants {
    Variants { worlds: true, ..v }
}

mod adjoint;
mod cg;
mod forces;
mod normals;
mod rk;
mod self_collision;
mod stats;
mod strain;
mod tile;
mod tri_contact;
mod vbd;
mod xpbd;

pub use adjoint::*;
pub use cg::*;
pub use forces::*;
pub use normals::*;
pub use rk::*;
pub use self_collision::*;
pub use stats::*;
pub use strain::*;
pub use tile::*;
pub use tri_contact::*;
pub use vbd::*;
pub use xpbd::*;

/// Every family's kernels, in the order the registry lists them: a new kernel is a row in
/// its family's file and an entry in that family's `ROWS`, nothing here.
const FAMILIES: &[&[&KernelDef]] = &[
    forces::ROWS,
    strain::ROWS,
    normals::ROWS,
    stats::ROWS,
    rk::ROWS,
    xpbd::ROWS,
    vbd::ROWS,
    cg::ROWS,
    self_collision::ROWS,
    tile::ROWS,
    tri_contact::ROWS,
    adjoint::ROWS,
];

/// How many kernels the families hold.
const fn count(families: &[&[&KernelDef]]) -> usize {
    let (mut n, mut i) = (0, 0);
    while i < families.len() {
        n += families[i].len();
        i += 1;
    }
    n
}

/// The families' kernels in one array.
const fn join<const N: usize>(families: &[&[&'static KernelDef]]) -> [&'static KernelDef; N] {
    let mut out: [&'static KernelDef; N] = [&PINS; N];
    let (mut i, mut at) = (0, 0);
    while i < families.len() {
        let mut j = 0;
        while j < families[i].len() {
            out[at] = families[i][j];
            at += 1;
            j += 1;
        }
        i += 1;
    }
    out
}

/// Every built-in kernel of the step, joined from the families.
pub static ALL: [&KernelDef; count(FAMILIES)] = join(FAMILIES);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_is_timed_under_a_label_of_the_one_list_in_core() {
        // core::timing::KERNEL_LABELS orders the reports' rows and is what the CPU solvers
        // time under; a row with a label outside it would be a second spelling.
        for def in ALL {
            assert!(
                timing::KERNEL_LABELS.contains(&def.label),
                "{}: label `{}` is not in KERNEL_LABELS",
                def.name,
                def.label
            );
        }
    }

    #[test]
    fn every_flavor_of_every_kernel_is_built_and_declares_only_bindings_the_table_names() {
        let mut seen = 0;
        for def in ALL {
            for k in def.flavors() {
                let shader = clothlab_shaders::kernel(&k.shader_name()).unwrap_or_else(|| {
                    panic!("{k}: the registry says it exists, the shaders build has no such shader")
                });
                // What naga finds the shader reading and writing is what the row says, so
                // the barriers derived from the row are the ones the shader needs. (A row
                // may name more reads than one flavor makes: the table's three homes.)
                for (what, used, declared) in
                    [("reads", shader.reads, def.reads), ("writes", shader.writes, def.writes)]
                {
                    for &b in used {
                        // (A second home of a buffer's data counts as the buffer.)
                        let buf = Buf::from_binding(b).expect("build.rs checks the binding numbers").data();
                        assert!(
                            declared.contains(&buf),
                            "{k} {what} {buf:?} (binding {b}), which its row does not say"
                        );
                    }
                }
                for &w in def.writes {
                    assert!(
                        shader.writes.contains(&w.binding()),
                        "{k}: its row says it writes {w:?}, the shader does not"
                    );
                }
                for w in def.pure.iter().chain(def.accumulates) {
                    assert!(def.writes.contains(w), "{k}: pure or accumulated {w:?} not among its writes");
                }
                seen += 1;
            }
        }
        // And the other way: every shader the build made belongs to a row (or is chain,
        // the overhead benchmark's, or render).
        let names: Vec<String> = ALL.iter().flat_map(|d| d.flavors()).map(|k| k.shader_name()).collect();
        for k in clothlab_shaders::KERNELS {
            assert!(
                names.iter().any(|n| n == k.name) || k.name == "chain" || k.name == "render",
                "shader {} has no row in the registry",
                k.name
            );
        }
        assert_eq!(seen, names.len());
    }

    #[test]
    fn flavors_fall_back_to_what_a_kernel_has() {
        let want = Flavor {
            constants: ConstantsHome::Immediates,
            table_image: true,
            float_atomics: true,
            colliders_uniform: true,
            shuffle: true,
            sdf_image: true,
        };
        assert_eq!(FORCES_SPRINGS.flavor(want).shader_name(), "forces_springs_tex_sh_imm");
        assert_eq!(SPRINGS_SCATTER.flavor(want).shader_name(), "springs_scatter_f32_imm");
        assert_eq!(STATS_REDUCE.flavor(want).shader_name(), "stats_reduce");
        assert_eq!(
            STATS_ATOMIC.flavor(Flavor { float_atomics: true, ..Flavor::default() }).shader_name(),
            "stats_atomic_f32"
        );
        assert_eq!(INTEGRATE_COLLIDE.flavor(want).shader_name(), "integrate_collide_cu_si_imm");
        let sto = Flavor { constants: ConstantsHome::Storage, ..Flavor::default() };
        assert_eq!(STRAIN_LIMIT.flavor(sto).shader_name(), "strain_limit_sto");
        assert_eq!(STATS.flavor(sto).shader_name(), "stats", "the statistics kernels use immediates for the substep");
        assert_eq!(groups(64 * 65535 + 1), (65535, 2));
    }
}
