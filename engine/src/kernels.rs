//! The kernel registry: one [`KernelDef`] per kernel says everything about it — its WGSL,
//! its CPU twin, what it runs over, the bindings it reads and writes, its pure outputs
//! (poisoned before a kernel test), the buffers it accumulates into (cleared before it),
//! its validation bound with the reason, its timing label and its variants. Recipes,
//! barriers, validation, the CLI's listings and the backends read this table; nothing
//! else matches on a kernel's name.
//!
//! A kernel from outside the crate is a `static KernelDef` with [`Source::Wgsl`]: its WGSL
//! is compiled when a backend first needs it (see `tests/tests/suite/custom_kernel.rs`).

use std::borrow::Cow;
use std::hash::{Hash, Hasher};

use clothlab_core::cpu::{self, Exec, SubstepStats};
use clothlab_core::grid::{ClothTopology, StepParams, V4};
use clothlab_core::layout::{BLOCK, Buf, WORKGROUP};
use clothlab_core::params::MAX_SUBSTEPS;
use clothlab_core::pins::{MAX_PIN_GROUPS, PinPose};
use clothlab_core::timing;

use crate::EngineError;

/// What a dispatch runs over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// One invocation per particle.
    Particles,
    /// One per [`BLOCK`] consecutive particles of a row: `n · ⌈n / BLOCK⌉` on a grid, a
    /// mesh's particles as one row (`⌈particles / BLOCK⌉`).
    Blocks,
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
            Count::Quads => topo.triangles.len().div_ceil(2) as u32,
            Count::Springs => topo.springs.len() as u32,
            Count::Triangles => topo.triangles.len() as u32,
            Count::Workgroup => WORKGROUP,
            Count::HashBlocks => cpu::self_collide::hash_blocks(topo.num_particles()),
            Count::Pairs if topo.n == 0 => (topo.num_particles() as u32).div_ceil(2),
            Count::Pairs => topo.n * topo.n.div_ceil(2),
            Count::Range => topo.springs.len() as u32,
            Count::Pins => topo.pins.slots.len() as u32,
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
        for constants in [ConstantsHome::Uniform, ConstantsHome::Immediates, ConstantsHome::Storage] {
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
            || p.num_capsules as usize > clothlab_core::sdf::MAX_CAPSULES
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
        (f.constants == ConstantsHome::Uniform || v.immediates)
            && (!f.table_image || v.table_image)
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
            constants: if v.immediates { want.constants } else { ConstantsHome::Uniform },
            table_image,
            float_atomics: want.float_atomics && v.float_atomics && !table_image,
            colliders_uniform: want.colliders_uniform && v.colliders_uniform,
            shuffle: want.shuffle && v.shuffle,
            sdf_image: want.sdf_image && v.sdf_image,
        };
        KernelRef { def: self, flavor }
    }

    /// The kernel in its plain flavor.
    pub fn plain(&'static self) -> KernelRef {
        KernelRef { def: self, flavor: Flavor::default() }
    }

    /// Every flavor the kernel has.
    pub fn flavors(&'static self) -> Vec<KernelRef> {
        Flavor::all().into_iter().filter(|f| self.has(*f)).map(|flavor| KernelRef { def: self, flavor }).collect()
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
}

impl PartialEq for KernelRef {
    fn eq(&self, other: &Self) -> bool {
        self.def.name == other.def.name && self.flavor == other.flavor
    }
}

impl Eq for KernelRef {}

impl Hash for KernelRef {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.def.name.hash(state);
        self.flavor.hash(state);
    }
}

impl std::fmt::Display for KernelRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.shader_name())
    }
}

impl KernelRef {
    /// The shader's name: `<name>[_f32][_tex][_cu][_si][_sh][_imm|_sto]`, as
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
            }
        )
    }

    /// Whether the shader reads the step constants from immediates.
    pub fn step_immediates(&self) -> bool {
        self.flavor.constants == ConstantsHome::Immediates
    }

    /// The complete WGSL.
    pub fn wgsl(&self) -> Result<Cow<'static, str>, EngineError> {
        match self.def.source {
            Source::Builtin => Ok(Cow::Borrowed(self.builtin()?.wgsl)),
            Source::Wgsl { includes, body } => {
                clothlab_shaders::compose(includes, body).map(Cow::Owned).map_err(|e| self.error(e))
            }
        }
    }

    /// SPIR-V 1.3, little-endian words as bytes.
    pub fn spirv(&self) -> Result<Cow<'static, [u8]>, EngineError> {
        match self.def.source {
            Source::Builtin => Ok(Cow::Borrowed(self.builtin()?.spirv)),
            Source::Wgsl { .. } => {
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
            Source::Builtin => {
                let k = self.builtin()?;
                Ok(Glsl {
                    text: Cow::Borrowed(k.glsl),
                    points: k.gl_points.to_vec(),
                    uniforms: k.gl_uniforms.iter().map(|&(n, o, c, w)| (n.to_string(), o, c, w)).collect(),
                })
            }
            Source::Wgsl { .. } => {
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
        Buf::Slots | Buf::BendSlots if k.def.name == "self_collide_mesh" => 0,
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

// ---- the twins ---------------------------------------------------------------------

fn forces(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::forces(a.exec, a.p, &b.pos, &b.vel, &mut b.force);
}

fn springs(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::springs(a.exec, &a.topo.slots, &b.pos, &b.vel, &mut b.force);
}

fn forces_springs(a: &TwinArgs, b: &mut HostBuffers) {
    forces(a, b);
    springs(a, b);
}

/// The wind of the faces around each particle, computed from the positions as
/// `tri_normals` and `vertex_normals` compute it, then `forces_springs` from it: the force
/// the three kernels leave, without the face and vertex normals (the kernel keeps those in
/// registers).
fn forces_springs_wind(a: &TwinArgs, b: &mut HostBuffers) {
    let mut faces = vec![[0.0; 4]; a.topo.triangles.len()];
    cpu::tri_normals(a.exec, &a.topo.triangles, &b.pos, &mut faces);
    let mut normal = vec![[0.0; 4]; b.pos.len()];
    cpu::vertex_normals(a.exec, a.p, &a.topo.face_slots, &faces, &mut normal, &mut b.force);
    forces_springs(a, b);
}

fn springs_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::springs_scatter(&a.topo.springs, &b.pos, &b.vel, &mut b.force);
}

fn integrate(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::integrate(a.exec, a.p, &b.force, &mut b.pos, &mut b.vel);
}

fn pins(a: &TwinArgs, b: &mut HostBuffers) {
    let poses: &[PinPose] = bytemuck::cast_slice(&b.pin_poses);
    clothlab_core::pins::drive(&a.topo.pins.slots, poses, a.substep, &mut b.pos, &mut b.vel);
}

fn collide(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::collide(a.exec, a.p, a.colliders, &mut b.pos, &mut b.vel);
}

fn integrate_collide(a: &TwinArgs, b: &mut HostBuffers) {
    integrate(a, b);
    collide(a, b);
}

/// The fused kernel keeps the total force in a register: the force buffer is left as the
/// springs left it.
fn forces_integrate_collide(a: &TwinArgs, b: &mut HostBuffers) {
    let springs = b.force.clone();
    forces(a, b);
    integrate_collide(a, b);
    b.force = springs;
}

/// The tiled substep (`fusion=tile`): what forces_springs_wind, integrate_collide and
/// `strain_passes` × (strain_count, strain_limit) leave, `tile_substeps` times — the new
/// positions in the other buffer of the pair, the new velocities in aux0; the positions,
/// velocities and forces it read untouched (it keeps the forces and counts in
/// workgroup memory).
fn substep_tile(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, vel, force) = (b.pos.clone(), b.vel.clone(), b.force.clone());
    for _ in 0..a.p.tile_substeps.max(1) {
        forces_springs_wind(a, b);
        integrate_collide(a, b);
        for _ in 0..a.p.strain_passes {
            strain_count(a, b);
            strain_limit(a, b);
            std::mem::swap(&mut b.pos, &mut b.pos_out);
        }
    }
    b.aux[0] = b.vel.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
    b.pos_out = std::mem::replace(&mut b.pos, pos);
    b.vel = vel;
    b.force = force;
}

/// The tiled substep's velocities (aux0) into place.
fn tile_vel(_: &TwinArgs, b: &mut HostBuffers) {
    b.vel = b.aux[0].clone();
}

/// The counts as the kernel leaves them in aux0: `(count, 0, 0, 0)` per particle.
fn strain_count(a: &TwinArgs, b: &mut HostBuffers) {
    let mut counts = vec![0.0; b.pos.len()];
    cpu::strain_count(a.exec, a.p, &a.topo.slots, &b.pos, &mut counts);
    b.aux[0] = counts.into_iter().map(|c| [c, 0.0, 0.0, 0.0]).collect();
}

fn strain_limit(a: &TwinArgs, b: &mut HostBuffers) {
    let counts: Vec<f32> = b.aux[0].iter().map(|c| c[0]).collect();
    cpu::strain_limit(a.exec, a.p, &a.topo.slots, &a.topo.tethers, &b.pos, &counts, &mut b.pos_out);
    cpu::strain_vel(a.exec, a.p, &b.pos, &b.pos_out, &mut b.vel);
}

/// The strain limit's pass, then its output counted into the self-collision hash (the
/// count's twin on the pass's output).
fn strain_limit_count(a: &TwinArgs, b: &mut HostBuffers) {
    strain_limit(a, b);
    std::mem::swap(&mut b.pos, &mut b.pos_out);
    hash_count(a, b);
    std::mem::swap(&mut b.pos, &mut b.pos_out);
}

fn tri_normals(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::tri_normals(a.exec, &a.topo.triangles, &b.pos, &mut b.faces);
}

/// Adds every vertex's adjacent face normals into its normal (what the naive scatter
/// accumulates; the recipe clears the normals first).
fn add_face_sums(a: &TwinArgs, b: &mut HostBuffers) {
    for (i, n) in b.normal.iter_mut().enumerate() {
        for &t in a.topo.face_slots.row(i).iter().filter(|&&t| t >= 0) {
            let f = b.faces[t as usize];
            n.iter_mut().zip(f).take(3).for_each(|(x, y)| *x += y);
        }
    }
}

fn tri_normals_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    tri_normals(a, b);
    add_face_sums(a, b);
}

/// The naive normals kernel's input: the scatter's sums of the current faces.
fn face_sums_input(a: &TwinArgs, b: &mut HostBuffers) {
    b.normal.iter_mut().for_each(|n| *n = [0.0; 4]);
    add_face_sums(a, b);
}

fn vertex_normals(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vertex_normals(a.exec, a.p, &a.topo.face_slots, &b.faces, &mut b.normal, &mut b.force);
}

fn stats(a: &TwinArgs, b: &mut HostBuffers) {
    let k = a.substep as usize;
    if b.stats.len() <= k {
        b.stats.resize(k + 1, SubstepStats { max_strain: 0.0, kinetic_energy: 0.0 });
    }
    b.stats[k] = cpu::substep_stats(a.p, &a.topo.slots, &b.pos, &b.vel);
}

fn euler(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::euler(a.exec, a.p, &b.force, &mut b.pos, &mut b.vel);
}

fn rk_begin(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::rk_begin(a.exec, a.p, &b.force, &b.pos, &mut b.vel, &mut b.aux);
}

fn rk_stage(a: &TwinArgs, b: &mut HostBuffers, st: &cpu::RkStage) {
    cpu::rk_stage(a.exec, a.p, st, &mut b.force, &mut b.pos, &mut b.vel, &mut b.aux);
}

fn rk2_1(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK2[0]);
}

fn rk2_2(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK2[1]);
}

fn rk4_1(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[0]);
}

fn rk4_2(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[1]);
}

fn rk4_3(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[2]);
}

fn rk4_4(a: &TwinArgs, b: &mut HostBuffers) {
    rk_stage(a, b, &cpu::RK4[3]);
}

/// The twins of the 12 XPBD passes (core::cpu::XPBD_PASSES).
macro_rules! xpbd_twins {
    ($($name:ident = $k:expr),*) => {
        $(fn $name(a: &TwinArgs, b: &mut HostBuffers) {
            cpu::xpbd_pass(a.p, &a.topo.slots, $k, &mut b.pos, &mut b.vel, &mut b.aux);
        })*
    };
}
xpbd_twins!(
    xpbd_0 = 0,
    xpbd_1 = 1,
    xpbd_2 = 2,
    xpbd_3 = 3,
    xpbd_4 = 4,
    xpbd_5 = 5,
    xpbd_6 = 6,
    xpbd_7 = 7,
    xpbd_8 = 8,
    xpbd_9 = 9,
    xpbd_10 = 10,
    xpbd_11 = 11
);

/// A mesh's XPBD pass over springs `first .. first + count`, λ of spring k in word k of
/// aux0 then aux1 (as the kernel keeps them).
fn xpbd_mesh(a: &TwinArgs, b: &mut HostBuffers) {
    let np = b.pos.len();
    let mut lambda: Vec<f32> = b.aux[0].iter().chain(&b.aux[1]).flatten().copied().collect();
    let (first, count) = (a.range.0 as usize, a.range.1 as usize);
    let end = (first + count).min(a.topo.springs.len());
    cpu::xpbd_mesh_pass(a.exec, a.p, &a.topo.springs, first.min(end)..end, &mut b.pos, &mut b.vel, &mut lambda);
    for (k, l) in lambda.chunks_exact(4).enumerate() {
        let v = [l[0], l[1], l[2], l[3]];
        if k < np { b.aux[0][k] = v } else { b.aux[1][k - np] = v }
    }
}

fn vbd_begin(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_begin(a.exec, a.p, &b.force, &b.pos, &b.vel, &mut b.aux);
}

/// One colour of VBD's sweep: particles `first .. first + count` of the colouring's list
/// (`topo.colours.order`, binding [`Buf::Colours`]).
fn vbd_colour(a: &TwinArgs, b: &mut HostBuffers) {
    let order = &a.topo.colours.order;
    let end = (a.range.0 as usize + a.range.1 as usize).min(order.len());
    let list = &order[(a.range.0 as usize).min(end)..end];
    cpu::vbd::vbd_colour(a.exec, a.p, &a.topo.slots, a.colliders, list, &mut b.aux);
}

/// The Chebyshev step after a sweep, ω the bits of the range's `first`.
fn vbd_accelerate(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_accelerate(a.exec, a.p, f32::from_bits(a.range.0), &mut b.aux);
}

fn vbd_finish(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::vbd::vbd_finish(a.exec, a.p, &mut b.pos, &mut b.vel, &b.aux);
}

/// Leaves the per-workgroup sums of `terms` in `aux[4]` (the GPU kernels' partials).
fn store_partials(b: &mut HostBuffers, terms: &[f32]) {
    for (g, s) in cpu::partial_sums(terms).into_iter().enumerate() {
        b.aux[4][g] = [s, 0.0, 0.0, 0.0];
    }
}

/// The partials' fold (what the reduction kernels compute in one workgroup).
fn partials_total(a: &TwinArgs, b: &HostBuffers) -> f32 {
    let groups = (a.topo.num_particles() as u32).div_ceil(WORKGROUP) as usize;
    cpu::fold(&b.aux[4][..groups].iter().map(|v| v[0]).collect::<Vec<_>>())
}

fn cg_begin(a: &TwinArgs, b: &mut HostBuffers) {
    let terms = cpu::cg_begin(a.exec, a.p, &a.topo.slots, &b.force, &b.pos, &b.vel, &mut b.aux);
    store_partials(b, &terms);
}

fn cg_matvec(a: &TwinArgs, b: &mut HostBuffers) {
    let terms = cpu::cg_matvec(a.exec, a.p, &a.topo.slots, &b.pos, &mut b.aux);
    store_partials(b, &terms);
}

fn cg_step(a: &TwinArgs, b: &mut HostBuffers) {
    let terms = cpu::cg_step(a.exec, &b.scalars[0], &mut b.aux);
    store_partials(b, &terms);
}

fn cg_reduce_pq(a: &TwinArgs, b: &mut HostBuffers) {
    let total = partials_total(a, b);
    cpu::cg_alpha(&mut b.scalars[0], total);
}

fn cg_reduce_rz(a: &TwinArgs, b: &mut HostBuffers) {
    let total = partials_total(a, b);
    cpu::cg_beta(&mut b.scalars[0], total);
}

fn cg_direction(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::cg_direction(a.exec, &b.scalars[0], &mut b.aux);
}

fn implicit_finish(a: &TwinArgs, b: &mut HostBuffers) {
    cpu::implicit_finish(a.exec, a.p, &mut b.pos, &mut b.vel, &b.aux);
}

// ---- self-collision (core::cpu::self_collide): the hash in aux2 (cells), aux3, aux4 ----

fn hash_buffers(b: &mut HostBuffers) -> cpu::HashBuffers<'_> {
    cpu::hash_buffers(&mut b.aux)
}

fn hash_count(a: &TwinArgs, b: &mut HostBuffers) {
    let h = cpu::hash_buffers(&mut b.aux);
    cpu::hash_count(a.p, &b.pos, h.cells, h.totals);
}

fn hash_scan_blocks(_: &TwinArgs, b: &mut HostBuffers) {
    let h = hash_buffers(b);
    cpu::hash_scan_blocks(h.cells, h.totals);
}

fn hash_scan_top(_: &TwinArgs, b: &mut HostBuffers) {
    cpu::hash_scan_top(hash_buffers(b).totals);
}

fn hash_scatter(a: &TwinArgs, b: &mut HostBuffers) {
    let h = cpu::hash_buffers(&mut b.aux);
    cpu::hash_scatter(a.p, &b.pos, &b.vel, h.cells, h.slots, h.vel_copy);
}

/// `self_collide` and `self_collide_mesh`: the response without friction between
/// particles, whatever the parameters (the recipe takes the `_friction` kernels where they
/// have Coulomb's coefficients).
fn self_collide(a: &TwinArgs, b: &mut HostBuffers) {
    self_collide_with(a, &a.p.without_coulomb(), b);
}

/// `self_collide_friction` and `self_collide_mesh_friction`: the response with Coulomb
/// friction at its contacts where the parameters have the coefficients.
fn self_collide_friction(a: &TwinArgs, b: &mut HostBuffers) {
    self_collide_with(a, a.p, b);
}

fn self_collide_with(a: &TwinArgs, p: &clothlab_core::StepParams, b: &mut HostBuffers) {
    let [vel_copy, _, cells, _, slots] = &b.aux[..] else { unreachable!("HostBuffers has the AUX buffers") };
    cpu::self_collide(a.exec, p, &b.pos, &mut b.vel, cells, slots, vel_copy, Some(&a.topo.slots), &mut b.pos_out);
}

/// Kernel-test inputs: the hash built by the twins up to the kernel under test (the
/// counts cleared first, as the recipe does).
fn hash_input(upto: usize) -> impl Fn(&TwinArgs, &mut HostBuffers) {
    move |a, b| {
        let h = hash_buffers(b);
        h.cells.iter_mut().chain(h.totals.iter_mut()).for_each(|c| *c = [0.0; 4]);
        let steps: [Twin; 4] = [hash_count, hash_scan_top, hash_scan_blocks, hash_scatter];
        for step in &steps[..upto] {
            step(a, b);
        }
    }
}

fn after_count(a: &TwinArgs, b: &mut HostBuffers) {
    hash_input(1)(a, b)
}

fn after_top(a: &TwinArgs, b: &mut HostBuffers) {
    hash_input(2)(a, b)
}

fn after_scan(a: &TwinArgs, b: &mut HostBuffers) {
    hash_input(3)(a, b)
}

/// The response's input: every 7th particle put within 0.3–0.8 thicknesses of one far
/// away in the grid (half the cloth on), velocity kept, so that contacts are many; then
/// the hash built.
fn built_hash(a: &TwinArgs, b: &mut HostBuffers) {
    let (np, t) = (b.pos.len(), a.p.self_thickness);
    for i in (0..np).step_by(7) {
        let q = (i + np / 2) % np;
        let off = t * (0.3 + 0.5 * ((i / 7) % 5) as f32 / 4.0);
        let dir: [f32; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.8, 0.0]][(i / 7) % 4];
        for (c, d) in dir.iter().enumerate() {
            let to = b.pos[q][c] + off * d;
            b.pos[i][c] = to;
        }
    }
    hash_input(4)(a, b)
}

/// The reduction's work is done by `stats`' twin, which reduces on the spot.
fn nothing(_: &TwinArgs, _: &mut HostBuffers) {}

// ---- the table -----------------------------------------------------------------------

use Buf::*;

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

const fn def(name: &'static str, twin: Twin, count: Count, reads: &'static [Buf], writes: &'static [Buf]) -> KernelDef {
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
    }
}

const PLAIN: Variants = Variants {
    immediates: false,
    table_image: false,
    float_atomics: false,
    colliders_uniform: false,
    shuffle: false,
    sdf_image: false,
};
const IMM_TEX: Variants = Variants { immediates: true, table_image: true, ..PLAIN };
const IMM_F32: Variants = Variants { immediates: true, float_atomics: true, ..PLAIN };
const IMM_CU: Variants = Variants { immediates: true, colliders_uniform: true, sdf_image: true, ..PLAIN };
/// The blocked gathers: the table's homes, and shuffles for the window.
const BLOCKED: Variants = Variants { shuffle: true, ..IMM_TEX };

/// Gravity and drag into the force buffer (added to the wind force already there).
pub static FORCES: KernelDef = def("forces", forces, Count::Particles, &[Params, Pos, Vel, Force], &[Force]);
/// The spring gather per particle over its 12-slot table.
pub static SPRINGS: KernelDef =
    KernelDef { check: GATHER, variants: IMM_TEX, ..def("springs", springs, Count::Particles, TABLE, &[Force]) };
/// The naive spring scatter: one invocation per spring, forces added with atomics.
pub static SPRINGS_SCATTER: KernelDef = KernelDef {
    check: SCATTER,
    label: timing::SPRINGS,
    variants: IMM_F32,
    ..def("springs_scatter", springs_scatter, Count::Springs, &[Params, Pos, Vel, Force, Springs, SpringsB], &[Force])
};
/// `forces` fused into the spring gather, four particles of a row per invocation.
pub static FORCES_SPRINGS: KernelDef = KernelDef {
    check: GATHER,
    label: timing::FORCES_SPRINGS,
    variants: BLOCKED,
    ..def("forces_springs", forces_springs, Count::Blocks, TABLE, &[Force])
};
/// `forces_springs` with the wind of the faces around each particle computed from the
/// positions the gather loads anyway (`normals=frame`): the force buffer is only written.
pub static FORCES_SPRINGS_WIND: KernelDef = KernelDef {
    check: WIND_GATHER,
    pure: &[Force],
    label: timing::FORCES_SPRINGS_WIND,
    variants: BLOCKED,
    ..def(
        "forces_springs_wind",
        forces_springs_wind,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Triangles, FaceSlots],
        &[Force],
    )
};
/// Verlet, pins, the grab and the floor.
pub static INTEGRATE: KernelDef = def("integrate", integrate, Count::Particles, STATE, &[Pos, Vel]);
/// Moving pins to their poses at the substep's end (`clothlab_core::pins`).
pub static PINS: KernelDef = KernelDef {
    variants: PLAIN,
    immediates: Immediates::Substep,
    label: timing::PINS,
    ..def("pins", pins, Count::Pins, &[Pos, Vel, Pins, PinPoses], &[Pos, Vel])
};
/// Spheres, boxes and bodies.
pub static COLLIDE: KernelDef =
    KernelDef { variants: IMM_CU, ..def("collide", collide, Count::Particles, COLLIDERS, &[Pos, Vel]) };
/// `integrate` and `collide` fused: each particle loaded and stored once.
pub static INTEGRATE_COLLIDE: KernelDef = KernelDef {
    label: timing::INTEGRATE_COLLIDE,
    variants: IMM_CU,
    ..def(
        "integrate_collide",
        integrate_collide,
        Count::Particles,
        &[Params, Pos, Vel, Force, Spheres, Boxes, Shapes],
        &[Pos, Vel],
    )
};
/// `forces`, `integrate` and `collide` fused: the thesis's optimized "Verlet" kernel. The
/// total force is used, not stored (the normals kernel rewrites the force buffer later in
/// the substep, so nothing reads it).
pub static FORCES_INTEGRATE_COLLIDE: KernelDef = KernelDef {
    label: timing::FORCES_INTEGRATE_COLLIDE,
    variants: IMM_CU,
    ..def(
        "forces_integrate_collide",
        forces_integrate_collide,
        Count::Particles,
        &[Params, Pos, Vel, Force, Spheres, Boxes, Shapes],
        &[Pos, Vel],
    )
};
/// Every particle's count of over-stretched strain-limited springs, into aux0 (dead
/// after the integrator's kernels): what the pass after it divides each spring by the
/// larger of its ends' counts of (the same at both ends: the pass keeps the momentum).
/// Timed as part of the strain limit.
pub static STRAIN_COUNT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[Aux0],
    variants: BLOCKED,
    label: timing::STRAIN_LIMIT,
    ..def(
        "strain_count",
        strain_count,
        Count::Blocks,
        &[Params, Pos, Slots, BendSlots, Adjacency, Interior, Table],
        &[Aux0],
    )
};
/// One Provot pass plus the tethers, into the other buffer of the pair; the velocities
/// gain the move over dt.
pub static STRAIN_LIMIT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    variants: BLOCKED,
    // The counts it divides by, of the disturbed positions (as the recipe runs it).
    test_input: Some(strain_count),
    ..def(
        "strain_limit",
        strain_limit,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers, Aux0],
        &[PosOut, Vel],
    )
};
/// The strain limit's last pass fused with self-collision's `hash_count` (the recipe's
/// choice when self-collision follows a strain limit): one dispatch fewer. Its counts are
/// checked against a recount of the positions it wrote (see
/// [`crate::validate::validate_kernels_with`]); a wrong count is off by a whole particle,
/// far past the positions' bound, so the bound leaves the counts exact.
pub static STRAIN_LIMIT_COUNT: KernelDef = KernelDef {
    check: GATHER,
    pure: &[PosOut],
    accumulates: &[Aux2, Aux3],
    variants: BLOCKED,
    test_input: Some(strain_count),
    label: timing::STRAIN_LIMIT_COUNT,
    ..def(
        "strain_limit_count",
        strain_limit_count,
        Count::Blocks,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Interior, Table, Tethers, Aux0, Aux2, Aux3],
        &[PosOut, Vel, Aux2, Aux3],
    )
};
/// The Verlet substep of a regular grid in one dispatch over workgroup-memory tiles
/// (`fusion=tile`): a workgroup per tile of `32 − 2·halo` points a side, the halo 2 + 2
/// per strain pass deep (times `tile_substeps`). Dispatched as a range of
/// [`crate::recipe::tile_command`] (its count of tiles depends on the pass count).
pub static SUBSTEP_TILE: KernelDef = KernelDef {
    check: TILE_CHECK,
    pure: &[PosOut, Aux0],
    label: timing::SUBSTEP_TILE,
    variants: IMM_CU,
    cloths: Cloths::Grid,
    ..def(
        "substep_tile",
        substep_tile,
        Count::Particles,
        &[Params, Pos, Vel, Interior, Spheres, Boxes, Shapes, Tethers],
        &[PosOut, Aux0],
    )
};
/// The tiled substep's new velocities (aux0) into place, after the swap.
pub static TILE_VEL: KernelDef = KernelDef {
    pure: &[Vel],
    label: timing::SUBSTEP_TILE,
    ..def("tile_vel", tile_vel, Count::Particles, &[Params, Aux0], &[Vel])
};
/// Workgroup memory the tiled substep needs (its 32 × 32 region of positions,
/// velocities and strain counts).
pub const TILE_WORKGROUP_BYTES: u32 = 32 * 32 * 32;
/// The side of the tiled substep's region (tile and halo), points.
pub const TILE_REGION: u32 = 32;

/// Face normals per quad of the grid.
/// A mesh's, per two triangles of the list.
pub static TRI_NORMALS: KernelDef =
    KernelDef { pure: &[Faces], ..def("tri_normals", tri_normals, Count::Quads, &[Params, Pos, Triangles], &[Faces]) };
/// The naive face normals: per triangle, also added to the corners' normals with atomics.
pub static TRI_NORMALS_SCATTER: KernelDef = KernelDef {
    check: SCATTER,
    pure: &[Faces],
    accumulates: &[Normal],
    label: timing::TRI_NORMALS,
    variants: IMM_F32,
    ..def(
        "tri_normals_scatter",
        tri_normals_scatter,
        Count::Triangles,
        &[Params, Pos, Normal, Triangles],
        &[Faces, Normal],
    )
};
/// Vertex normals gathered from the face normals, and the wind force.
pub static VERTEX_NORMALS: KernelDef = KernelDef {
    check: GATHER,
    pure: &[Normal, Force],
    ..def(
        "vertex_normals",
        vertex_normals,
        Count::Particles,
        &[Params, Pos, Vel, Faces, FaceSlots, Adjacency, Normal, Force],
        &[Normal, Force],
    )
};
/// The naive vertex normals: the scatter's sums normalised, and the wind force.
pub static VERTEX_NORMALS_NAIVE: KernelDef = KernelDef {
    check: GATHER,
    pure: &[Force],
    label: timing::VERTEX_NORMALS,
    test_input: Some(face_sums_input),
    ..def(
        "vertex_normals_naive",
        vertex_normals,
        Count::Particles,
        &[Params, Pos, Vel, Faces, FaceSlots, Adjacency, Normal, Force],
        &[Normal, Force],
    )
};
/// Statistics by subgroup and workgroup reductions: one partial per workgroup.
pub static STATS: KernelDef = KernelDef {
    check: STATS_TEST,
    label: timing::STATS,
    variants: Variants { table_image: true, ..PLAIN },
    immediates: Immediates::Substep,
    ..def("stats", stats, Count::Particles, &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table], &[Partials])
};
/// Statistics by atomics from every invocation.
pub static STATS_ATOMIC: KernelDef = KernelDef {
    check: STATS_TEST,
    label: timing::STATS,
    variants: Variants { table_image: true, float_atomics: true, ..PLAIN },
    immediates: Immediates::Substep,
    ..def(
        "stats_atomic",
        stats,
        Count::Particles,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table, StatsMax, StatsEnergy],
        &[StatsMax, StatsEnergy],
    )
};
/// The statistics' final fold of the partials.
pub static STATS_REDUCE: KernelDef = KernelDef {
    check: STATS_TEST,
    label: timing::STATS,
    variants: PLAIN,
    immediates: Immediates::Substep,
    ..def(
        "stats_reduce",
        nothing,
        Count::Workgroup,
        &[Params, Partials, StatsMax, StatsEnergy],
        &[StatsMax, StatsEnergy],
    )
};

// ---- the integrators other than Verlet (core::cpu::integrators) ----

/// Conjugate gradients: dot products summed per workgroup (in a tree on the GPU, in order
/// on the CPU) and over 16 iterations; the rollout's bound covers the rest.
const CG: Check = Check::Bound {
    relative: 1e-4,
    reason: "dot products summed in another order (tree per workgroup vs in order), divided into α and β",
};
const RK_READS: &[Buf] = &[Params, Pos, Vel, Force, Aux0, Aux1, Aux2, Aux3, Aux4];
const CG_PARTIALS: &[Buf] = &[Params, Aux4, Scalars];

/// Explicit Euler: `x' = x + u`, `u' = u + f dt²/m`.
pub static EULER: KernelDef =
    KernelDef { label: timing::INTEGRATE, ..def("euler", euler, Count::Particles, STATE, &[Pos, Vel]) };
/// Saves x₀, the damped v₀ and the wind for a Runge–Kutta substep.
pub static RK_BEGIN: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    pure: &[Aux0, Aux1, Aux4],
    ..def("rk_begin", rk_begin, Count::Particles, STATE, &[Vel, Aux0, Aux1, Aux4])
};
/// A stage kernel (every stage's shader has the force write; the last one never runs it).
const fn rk(name: &'static str, twin: Twin) -> KernelDef {
    KernelDef {
        label: timing::INTEGRATE,
        ..def(name, twin, Count::Particles, RK_READS, &[Pos, Vel, Force, Aux2, Aux3])
    }
}
/// RK2's first stage (to the midpoint).
pub static RK2_1: KernelDef = rk("rk2_1", rk2_1);
/// RK2's second stage (the end of the substep).
pub static RK2_2: KernelDef = rk("rk2_2", rk2_2);
/// RK4's first stage.
pub static RK4_1: KernelDef = rk("rk4_1", rk4_1);
/// RK4's second stage.
pub static RK4_2: KernelDef = rk("rk4_2", rk4_2);
/// RK4's third stage.
pub static RK4_3: KernelDef = rk("rk4_3", rk4_3);
/// RK4's fourth stage (the end of the substep).
pub static RK4_4: KernelDef = rk("rk4_4", rk4_4);
/// One XPBD pass: the springs of one direction and colour (core::cpu::XPBD_PASSES),
/// both ends moved in place, their velocities with them.
const fn xpbd(name: &'static str, twin: Twin) -> KernelDef {
    KernelDef {
        check: GATHER,
        label: timing::XPBD,
        variants: IMM_TEX,
        cloths: Cloths::Grid,
        ..def(
            name,
            twin,
            Count::Particles,
            &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table, Aux0, Aux1],
            &[Pos, Vel, Aux0, Aux1],
        )
    }
}
/// The 12 passes of one XPBD iteration, in order.
pub static XPBD: [KernelDef; 12] = [
    xpbd("xpbd_0", xpbd_0),
    xpbd("xpbd_1", xpbd_1),
    xpbd("xpbd_2", xpbd_2),
    xpbd("xpbd_3", xpbd_3),
    xpbd("xpbd_4", xpbd_4),
    xpbd("xpbd_5", xpbd_5),
    xpbd("xpbd_6", xpbd_6),
    xpbd("xpbd_7", xpbd_7),
    xpbd("xpbd_8", xpbd_8),
    xpbd("xpbd_9", xpbd_9),
    xpbd("xpbd_10", xpbd_10),
    xpbd("xpbd_11", xpbd_11),
];
/// One XPBD pass of a mesh: a range of its spring list sorted by pass
/// (`MeshTables::xpbd_passes`), λ per spring in aux0 and aux1.
pub static XPBD_MESH: KernelDef = KernelDef {
    check: GATHER,
    label: timing::XPBD,
    variants: PLAIN,
    immediates: Immediates::Range,
    cloths: Cloths::Mesh,
    ..def(
        "xpbd_mesh",
        xpbd_mesh,
        Count::Range,
        &[Params, Pos, Vel, Springs, SpringsB, Aux0, Aux1],
        &[Pos, Vel, Aux0, Aux1],
    )
};
/// VBD: the predicted velocity v' (aux0; the prediction y = x⁰ + h v'), the substep's
/// start x⁰ (aux1) and the displacement D = h v' (aux2) (core::cpu::vbd::vbd_begin).
pub static VBD_BEGIN: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    pure: &[Aux0, Aux1, Aux2],
    ..def("vbd_begin", vbd_begin, Count::Particles, STATE, &[Aux0, Aux1, Aux2])
};
/// VBD: one colour's Newton steps, each particle of the range of the colouring's list
/// ([`Buf::Colours`]) on its 3 × 3 block over its row of the table, into its
/// displacement (aux2).
pub static VBD_COLOUR: KernelDef = KernelDef {
    check: Check::Bound {
        relative: 2e-5,
        reason: "a gather over the row's springs into a 3 × 3 block, solved by cofactors (one division)",
    },
    label: timing::VBD,
    variants: Variants { table_image: true, colliders_uniform: true, sdf_image: true, ..PLAIN },
    immediates: Immediates::Range,
    ..def(
        "vbd_colour",
        vbd_colour,
        Count::Range,
        &[Params, Colours, Slots, BendSlots, Adjacency, Table, Spheres, Boxes, Shapes, Aux0, Aux1, Aux2],
        &[Aux2],
    )
};
/// VBD: the Chebyshev acceleration after a sweep (`vbd_rho` > 0), ω in the immediates as
/// the bits of the range's `first`, `count` the particles (core::cpu::vbd::vbd_accelerate).
pub static VBD_ACCELERATE: KernelDef = KernelDef {
    label: timing::VBD,
    variants: PLAIN,
    immediates: Immediates::Range,
    ..def("vbd_accelerate", vbd_accelerate, Count::Range, &[Params, Aux0, Aux1, Aux2, Aux3, Aux4], &[Aux2, Aux3, Aux4])
};
/// VBD: x = x⁰ + D, v = v' + (D − h v')/h, with pins, grab and floor
/// (core::cpu::vbd::vbd_finish).
pub static VBD_FINISH: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    ..def("vbd_finish", vbd_finish, Count::Particles, &[Params, Aux0, Aux1, Aux2], &[Pos, Vel])
};
/// Implicit: r = dt f − dt² K v, p = z, Δv = 0, and the partials of r·z.
pub static CG_BEGIN: KernelDef = KernelDef {
    check: GATHER,
    label: timing::CG,
    variants: IMM_TEX,
    ..def(
        "cg_begin",
        cg_begin,
        Count::Particles,
        &[Params, Pos, Vel, Force, Slots, BendSlots, Adjacency, Table, Aux2],
        &[Aux0, Aux1, Aux2, Aux4],
    )
};
/// Implicit: q = A p and the partials of p·q.
pub static CG_MATVEC: KernelDef = KernelDef {
    check: GATHER,
    label: timing::CG,
    variants: IMM_TEX,
    ..def(
        "cg_matvec",
        cg_matvec,
        Count::Particles,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Table, Aux2],
        &[Aux3, Aux4],
    )
};
/// Implicit: p·q folded, α = r·z / p·q.
pub static CG_REDUCE_PQ: KernelDef = KernelDef {
    check: CG,
    label: timing::CG,
    ..def("cg_reduce_pq", cg_reduce_pq, Count::Workgroup, CG_PARTIALS, &[Scalars])
};
/// Implicit: Δv += α p, r −= α q, and the partials of r·z.
pub static CG_STEP: KernelDef = KernelDef {
    check: CG,
    label: timing::CG,
    ..def("cg_step", cg_step, Count::Particles, &[Params, Aux0, Aux1, Aux2, Aux3, Scalars], &[Aux0, Aux1, Aux4])
};
/// Implicit: r·z folded, β = new / old.
pub static CG_REDUCE_RZ: KernelDef = KernelDef {
    check: CG,
    label: timing::CG,
    ..def("cg_reduce_rz", cg_reduce_rz, Count::Workgroup, CG_PARTIALS, &[Scalars])
};
/// Implicit: p = z + β p.
pub static CG_DIRECTION: KernelDef = KernelDef {
    check: CG,
    label: timing::CG,
    ..def("cg_direction", cg_direction, Count::Particles, &[Params, Aux1, Aux2, Scalars], &[Aux2])
};
/// Implicit: v₁ = (1 − damping) v₀ + Δv, x₁ = x₀ + v₁ dt, with pins, grab and floor.
pub static IMPLICIT_FINISH: KernelDef = KernelDef {
    label: timing::INTEGRATE,
    ..def("implicit_finish", implicit_finish, Count::Particles, &[Params, Pos, Vel, Aux0], &[Pos, Vel])
};

// ---- self-collision (core::cpu::self_collide) ----

/// Integer work (counts, prefix sums, indices): the same bits everywhere.
const EXACT: Check = Check::Bound { relative: 0.0, reason: "integers: counts, prefix sums and indices" };
const fn hash(
    name: &'static str,
    twin: Twin,
    count: Count,
    reads: &'static [Buf],
    writes: &'static [Buf],
) -> KernelDef {
    KernelDef { check: EXACT, label: timing::SELF_HASH, ..def(name, twin, count, reads, writes) }
}
/// Each particle's bucket, and the buckets' and their blocks' counts (atomics).
pub static HASH_COUNT: KernelDef = KernelDef {
    accumulates: &[Aux2, Aux3],
    ..hash("hash_count", hash_count, Count::Particles, &[Params, Pos, Aux2, Aux3], &[Aux2, Aux3])
};
/// The blocks' totals' exclusive prefix: each block's offset (one workgroup).
pub static HASH_SCAN_TOP: KernelDef = KernelDef {
    test_input: Some(after_count),
    ..hash("hash_scan_top", hash_scan_top, Count::Workgroup, &[Params, Aux3], &[Aux3])
};
/// The counts' inclusive prefix within each block of buckets from its offset: every
/// bucket's end in the whole array.
pub static HASH_SCAN_BLOCKS: KernelDef = KernelDef {
    test_input: Some(after_top),
    ..hash("hash_scan_blocks", hash_scan_blocks, Count::HashBlocks, &[Params, Aux2, Aux3], &[Aux2])
};
/// Every particle's position and slot word into its bucket's range, in any order
/// (atomics), each bucket's word moved to its start: checked bucket by bucket as sets.
pub static HASH_SCATTER: KernelDef = KernelDef {
    test_input: Some(after_scan),
    check: Check::Own("the_gpu_hash_lists_what_the_cpu_lists_after_its_scatter"),
    ..hash("hash_scatter", hash_scatter, Count::Particles, &[Params, Pos, Vel, Aux2], &[Aux0, Aux2, Aux4])
};
/// The response's check: a gather over the contacts, in fixed point.
const RESPONSE: Check = Check::Bound {
    relative: 2e-5,
    reason: "a gather over the contacts with divisions and square roots, truncated to fixed point \
             (a last-bit difference moves a push by t / 65536 at most; exact on lavapipe)",
};
/// The response: every particle pushed out of its close candidates, into the other
/// position buffer.
pub static SELF_COLLIDE: KernelDef = KernelDef {
    check: RESPONSE,
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Grid,
    ..def("self_collide", self_collide, Count::Pairs, &[Params, Pos, Vel, Aux2, Aux4], &[PosOut, Vel])
};
/// [`SELF_COLLIDE`] with Coulomb friction at its contacts (the contacts' velocities from
/// the copy in aux0 that `hash_scatter` writes): the recipe's response where the
/// parameters have Coulomb's coefficients.
pub static SELF_COLLIDE_FRICTION: KernelDef = KernelDef {
    check: RESPONSE,
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Grid,
    ..def(
        "self_collide_friction",
        self_collide_friction,
        Count::Pairs,
        &[Params, Pos, Vel, Aux0, Aux2, Aux4],
        &[PosOut, Vel],
    )
};
/// [`SELF_COLLIDE`] on a mesh: pairs of consecutive particles, a particle's neighbours
/// its springs (from the table, for the entries within the thickness).
pub static SELF_COLLIDE_MESH: KernelDef = KernelDef {
    check: RESPONSE,
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Mesh,
    ..def(
        "self_collide_mesh",
        self_collide,
        Count::Pairs,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Aux2, Aux4],
        &[PosOut, Vel],
    )
};
/// [`SELF_COLLIDE_MESH`] with Coulomb friction at its contacts ([`SELF_COLLIDE_FRICTION`]'s).
pub static SELF_COLLIDE_MESH_FRICTION: KernelDef = KernelDef {
    check: RESPONSE,
    pure: &[PosOut],
    label: timing::SELF_COLLIDE,
    test_input: Some(built_hash),
    cloths: Cloths::Mesh,
    ..def(
        "self_collide_mesh_friction",
        self_collide_friction,
        Count::Pairs,
        &[Params, Pos, Vel, Slots, BendSlots, Adjacency, Aux0, Aux2, Aux4],
        &[PosOut, Vel],
    )
};
/// Self-collision's kernels, in recipe order.
pub static SELF_COLLISION: [&KernelDef; 5] =
    [&HASH_COUNT, &HASH_SCAN_TOP, &HASH_SCAN_BLOCKS, &HASH_SCATTER, &SELF_COLLIDE];

/// Every built-in kernel of the step.
pub static ALL: [&KernelDef; 62] = [
    &PINS,
    &FORCES,
    &SPRINGS,
    &SPRINGS_SCATTER,
    &FORCES_SPRINGS,
    &FORCES_SPRINGS_WIND,
    &INTEGRATE,
    &COLLIDE,
    &INTEGRATE_COLLIDE,
    &FORCES_INTEGRATE_COLLIDE,
    &STRAIN_COUNT,
    &STRAIN_LIMIT,
    &TRI_NORMALS,
    &TRI_NORMALS_SCATTER,
    &VERTEX_NORMALS,
    &VERTEX_NORMALS_NAIVE,
    &STATS,
    &STATS_ATOMIC,
    &STATS_REDUCE,
    &EULER,
    &RK_BEGIN,
    &RK2_1,
    &RK2_2,
    &RK4_1,
    &RK4_2,
    &RK4_3,
    &RK4_4,
    &XPBD[0],
    &XPBD[1],
    &XPBD[2],
    &XPBD[3],
    &XPBD[4],
    &XPBD[5],
    &XPBD[6],
    &XPBD[7],
    &XPBD[8],
    &XPBD[9],
    &XPBD[10],
    &XPBD[11],
    &XPBD_MESH,
    &VBD_BEGIN,
    &VBD_COLOUR,
    &VBD_ACCELERATE,
    &VBD_FINISH,
    &CG_BEGIN,
    &CG_MATVEC,
    &CG_REDUCE_PQ,
    &CG_STEP,
    &CG_REDUCE_RZ,
    &CG_DIRECTION,
    &IMPLICIT_FINISH,
    &HASH_COUNT,
    &STRAIN_LIMIT_COUNT,
    &HASH_SCAN_TOP,
    &HASH_SCAN_BLOCKS,
    &HASH_SCATTER,
    &SELF_COLLIDE,
    &SELF_COLLIDE_MESH,
    &SELF_COLLIDE_FRICTION,
    &SELF_COLLIDE_MESH_FRICTION,
    &SUBSTEP_TILE,
    &TILE_VEL,
];

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
