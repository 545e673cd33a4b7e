//! How the step's data is laid out for the kernels: one typed id per binding ([`Buf`]: the
//! number every WGSL kernel declares it at, and what kind of binding it is) and the
//! constants the WGSL shares with Rust. `shaders/build.rs` writes the WGSL constants from
//! [`wgsl_constants`] and checks every `@binding(k)` of every kernel against [`Buf`], so
//! a changed constant or binding cannot leave the shaders stale.

pub use crate::grid::{FACE_SLOTS, SLOTS, STRAIN_SLOTS, TETHER_SLOTS};

/// Invocations per workgroup of every compute kernel.
pub const WORKGROUP: u32 = 64;
/// Particles per invocation of the blocked kernels (consecutive particles of a row).
pub const BLOCK: u32 = 4;
/// Rows of a strip of the strain limit's pass down strips (`strain_counts=strip`): an
/// invocation carries its block's columns through this many rows, each spring's length
/// and each count computed once; two rows above and below it are the strip's overhead.
pub const STRIP_ROWS: u32 = 16;
/// Texels per row of the spring-table image (the thesis's texture memory).
pub const TABLE_WIDTH: u32 = 4096;
/// Pairs each owner of the contact between triangles keeps (a vertex its triangles, an
/// edge its edges; more are counted, not kept).
pub const TRI_SLOTS: u32 = crate::tri_contact::PAIRS_PER_OWNER as u32;
/// The most cells a query of the contact between triangles' grids walks
/// ([`crate::broad::QUERY_CELLS`]).
pub const TRI_QUERY_CELLS: u32 = crate::broad::QUERY_CELLS;

/// A spring over `(1 + τ)·rest` is pulled towards `(1 + STRAIN_AIM·τ)·rest`, a little
/// inside the limit: corrections proportional to the excess over the limit itself make
/// Jacobi approach the bound only asymptotically (measured: 0.1002 after 400 passes for
/// τ = 0.1), aiming inside ends the passes in finitely many steps. Aiming far inside
/// (0.9) injects velocity: springs that carry the cloth's weight are pulled in every
/// substep and the pinned corners jitter; 0.95 measured no jitter (max speed of a cloth
/// at rest 0.09 m/s vs 1.1 m/s at 0.9).
pub const STRAIN_AIM: f32 = 0.95;
/// Planes of [`Buf::Adjoint`]: x̄, v̄, the force's gradient (a strain pass: its point's),
/// five of the parameters' partials (`clothlab_cpu::adjoint::Partial`), then a strain
/// pass's two tethers' shares of their pins.
pub const ADJ_ROWS: u32 = 10;

/// What kind of binding a [`Buf`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BindKind {
    /// A uniform block (`var<uniform>`).
    Uniform,
    /// A storage buffer (`var<storage>`).
    Storage,
    /// A sampled image (`texture_2d<u32>`).
    Image,
    /// A 3-D sampled image of floats read through a filtering sampler
    /// (`texture_3d<f32>`): the bodies' distance fields with `sdf=image`.
    Volume,
    /// A filtering sampler (`sampler`): trilinear, clamped to the edge.
    Sampler,
}

/// The bindings of the step (group 0), by the number the WGSL declares them at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u32)]
pub enum Buf {
    /// The step constants ([`crate::StepParams`]).
    Params = 0,
    /// The current positions (w: 1 free, 0 pinned).
    Pos = 1,
    /// The velocities, m/s.
    Vel = 2,
    /// Forces (also the wind force the normals kernel leaves for the next substep).
    Force = 3,
    /// Vertex normals (the naive scatter's accumulators).
    Normal = 4,
    /// The other buffer of the position pair (the strain limit's output).
    PosOut = 5,
    /// A grid's spring slots 0..8 of every particle (structural, shear); the first half of
    /// a mesh's rows, one after another (see [`Buf::Adjacency`]).
    Slots = 6,
    /// The flat spring list, first half.
    Springs = 7,
    /// Tethers to the pins.
    Tethers = 8,
    /// Triangle corners.
    Triangles = 9,
    /// Per-vertex adjacent faces: a grid's six a particle, a mesh's compressed rows.
    FaceSlots = 10,
    /// Face normals, |N| in w.
    Faces = 11,
    /// Sphere colliders.
    Spheres = 12,
    /// Box colliders.
    Boxes = 13,
    /// A grid's spring slots 8..12 of every particle (bend); the rest of a mesh's rows.
    BendSlots = 14,
    /// The flat spring list, second half.
    SpringsB = 15,
    /// The regular grid's spring constants (uniform).
    Interior = 16,
    /// Per-substep largest structural strain.
    StatsMax = 17,
    /// Per-substep kinetic energy.
    StatsEnergy = 18,
    /// Per-workgroup partial statistics.
    Partials = 19,
    /// The spring table as an image.
    Table = 20,
    /// The spheres in a uniform block (`colliders=uniform`: the thesis's constant memory).
    SpheresUniform = 21,
    /// The boxes in a uniform block.
    BoxesUniform = 22,
    /// The step constants in a storage buffer (`constants=storage`).
    ParamsStorage = 23,
    /// Scratch 0. The five scratch buffers hold what one kernel hands the next within a
    /// substep, and each user's data is dead before the next user writes its own; by role:
    /// - RK: x₀; implicit Euler: Δv; XPBD: λ (a grid's slots 1, 3, 7 at each spring's
    ///   first end; a mesh's springs `k < n`); VBD: the predicted velocity v′
    ///   (`core::cpu::integrators`, `core::cpu::vbd`);
    /// - the strain limit: each particle's count of stretched springs (`strain_count`,
    ///   read by the pass; `core::cpu::strain_limit`);
    /// - self-collision with Coulomb friction: the velocities' copy `hash_scatter` writes
    ///   for the response;
    /// - the tiled substep: the new velocities, put into place by `tile_vel`.
    Aux0 = 24,
    /// Scratch 1 (see [`Buf::Aux0`]): RK: v₀; implicit: r, w the preconditioner's diagonal;
    /// XPBD: λ (a grid's slots 6, 9, 11; a mesh's springs `k ≥ n`); VBD: the substep's
    /// start x⁰.
    Aux1 = 25,
    /// Scratch 2: RK: Σ bₛuₛ; implicit: p; VBD: the displacement D = x − x⁰; self-collision's
    /// hash: the per-cell counts, then the cells' starts (`hash_count`, the scans,
    /// `hash_scatter`; `core::cpu::self_collide`).
    Aux2 = 26,
    /// Scratch 3: RK: Σ bₛgₛ; implicit: q = A p; VBD: the Chebyshev step's last
    /// displacement; the hash: the blocks' totals of the counts.
    Aux3 = 27,
    /// Scratch 4: RK: the substep's wind force; implicit: the CG reductions' sums per
    /// workgroup; VBD: the Chebyshev step's displacement before the last; the hash: the
    /// particles sorted by cell (its slots).
    Aux4 = 28,
    /// The conjugate-gradient scalars `r·z`, `p·q`, `α`, `β` (one `vec4<f32>`).
    Scalars = 29,
    /// A mesh's compressed rows (`tables::Rows`): per particle `(first slot within its
    /// binding, head length, first face slot, slot count | 1 << 31 where the row is in
    /// binding 14)`, and one past the last `(0, 0, end of the faces, binding 14's first
    /// entry in the whole table)` (`clothlab_engine::tables::adjacency`). A grid's table
    /// is of fixed rows and its kernels never read this (one unused element).
    Adjacency = 30,
    /// Vertex Block Descent's colouring (`tables::Colours::order`): every particle once,
    /// colour by colour, `u32` each; a colour's dispatch sweeps its range.
    Colours = 31,
    /// The moving pins (`pins::PinSlot`; one unused element when none move).
    Pins = 32,
    /// The frame's pin poses (`pins::PinPose`), a block of `MAX_PIN_GROUPS` per substep.
    PinPoses = 33,
    /// The rods and the bodies (mesh colliders), `f32`s: `MAX_BODIES` heads of
    /// `SdfHead::FLOATS` (the bodies' poses at the current substep), `MAX_RODS` rods of
    /// 16 floats (`scene::RodRecord`, at the current substep, the kind in
    /// `b.w`), then every body's distance values (`crate::sdf`: `RODS_AT`, `VALUES_AT`). One binding for all: a
    /// VBD sweep's kernel binds 16 storage blocks, llvmpipe's GL limit.
    Shapes = 34,
    /// The bodies' distance values as one 3-D `r32float` image (`sdf=image`: the thesis's
    /// texture memory, where the texture unit interpolates): the bodies' grids stacked
    /// along z in body order, each in its own slices (`x, y` from the image's corner),
    /// sampled through [`Buf::SdfSampler`]. A second home of [`Buf::Shapes`]' values.
    SdfImage = 35,
    /// The trilinear sampler of [`Buf::SdfImage`].
    SdfSampler = 36,
    /// The contact, friction and solver constants ([`crate::step_params::ContactParams`],
    /// `StepParams::contact`): a uniform block beside the step's, part of
    /// [`Buf::Params`]' data (a row that reads the constants reads both).
    Contact = 37,
    /// The contact between triangles' edges (`core::cpu::tri_contact::TriLayout::
    /// edges_words`): a header `[triangles, edges, buckets, 0]`, then two vertices an
    /// edge. One element where the scene has no such contact (so the other three).
    TriEdges = 38,
    /// The contact between triangles: each particle's position at the substep's start
    /// and its bound on its motion (f32 bits in w, lowered by atomic minima).
    TriFloats = 39,
    /// The contact between triangles' integers (`core::cpu::tri_contact::TriLayout`):
    /// its scalars, the two grids of the primitives' boxes, each owner's count of pairs,
    /// each particle's fixed-point sums. Cleared at the substep's start.
    TriInts = 40,
    /// The contact between triangles' pairs: [`TRI_SLOTS`] an owner (a vertex's
    /// triangles, an edge's edges).
    TriPairs = 41,
    /// The adjoint of a substep (`grad=True` on a GPU; docs/gradients.md): [`ADJ_ROWS`]
    /// planes of one `vec4` a particle, plane `r` of particle `i` at `r · N + i`: the
    /// gradient with respect to the position, the velocity, the force, five planes of the
    /// parameters' partials each particle adds up, two of the tethers' shares
    /// (`clothlab_cpu::adjoint`). One element where the solver has none.
    Adjoint = 42,
}

impl Buf {
    /// Every binding, in binding order.
    pub const ALL: [Buf; 43] = [
        Buf::Params,
        Buf::Pos,
        Buf::Vel,
        Buf::Force,
        Buf::Normal,
        Buf::PosOut,
        Buf::Slots,
        Buf::Springs,
        Buf::Tethers,
        Buf::Triangles,
        Buf::FaceSlots,
        Buf::Faces,
        Buf::Spheres,
        Buf::Boxes,
        Buf::BendSlots,
        Buf::SpringsB,
        Buf::Interior,
        Buf::StatsMax,
        Buf::StatsEnergy,
        Buf::Partials,
        Buf::Table,
        Buf::SpheresUniform,
        Buf::BoxesUniform,
        Buf::ParamsStorage,
        Buf::Aux0,
        Buf::Aux1,
        Buf::Aux2,
        Buf::Aux3,
        Buf::Aux4,
        Buf::Scalars,
        Buf::Adjacency,
        Buf::Colours,
        Buf::Pins,
        Buf::PinPoses,
        Buf::Shapes,
        Buf::SdfImage,
        Buf::SdfSampler,
        Buf::Contact,
        Buf::TriEdges,
        Buf::TriFloats,
        Buf::TriInts,
        Buf::TriPairs,
        Buf::Adjoint,
    ];

    /// The integrators' scratch particle buffers, in order.
    pub const AUX: [Buf; 5] = [Buf::Aux0, Buf::Aux1, Buf::Aux2, Buf::Aux3, Buf::Aux4];

    /// The `@binding` number.
    pub const fn binding(self) -> u32 {
        self as u32
    }

    /// The binding with number `b`.
    pub fn from_binding(b: u32) -> Option<Buf> {
        Self::ALL.get(b as usize).copied()
    }

    /// What kind of binding it is.
    pub const fn kind(self) -> BindKind {
        match self {
            Buf::Params | Buf::Interior | Buf::SpheresUniform | Buf::BoxesUniform | Buf::Contact => BindKind::Uniform,
            Buf::Table => BindKind::Image,
            Buf::SdfImage => BindKind::Volume,
            Buf::SdfSampler => BindKind::Sampler,
            _ => BindKind::Storage,
        }
    }

    /// A short name (buffer labels, reports).
    pub const fn name(self) -> &'static str {
        match self {
            Buf::Params => "params",
            Buf::Pos => "pos",
            Buf::Vel => "vel",
            Buf::Force => "force",
            Buf::Normal => "normal",
            Buf::PosOut => "pos_out",
            Buf::Slots => "slots",
            Buf::Springs => "springs",
            Buf::Tethers => "tethers",
            Buf::Triangles => "triangles",
            Buf::FaceSlots => "face_slots",
            Buf::Faces => "faces",
            Buf::Spheres => "spheres",
            Buf::Boxes => "boxes",
            Buf::BendSlots => "bend_slots",
            Buf::SpringsB => "springs_b",
            Buf::Interior => "interior",
            Buf::StatsMax => "stats_max",
            Buf::StatsEnergy => "stats_energy",
            Buf::Partials => "partials",
            Buf::Table => "table",
            Buf::SpheresUniform => "spheres_uniform",
            Buf::BoxesUniform => "boxes_uniform",
            Buf::ParamsStorage => "params_storage",
            Buf::Aux0 => "aux0",
            Buf::Aux1 => "aux1",
            Buf::Aux2 => "aux2",
            Buf::Aux3 => "aux3",
            Buf::Aux4 => "aux4",
            Buf::Scalars => "scalars",
            Buf::Adjacency => "adjacency",
            Buf::Colours => "colours",
            Buf::Pins => "pins",
            Buf::PinPoses => "pin_poses",
            Buf::Shapes => "shapes",
            Buf::SdfImage => "sdf_image",
            Buf::SdfSampler => "sdf_sampler",
            Buf::Contact => "contact",
            Buf::TriEdges => "tri_edges",
            Buf::TriFloats => "tri_floats",
            Buf::TriInts => "tri_ints",
            Buf::TriPairs => "tri_pairs",
            Buf::Adjoint => "adjoint",
        }
    }

    /// The buffer whose data this binding holds: a second home of the same data (the
    /// constants in storage, the colliders in uniform blocks) names the first, so that
    /// registry rows, hazards and host copies need to know only one.
    pub const fn data(self) -> Buf {
        match self {
            Buf::ParamsStorage | Buf::Contact => Buf::Params,
            Buf::SpheresUniform => Buf::Spheres,
            Buf::BoxesUniform => Buf::Boxes,
            Buf::SdfImage | Buf::SdfSampler => Buf::Shapes,
            b => b,
        }
    }

    /// The other homes of this buffer's data (see [`Buf::data`]).
    pub const fn homes(self) -> &'static [Buf] {
        match self {
            Buf::Params => &[Buf::ParamsStorage, Buf::Contact],
            Buf::Spheres => &[Buf::SpheresUniform],
            Buf::Boxes => &[Buf::BoxesUniform],
            Buf::Shapes => &[Buf::SdfImage],
            _ => &[],
        }
    }
}

/// What a scene uses of the collider walk's code: the kernels' `USES_*` constants. The
/// built kernels say `true` for all (they serve every scene); `specialize=on` rebuilds a
/// scene's kernels with what it uses ([`Uses::of`]), so that a kernel compiles to the code
/// the scene needs: code a scene does not use costs a kernel on llvmpipe about as much as
/// code it runs (docs/bench/lavapipe-specialise).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Uses {
    /// Rods: capsules, cylinders (`USES_RODS`: the rods' loops).
    pub rods: bool,
    /// Bodies (`USES_BODIES`: the bodies' loops and their fields' reads).
    pub bodies: bool,
    /// Coulomb friction (`USES_COULOMB`: `coulomb()` is false without it).
    pub coulomb: bool,
    /// Moving colliders (`USES_MOTION`: a surface's velocity is zero without it).
    pub motion: bool,
}

impl Uses {
    /// Everything: the code every scene may run (what the build compiles).
    pub const ALL: Uses = Uses { rods: true, bodies: true, coulomb: true, motion: true };

    /// What `scene` with `params` uses: what a kernel specialised to it keeps. Every
    /// `false` is a value the kernels would compute anyway (no rod or body to loop over,
    /// Coulomb's coefficients zero, every collider's velocity and spin zero), so a
    /// specialised kernel computes the general one's bits.
    pub fn of(scene: &crate::Scene, params: &crate::SimParams) -> Uses {
        Uses {
            rods: !scene.rods.is_empty(),
            bodies: !scene.bodies.is_empty(),
            coulomb: params.coulomb(),
            motion: scene.moves(),
        }
    }

    /// What it keeps, in words: `rods, coulomb`, or `none`.
    pub fn kept(&self) -> String {
        let kept: Vec<&str> =
            [(self.rods, "rods"), (self.bodies, "bodies"), (self.coulomb, "coulomb"), (self.motion, "motion")]
                .into_iter()
                .filter_map(|(on, name)| on.then_some(name))
                .collect();
        if kept.is_empty() { "none".into() } else { kept.join(", ") }
    }

    /// The WGSL constants (`const USES_RODS: bool = true;` …).
    pub fn wgsl(&self) -> String {
        format!(
            "const USES_RODS: bool = {};\nconst USES_BODIES: bool = {};\nconst USES_COULOMB: bool = {};\nconst USES_MOTION: bool = {};\n",
            self.rods, self.bodies, self.coulomb, self.motion
        )
    }
}

/// The contact between triangles' scalars at the head of its integers ([`Buf::TriInts`]),
/// by index (u32 words; f32 values as bits): `core::cpu::tri_contact::at`.
pub mod tri_at {
    /// The fastest free vertex's speed (f32 bits: atomic max).
    pub const SPEED: usize = 0;
    /// The substep's reach (f32).
    pub const REACH: usize = 1;
    /// The grids' cell (f32).
    pub const CELL: usize = 2;
    /// The triangles' largest box extent, x y z (f32, atomic max).
    pub const EXTENT_T: usize = 3;
    /// The edges' largest box extent, x y z (f32, atomic max).
    pub const EXTENT_E: usize = 6;
    /// Pairs found in all.
    pub const PAIRS: usize = 9;
    /// Pairs found beyond an owner's [`super::TRI_SLOTS`] (left out of the responses).
    pub const OVERFLOW: usize = 10;
    /// Pairs the velocity pass slowed.
    pub const SLOWED: usize = 11;
    /// Pair pushes of the separation's passes.
    pub const PUSHED: usize = 12;
    /// Vertices the clamp cut.
    pub const CLAMPED: usize = 13;
    /// The free vertices' displacement sums: x low, x high, y low, y high, z low, z high.
    pub const MEAN: usize = 14;
    /// The free vertices.
    pub const FREE: usize = 20;
    /// 1 where some vertex is farther than its bound from the mean displacement.
    pub const OVER: usize = 21;
    /// 1 where some vertex moved farther than its bound.
    pub const MOVED: usize = 22;
    /// The scalars' words.
    pub const WORDS: usize = 32;
}

/// The WGSL `const` declarations of the values above (prepended to every kernel).
pub fn wgsl_constants() -> String {
    let u = |name: &str, v: u32| format!("const {name}: u32 = {v}u;\n");
    let mut s = String::from("// Generated by shaders/build.rs from clothlab_core::layout: do not edit.\n");
    s += &u("WORKGROUP", WORKGROUP);
    s += &u("SLOTS", SLOTS as u32);
    s += &u("STRAIN_SLOTS", STRAIN_SLOTS as u32);
    s += &u("FACE_SLOTS", FACE_SLOTS as u32);
    s += &u("TETHER_SLOTS", TETHER_SLOTS as u32);
    s += &u("BLOCK", BLOCK);
    s += &u("STRIP_ROWS", STRIP_ROWS);
    s += &u("TABLE_WIDTH", TABLE_WIDTH);
    s += &u("TRI_SLOTS", TRI_SLOTS);
    s += &u("ADJ_ROWS", ADJ_ROWS);
    s += &u("VBD_TERMS", crate::tri_contact::VBD_TERMS as u32);
    s += &u("TRI_QUERY_CELLS", TRI_QUERY_CELLS);
    s += &format!("const BIG_CELLS: f32 = {:?};\n", crate::broad::BIG_CELLS);
    {
        use tri_at as at;
        for (name, v) in [
            ("SPEED", at::SPEED),
            ("REACH", at::REACH),
            ("CELL", at::CELL),
            ("EXTENT_T", at::EXTENT_T),
            ("EXTENT_E", at::EXTENT_E),
            ("PAIRS", at::PAIRS),
            ("OVERFLOW", at::OVERFLOW),
            ("SLOWED", at::SLOWED),
            ("PUSHED", at::PUSHED),
            ("CLAMPED", at::CLAMPED),
            ("MEAN", at::MEAN),
            ("FREE", at::FREE),
            ("OVER", at::OVER),
            ("MOVED", at::MOVED),
            ("WORDS", at::WORDS),
        ] {
            s += &u(&format!("TRI_AT_{name}"), v as u32);
        }
    }
    s += &format!("const CONTACT_UNITS: f32 = {:?};\n", crate::tables::CONTACT_UNITS);
    s += &format!("const TRI_BOUND_FRACTION: f32 = {:?};\n", crate::tri_contact::BOUND_FRACTION);
    s += &format!("const TRI_REACH_PER_MOTION: f32 = {:?};\n", crate::tri_contact::REACH_PER_MOTION);
    // tri_start.wgsl writes the reach's cap as t + (s + s).
    const _: () = assert!(crate::tri_contact::MAX_REACH_SPACINGS == 2.0);
    s += &format!("const TRI_MEAN_UNIT: f32 = {:?};\n", crate::tri_contact::MEAN_UNIT);
    s += &u("MAX_COLLIDERS", crate::scene::MAX_COLLIDERS as u32);
    s += &u("SDF_HEAD_FLOATS", crate::sdf::SdfHead::FLOATS as u32);
    s += &u("SHAPES_RODS_AT", crate::sdf::RODS_AT as u32);
    for kind in crate::scene::RodKind::ALL {
        s += &format!("const ROD_{}: f32 = {:?};\n", kind.name().to_uppercase(), kind.mark());
    }
    s += &u("SHAPES_VALUES_AT", crate::sdf::VALUES_AT as u32);
    s += &u("MAX_PIN_GROUPS", crate::pins::MAX_PIN_GROUPS as u32);
    s += &format!("const STRAIN_AIM: f32 = {STRAIN_AIM:?};\n");
    s += &Uses::ALL.wgsl();
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_number_themselves_in_order() {
        for (k, b) in Buf::ALL.iter().enumerate() {
            assert_eq!(b.binding(), k as u32);
            assert_eq!(Buf::from_binding(k as u32), Some(*b));
        }
        assert_eq!(Buf::from_binding(Buf::ALL.len() as u32), None);
    }

    #[test]
    fn the_wgsl_constants_carry_the_rust_values() {
        let s = wgsl_constants();
        assert!(s.contains("const BLOCK: u32 = 4u;") && s.contains("const SLOTS: u32 = 12u;"), "{s}");
        assert!(s.contains(&format!("const STRAIN_AIM: f32 = {STRAIN_AIM:?};")), "{s}");
    }
}
