//! Variants as sets of switches: each CUDA-style optimisation of the step is one
//! independent choice, so that each can be measured alone (`clothlab bench --ladder`).
//! `naive`, `optimized` and `thesis` are presets, names for sets of switches; `--variant`
//! names a preset and `--set-variant key=value` changes one switch of it.
//!
//! A switch the adapter lacks, or two that exclude each other, is refused with one line
//! naming the switch ([`Variant::check`]); a preset instead falls back to what the adapter
//! has ([`VariantSpec::resolve`]), so that `naive` and `optimized` run everywhere.

use std::fmt;

use crate::kernels::{ConstantsHome, Flavor};

/// What the adapter offers that the recipes use.
#[derive(Debug, Clone, Copy)]
pub struct Caps {
    /// `atomic<f32>` add in storage buffers.
    pub float_atomics: bool,
    /// Immediates (push constants) large enough for the step constants.
    pub immediates: bool,
    /// The engine can read the spring table from a sampled image (`<kernel>_tex` twins:
    /// the thesis's texture memory).
    pub table_image: bool,
    /// Subgroup arithmetic and relative shuffles in compute shaders (`neighbours=shuffle`).
    pub subgroups: bool,
    /// The cloth is an n × n grid (not the adapter's: the cloth's). A mesh has no
    /// neighbours by offset and no constants shared by every particle (`table=uniform`)
    /// and no rows whose blocks lanes could pass each other (`neighbours=shuffle`).
    pub grid: bool,
    /// The bodies' distance fields in a 3-D image sampled through a trilinear sampler of
    /// 32-bit floats (`sdf=image`, the `_si` twins).
    pub sdf_image: bool,
    /// Workgroup memory for the tiled substep's region
    /// ([`crate::kernels::TILE_WORKGROUP_BYTES`], `fusion=tile`).
    pub tile: bool,
    /// The adapter runs on the CPU ([`crate::gpu::EngineInfo::cpu`]).
    pub cpu: bool,
}

/// How the forces of springs reach the particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Accumulate {
    /// One invocation per spring, added into both ends with atomics.
    Scatter,
    /// One invocation per particle, summing what acts on it: no atomics.
    Gather,
}

/// How the vertex normals (and the wind, which the faces' normals give) are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Normals {
    /// Every substep, one invocation per triangle, added into the corners with atomics.
    Scatter,
    /// Every substep, one invocation per vertex, summing its stored face normals.
    Gather,
    /// Once per frame, gathered, for drawing: within the frame the forces gather computes
    /// the wind of the faces around each particle itself from the positions it loads
    /// (Verlet and symplectic Euler with `fusion=clothlab`; the other integrators' force
    /// kernels read the wind from the buffer, so they keep the normals every substep).
    Frame,
}

/// Which atomics the scatters add with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Atomics {
    /// `atomic<f32>` add (float atomics: Vulkan's shaderBufferFloat32AtomicAdd).
    Float,
    /// A compare-exchange loop on the float's bits (works everywhere).
    Cas,
}

/// Which kernels of the step are fused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fusion {
    /// One dispatch per kernel: forces, springs, integrate, collide.
    None,
    /// The forces into the integration: springs alone, then forces + Verlet + collisions
    /// in one kernel (the thesis's fusion; the switch's value `thesis`).
    IntoIntegrate,
    /// The forces into the springs' gather (four particles of a row per invocation),
    /// then integrate + collide in one kernel (the switch's value `clothlab`).
    IntoGather,
    /// The whole Verlet substep in one dispatch over tiles of the grid held in workgroup
    /// memory with a halo as deep as the stages reach (`substep_tile`), its velocities put
    /// into place by a copy (`tile_vel`). Other integrators, meshes and more strain passes
    /// than [`crate::recipe::TILE_MAX_PASSES`] run clothlab's fusion.
    Tile,
}

/// How many substeps one dispatch of the tiled substep advances (temporal blocking).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Temporal {
    /// One.
    Off,
    /// As many as divide the frame's substeps and leave tiles of at least
    /// [`crate::recipe::TILE_MIN_SIDE`] (the halo grows with each); a whole frame where the
    /// cloth fits one region (`recipe::dispatch_substeps`). Needs `fusion=tile`.
    On,
}

/// How often the step is submitted to the queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Submit {
    /// One submission per substep (the last one waited for).
    Substep,
    /// One submission per frame.
    Frame,
}

/// Where the step constants live.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Constants {
    /// A read-only storage buffer.
    Storage,
    /// A uniform buffer (constant memory).
    Uniform,
    /// Immediates (push constants), recorded into the command buffer.
    Push,
}

/// Where the collide kernels read the bodies' distance fields from (`crate::kernels`'
/// `_si` twins; `core::sdf`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sdf {
    /// The values in the shapes' storage buffer, interpolated by the kernel (eight loads):
    /// the CPU twins' arithmetic, bit for bit on llvmpipe.
    Storage,
    /// A 3-D `r32float` image the texture unit interpolates (the thesis's texture memory):
    /// one filtered sample for φ, the cell's eight texels for the interpolant's gradient
    /// (the twin's normal); within the filter's precision of the twins.
    Image,
}

/// Whether the kernels are compiled for the scene (`core::layout::Uses`): the collider
/// walk's code for rods, bodies, Coulomb friction and moving surfaces kept only where the
/// scene has them. The same bits either way (what is dropped computes nothing the scene
/// needs); what it buys is measured by the ladder's rung.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Specialize {
    /// The kernels as built: every scene's code.
    Off,
    /// Each kernel rebuilt with the scene's `USES_*` constants when the solver is made
    /// (and again when a parameter changes what it uses: Coulomb's coefficients).
    On,
}

/// Where the strain limit's pass gets the counts it divides by (the springs over their
/// limit at each end: core::cpu::strain_limit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StrainCounts {
    /// A count dispatch before each pass writes every particle's count (aux0); the pass
    /// reads them.
    Dispatch,
    /// The pass counts for itself: its own count from the window it loads, a neighbour's
    /// only for a spring over its limit (two rings out). One dispatch and one write and read
    /// of the counts fewer per pass; the same counts, the same bits.
    Inline,
    /// The pass counts for itself down strips of rows: an invocation carries a block's
    /// columns through `STRIP_ROWS` rows, each spring's length computed once for the counts
    /// of both its ends and for the pass. Fewer invocations (a sixteenth), less arithmetic;
    /// the same counts, the same bits.
    Strip,
}

/// Where the gathers read the spring table from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Table {
    /// Every particle reads its 12 slots from read-only storage buffers.
    Storage,
    /// Every particle reads its slots from a sampled image (the thesis's texture memory).
    Image,
    /// The springs' constants in a uniform block and neighbours by offset on the regular
    /// grid (storage buffers only for an irregular table).
    Uniform,
}

/// Where the sphere and box colliders live.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Colliders {
    /// Read-only storage buffers.
    Storage,
    /// Uniform blocks (the thesis's constant memory).
    Uniform,
}

/// How the blocked gathers get the points beside their own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Neighbours {
    /// Every lane loads its whole window.
    Load,
    /// Lanes holding consecutive blocks of a row pass each other their points by subgroup
    /// shuffles (the warp-shuffle idiom of CUDA).
    Shuffle,
}

/// What the renderer draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Draw {
    /// Vertex buffers of their own, which every frame's positions and normals are copied
    /// into at its end (what an API without shared buffers does).
    Copy,
    /// The simulation's own position and normal buffers (shared between compute and
    /// drawing: no copy).
    Shared,
}

/// A formulation of the step: one value per switch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Variant {
    /// Spring forces: scattered with atomics or gathered per particle.
    pub springs: Accumulate,
    /// Vertex normals: face normals scattered into the corners, or gathered per vertex,
    /// every substep; or gathered once per frame, the wind computed in the forces gather.
    pub normals: Normals,
    /// The scatters' atomics.
    pub atomics: Atomics,
    /// Which kernels are fused.
    pub fusion: Fusion,
    /// Submissions per frame.
    pub submit: Submit,
    /// Where the step constants live.
    pub constants: Constants,
    /// Where the spring table lives.
    pub table: Table,
    /// Where the colliders live.
    pub colliders: Colliders,
    /// Neighbour positions in the blocked gathers: loaded, or passed by shuffles.
    pub neighbours: Neighbours,
    /// What the renderer draws from.
    pub draw: Draw,
    /// Substeps per dispatch of the tiled substep.
    pub temporal: Temporal,
    /// Where the bodies' distance fields are read from.
    pub sdf: Sdf,
    /// Whether the kernels are compiled for the scene.
    pub specialize: Specialize,
    /// Where the strain limit's pass gets its counts.
    pub strain_counts: StrainCounts,
}

/// One switch: its key, its values (in ladder order: the naive one first) and what it
/// chooses.
#[derive(Debug, Clone, Copy)]
pub struct Switch {
    /// The key of `--set-variant key=value`.
    pub key: &'static str,
    /// Its values.
    pub values: &'static [&'static str],
    /// What it chooses, in one line.
    pub help: &'static str,
}

/// Every switch.
pub const SWITCHES: [Switch; 14] = [
    Switch {
        key: "springs",
        values: &["scatter", "gather"],
        help: "spring forces: per spring with atomics, or per particle",
    },
    Switch {
        key: "normals",
        values: &["scatter", "gather", "frame"],
        help: "vertex normals: per triangle with atomics, or per vertex, every substep; or once per frame, the wind in the forces gather",
    },
    Switch {
        key: "atomics",
        values: &["float", "cas"],
        help: "the scatters' atomics: float add, or a compare-exchange loop",
    },
    Switch {
        key: "fusion",
        values: &["none", "thesis", "clothlab", "tile"],
        help: "none; the thesis's forces+Verlet+collisions; clothlab's forces+springs and integrate+collide; the whole substep in one dispatch over workgroup-memory tiles",
    },
    Switch { key: "submit", values: &["substep", "frame"], help: "one queue submission per substep, or per frame" },
    Switch {
        key: "constants",
        values: &["storage", "uniform", "push"],
        help: "the step constants: storage buffer, uniform buffer, or immediates (push constants)",
    },
    Switch {
        key: "table",
        values: &["storage", "image", "uniform"],
        help: "the spring table: storage buffers, a sampled image, or a uniform block with neighbours by offset",
    },
    Switch { key: "colliders", values: &["storage", "uniform"], help: "spheres and boxes: storage or uniform buffers" },
    Switch {
        key: "neighbours",
        values: &["load", "shuffle"],
        help: "the blocked gathers' neighbour positions: loaded, or passed between lanes by subgroup shuffles",
    },
    Switch {
        key: "draw",
        values: &["copy", "shared"],
        help: "the renderer draws from copies made every frame, or from the simulation's own buffers",
    },
    Switch {
        key: "temporal",
        values: &["off", "on"],
        help: "the tiled substep advances one substep per dispatch, or several with a deeper halo (a whole frame where the cloth fits one tile); needs fusion=tile",
    },
    Switch {
        key: "sdf",
        values: &["storage", "image"],
        help: "the bodies' distance fields: a storage buffer interpolated by the kernel, or a 3-D image the texture unit interpolates",
    },
    Switch {
        key: "specialize",
        values: &["off", "on"],
        help: "the kernels as built for every scene, or compiled for the scene: the code for rods, bodies, Coulomb friction and moving colliders only where it has them",
    },
    Switch {
        key: "strain_counts",
        values: &["dispatch", "inline", "strip"],
        help: "the strain limit's counts of springs over their limit: a count dispatch before each pass, counted by the pass itself where it needs them, or by a pass down strips of rows that computes each spring's length once",
    },
];

/// The presets, by name.
pub const PRESETS: [(&str, Variant); 3] =
    [("naive", Variant::NAIVE), ("optimized", Variant::OPTIMIZED), ("thesis", Variant::THESIS)];

impl Variant {
    /// The direct port: every kernel on its own, scatters with float atomics, a
    /// submission per substep, everything read from storage buffers, the renderer's
    /// vertex buffers copies.
    pub const NAIVE: Variant = Variant {
        springs: Accumulate::Scatter,
        normals: Normals::Scatter,
        atomics: Atomics::Float,
        fusion: Fusion::None,
        submit: Submit::Substep,
        constants: Constants::Storage,
        table: Table::Storage,
        colliders: Colliders::Storage,
        neighbours: Neighbours::Load,
        draw: Draw::Copy,
        temporal: Temporal::Off,
        sdf: Sdf::Storage,
        specialize: Specialize::Off,
        strain_counts: StrainCounts::Dispatch,
    };
    /// clothlab's optimized step, the [`LADDER`]'s rung before the tiles (every earlier
    /// rung's switch set; `fusion=tile` is left out: slower on lavapipe and on the H100,
    /// docs/variants.md):
    /// gathers, its fusion with the wind computed in the forces gather and the normals once
    /// per frame, one submission per frame, push constants, the table as uniform constants
    /// with neighbours by offset, colliders in a uniform block, neighbours' columns by
    /// subgroup shuffles, the kernels compiled for the scene, the strain pass counting for
    /// itself down strips of rows. [`Variant::fit`] falls back where an adapter lacks a
    /// switch (no subgroups: loads; no push constants: a uniform block) and, on a GPU,
    /// counts inline instead of down strips (the strips keep few of a GPU's lanes busy). Measured on lavapipe
    /// (docs/variants.md) it is the fastest combination the ladder reached on both APIs,
    /// and `validate --every-switch` checks it against the twins like every rung.
    pub const OPTIMIZED: Variant = Variant {
        springs: Accumulate::Gather,
        normals: Normals::Frame,
        atomics: Atomics::Float,
        fusion: Fusion::IntoGather,
        submit: Submit::Frame,
        constants: Constants::Push,
        table: Table::Uniform,
        colliders: Colliders::Uniform,
        neighbours: Neighbours::Shuffle,
        draw: Draw::Shared,
        temporal: Temporal::Off,
        sdf: Sdf::Storage,
        specialize: Specialize::On,
        strain_counts: StrainCounts::Strip,
    };
    /// The thesis's optimized CUDA program (ch. 6.3.1): springs scattered with atomics,
    /// forces + Verlet + collisions fused, normals gathered from stored face normals, the
    /// spring table in texture memory, the spheres and the constants in constant memory.
    pub const THESIS: Variant = Variant {
        springs: Accumulate::Scatter,
        normals: Normals::Gather,
        atomics: Atomics::Float,
        fusion: Fusion::IntoIntegrate,
        submit: Submit::Frame,
        constants: Constants::Uniform,
        table: Table::Image,
        colliders: Colliders::Uniform,
        neighbours: Neighbours::Load,
        draw: Draw::Shared,
        temporal: Temporal::Off,
        sdf: Sdf::Storage,
        specialize: Specialize::Off,
        strain_counts: StrainCounts::Dispatch,
    };

    /// Which value of switch `key` it has: the position in the switch's
    /// [`Switch::values`] (each enum's variants are declared in that order, the naive one
    /// first).
    fn position(&self, key: &str) -> Option<usize> {
        Some(match key {
            "springs" => self.springs as usize,
            "normals" => self.normals as usize,
            "atomics" => self.atomics as usize,
            "fusion" => self.fusion as usize,
            "submit" => self.submit as usize,
            "constants" => self.constants as usize,
            "table" => self.table as usize,
            "colliders" => self.colliders as usize,
            "neighbours" => self.neighbours as usize,
            "draw" => self.draw as usize,
            "temporal" => self.temporal as usize,
            "sdf" => self.sdf as usize,
            "specialize" => self.specialize as usize,
            "strain_counts" => self.strain_counts as usize,
            _ => return None,
        })
    }

    /// The value of switch `key`.
    pub fn get(&self, key: &str) -> Option<&'static str> {
        let i = self.position(key)?;
        SWITCHES.iter().find(|s| s.key == key).and_then(|s| s.values.get(i).copied())
    }

    /// Sets switch `key` to `value`; an unknown key or value is refused in one line
    /// listing the known ones.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), VariantError> {
        let switch = SWITCHES.iter().find(|s| s.key == key).ok_or_else(|| {
            VariantError(format!(
                "unknown variant switch `{key}`: the switches are {}",
                SWITCHES.iter().map(|s| s.key).collect::<Vec<_>>().join(", ")
            ))
        })?;
        let i = switch.values.iter().position(|v| *v == value).ok_or_else(|| {
            VariantError(format!("switch {key}={value}: {key} is one of {}", switch.values.join(", ")))
        })?;
        let acc = [Accumulate::Scatter, Accumulate::Gather];
        match key {
            "springs" => self.springs = acc[i],
            "normals" => self.normals = [Normals::Scatter, Normals::Gather, Normals::Frame][i],
            "atomics" => self.atomics = [Atomics::Float, Atomics::Cas][i],
            "fusion" => self.fusion = [Fusion::None, Fusion::IntoIntegrate, Fusion::IntoGather, Fusion::Tile][i],
            "submit" => self.submit = [Submit::Substep, Submit::Frame][i],
            "constants" => self.constants = [Constants::Storage, Constants::Uniform, Constants::Push][i],
            "table" => self.table = [Table::Storage, Table::Image, Table::Uniform][i],
            "colliders" => self.colliders = [Colliders::Storage, Colliders::Uniform][i],
            "neighbours" => self.neighbours = [Neighbours::Load, Neighbours::Shuffle][i],
            "draw" => self.draw = [Draw::Copy, Draw::Shared][i],
            "sdf" => self.sdf = [Sdf::Storage, Sdf::Image][i],
            "specialize" => self.specialize = [Specialize::Off, Specialize::On][i],
            "strain_counts" => {
                self.strain_counts = [StrainCounts::Dispatch, StrainCounts::Inline, StrainCounts::Strip][i]
            }
            _ => self.temporal = [Temporal::Off, Temporal::On][i],
        }
        Ok(())
    }

    /// The preset named `name`.
    pub fn preset(name: &str) -> Result<Variant, VariantError> {
        PRESETS.iter().find(|(n, _)| *n == name).map(|(_, v)| *v).ok_or_else(|| {
            VariantError(format!(
                "unknown variant `{name}`: the presets are {}",
                PRESETS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ))
        })
    }

    /// Every switch as `key=value`, comma-separated.
    pub fn switches(&self) -> String {
        SWITCHES.iter().map(|s| format!("{}={}", s.key, self.get(s.key).unwrap_or("?"))).collect::<Vec<_>>().join(",")
    }

    /// The name of a solver of this variant: `prefix` alone for the optimized preset
    /// (`wgpu`, `vulkan`: the backends' names), else `<prefix>-<label>`
    /// (`vulkan-naive`, `wgpu-thesis+table=storage`).
    pub fn solver_name(&self, prefix: &str) -> String {
        match self.label().as_str() {
            "optimized" => prefix.to_string(),
            label => format!("{prefix}-{label}"),
        }
    }

    /// A short name: the preset it is, or the closest preset plus the switches that
    /// differ (`naive+submit=frame`).
    pub fn label(&self) -> String {
        let diff = |p: &Variant| -> Vec<String> {
            SWITCHES
                .iter()
                .filter(|s| self.get(s.key) != p.get(s.key))
                .map(|s| format!("{}={}", s.key, self.get(s.key).unwrap_or("?")))
                .collect()
        };
        let (name, d) =
            PRESETS.iter().map(|(n, p)| (*n, diff(p))).min_by_key(|(_, d)| d.len()).expect("there are presets");
        if d.is_empty() { name.to_string() } else { format!("{name}+{}", d.join("+")) }
    }

    /// Whether it runs on an adapter with `caps`, and whether its switches fit together:
    /// the first that does not, in one line naming the switch.
    pub fn check(&self, caps: &Caps, api: &str) -> Result<(), VariantError> {
        let scatters = self.springs == Accumulate::Scatter || self.normals == Normals::Scatter;
        if scatters && self.atomics == Atomics::Float && !caps.float_atomics {
            return Err(VariantError(format!(
                "switch atomics=float: this adapter has no float atomic add on {api}; use atomics=cas"
            )));
        }
        if self.constants == Constants::Push && !caps.immediates {
            return Err(VariantError(format!(
                "switch constants=push: this adapter has no immediates (push constants) for the step constants on {api}; use constants=uniform"
            )));
        }
        if self.table == Table::Image && !caps.table_image {
            return Err(VariantError(format!(
                "switch table=image: the {api} engine has no spring-table image; use table=storage or table=uniform"
            )));
        }
        if self.sdf == Sdf::Image && !caps.sdf_image {
            return Err(VariantError(format!(
                "switch sdf=image: the {api} engine on this adapter has no filtered 3-D image of 32-bit floats for the bodies' distance fields; use sdf=storage"
            )));
        }
        if self.table == Table::Uniform && !caps.grid {
            return Err(VariantError(
                "switch table=uniform: a mesh has no neighbours by offset nor spring constants shared by every particle; use table=storage or table=image".into(),
            ));
        }
        if self.neighbours == Neighbours::Shuffle && !caps.grid {
            return Err(VariantError(
                "switch neighbours=shuffle: a mesh has no grid rows whose blocks lanes could pass each other; use neighbours=load".into(),
            ));
        }
        if self.neighbours == Neighbours::Shuffle && !caps.subgroups {
            return Err(VariantError(format!(
                "switch neighbours=shuffle: this adapter has no subgroup shuffles in compute shaders on {api}; use neighbours=load"
            )));
        }
        if self.normals == Normals::Frame && !matches!(self.fusion, Fusion::IntoGather | Fusion::Tile) {
            return Err(VariantError(
                "switch normals=frame needs fusion=clothlab or fusion=tile: the wind is computed inside clothlab's forces+springs gather".into(),
            ));
        }
        if self.fusion == Fusion::Tile {
            if !caps.grid {
                return Err(VariantError(
                    "switch fusion=tile: a mesh has no grid to cut into tiles; use fusion=clothlab".into(),
                ));
            }
            if !caps.tile {
                return Err(VariantError(format!(
                    "switch fusion=tile: this adapter has less than the {} KiB of workgroup memory a tile needs on {api}; use fusion=clothlab",
                    crate::kernels::TILE_WORKGROUP_BYTES / 1024
                )));
            }
            if self.springs == Accumulate::Scatter || self.normals != Normals::Frame || self.table != Table::Uniform {
                return Err(VariantError(
                    "switch fusion=tile needs springs=gather, normals=frame and table=uniform: the tile computes the grid's springs and wind from the points it holds".into(),
                ));
            }
        }
        if self.temporal == Temporal::On && !caps.grid {
            return Err(VariantError(
                "switch temporal=on: a mesh has no grid to cut into tiles; use temporal=off".into(),
            ));
        }
        if self.temporal == Temporal::On && self.fusion != Fusion::Tile {
            return Err(VariantError(
                "switch temporal=on needs fusion=tile: several substeps per dispatch are the tiles' deeper halo".into(),
            ));
        }
        if self.fusion == Fusion::IntoGather && self.springs == Accumulate::Scatter {
            return Err(VariantError(
                "switches fusion=clothlab and springs=scatter exclude each other: clothlab's fusion puts forces into the spring gather (use springs=gather, or fusion=none|thesis)".into(),
            ));
        }
        Ok(())
    }

    /// The variant with what `caps` lack replaced by the nearest thing they have (how a
    /// preset runs everywhere).
    pub fn fit(mut self, caps: &Caps) -> Variant {
        if !caps.float_atomics {
            self.atomics = Atomics::Cas;
        }
        if !caps.immediates && self.constants == Constants::Push {
            self.constants = Constants::Uniform;
        }
        if !caps.table_image && self.table == Table::Image {
            self.table = Table::Storage;
        }
        if !caps.sdf_image {
            self.sdf = Sdf::Storage;
        }
        if !caps.subgroups || !caps.grid {
            self.neighbours = Neighbours::Load;
        }
        if !caps.grid && self.table == Table::Uniform {
            self.table = Table::Storage;
        }
        if self.fusion == Fusion::Tile && (!caps.grid || !caps.tile || self.table != Table::Uniform) {
            self.fusion = Fusion::IntoGather;
        }
        if self.fusion != Fusion::Tile {
            self.temporal = Temporal::Off;
        }
        // The strain pass down strips runs a sixteenth of the invocations: on a CPU
        // adapter that costs nothing and its lengths computed once are the gain; a GPU
        // would keep few of its lanes busy, so there the pass counts inline.
        if !caps.cpu && self.strain_counts == StrainCounts::Strip {
            self.strain_counts = StrainCounts::Inline;
        }
        self
    }

    /// The shader flavor its kernels are picked in.
    pub fn flavor(&self) -> Flavor {
        Flavor {
            constants: match self.constants {
                Constants::Storage => ConstantsHome::Storage,
                Constants::Uniform => ConstantsHome::Uniform,
                Constants::Push => ConstantsHome::Immediates,
            },
            table_image: self.table == Table::Image,
            float_atomics: self.atomics == Atomics::Float,
            colliders_uniform: self.colliders == Colliders::Uniform,
            shuffle: self.neighbours == Neighbours::Shuffle,
            sdf_image: self.sdf == Sdf::Image,
        }
    }
}

/// The optimisation ladder: from `naive`, one switch at a time, in this order (each rung
/// keeps the switches of the rungs before it).
pub const LADDER: [(&str, &str); 19] = [
    ("submit", "frame"),
    ("draw", "shared"),
    ("constants", "uniform"),
    ("constants", "push"),
    ("colliders", "uniform"),
    ("normals", "gather"),
    ("springs", "gather"),
    ("fusion", "thesis"),
    ("fusion", "clothlab"),
    ("table", "image"),
    ("table", "uniform"),
    ("neighbours", "shuffle"),
    ("normals", "frame"),
    // The kernels compiled for the scene: the code for rods, bodies, Coulomb friction and
    // moving colliders only where it has them (docs/bench/lavapipe-specialise).
    ("specialize", "on"),
    // The strain limit's pass counting for itself: no count dispatch
    // (docs/bench/lavapipe-strain-inline).
    ("strain_counts", "inline"),
    // The strain pass down strips of rows, each length computed once: the optimized
    // preset's on a CPU adapter (docs/bench/lavapipe-strain-strip).
    ("strain_counts", "strip"),
    ("fusion", "tile"),
    ("temporal", "on"),
    // The bodies' fields from the image: measures something only on a scene with bodies
    // (`bench --ladder --scene scenes/body-sphere.toml`); last, so that `optimized` stays
    // the rung before the tiles and computes the twins' bits.
    ("sdf", "image"),
];

/// One rung of the ladder.
#[derive(Debug, Clone)]
pub struct Rung {
    /// The switch it sets (`None`: the first rung, naive).
    pub step: Option<(&'static str, &'static str)>,
    /// The variant it runs (the rung before's when skipped).
    pub variant: Variant,
    /// Why the rung is skipped on this adapter (the switch it lacks).
    pub skipped: Option<String>,
}

impl Rung {
    /// The rung's name: `naive`, or the switch it sets (`+submit=frame`).
    pub fn name(&self) -> String {
        match self.step {
            None => "naive".into(),
            Some((k, v)) => format!("+{k}={v}"),
        }
    }
}

/// The ladder on an adapter with `caps`: naive (fitted to the adapter), then one rung per
/// [`LADDER`] step; a step the adapter lacks is kept as a skipped rung with the reason.
pub fn ladder(caps: &Caps, api: &str) -> Vec<Rung> {
    let mut v = Variant::NAIVE.fit(caps);
    let mut rungs = vec![Rung { step: None, variant: v, skipped: None }];
    for (k, val) in LADDER {
        let mut next = v;
        let ok = next.set(k, val).and_then(|_| next.check(caps, api));
        match ok {
            Ok(()) => {
                v = next;
                rungs.push(Rung { step: Some((k, val)), variant: v, skipped: None });
            }
            Err(e) => rungs.push(Rung { step: Some((k, val)), variant: v, skipped: Some(e.0) }),
        }
    }
    rungs
}

/// Variants that together set every switch to every value the adapter has at least once,
/// each in a recipe: the ladder's rungs, the thesis preset, and naive with the other
/// atomics. What `clothlab validate --every-switch` rolls out.
pub fn covering(caps: &Caps, api: &str) -> Vec<Variant> {
    let mut v: Vec<Variant> =
        ladder(caps, api).into_iter().filter(|r| r.skipped.is_none()).map(|r| r.variant).collect();
    let mut cas = Variant::NAIVE.fit(caps);
    cas.atomics = if cas.atomics == Atomics::Float { Atomics::Cas } else { Atomics::Float };
    // The image's rung sits on the temporal one, which a moving scene refuses: it is also
    // covered on `optimized`.
    let mut image = Variant::OPTIMIZED.fit(caps);
    image.sdf = Sdf::Image;
    for extra in [Variant::THESIS.fit(caps), cas, image] {
        if extra.check(caps, api).is_ok() && !v.contains(&extra) {
            v.push(extra);
        }
    }
    v
}

impl fmt::Display for Variant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.label())
    }
}

/// A refused variant, in one line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct VariantError(pub String);

/// A variant as the user asked for it: a preset (which falls back to what the adapter
/// has) and the switches set explicitly (which are refused where the adapter lacks them).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VariantSpec {
    /// The preset.
    pub base: Variant,
    /// `key=value` changes on top, in order.
    pub set: Vec<(String, String)>,
}

impl From<Variant> for VariantSpec {
    fn from(base: Variant) -> Self {
        Self { base, set: Vec::new() }
    }
}

impl VariantSpec {
    /// Exactly `v`: every switch set explicitly, so that one the adapter lacks is refused
    /// rather than replaced (what the app asks for when a switch is picked by hand).
    pub fn exact(v: Variant) -> VariantSpec {
        VariantSpec {
            base: v,
            set: SWITCHES.iter().map(|s| (s.key.to_string(), v.get(s.key).unwrap_or_default().to_string())).collect(),
        }
    }

    /// `preset` with the `key=value` changes of `set` (each checked as a switch now).
    pub fn parse(preset: &str, set: &[String]) -> Result<VariantSpec, VariantError> {
        let base = Variant::preset(preset)?;
        let mut spec = VariantSpec { base, set: Vec::new() };
        let mut probe = base;
        for s in set {
            let (k, v) = s
                .split_once('=')
                .ok_or_else(|| VariantError(format!("--set-variant {s}: expected key=value, e.g. fusion=thesis")))?;
            let (k, v) = (k.trim(), v.trim());
            probe.set(k, v)?;
            spec.set.push((k.to_string(), v.to_string()));
        }
        Ok(spec)
    }

    /// The variant to run on an adapter with `caps`: the preset fitted to them, then the
    /// explicit switches, all checked.
    pub fn resolve(&self, caps: &Caps, api: &str) -> Result<Variant, VariantError> {
        let mut v = self.base.fit(caps);
        for (k, val) in &self.set {
            v.set(k, val)?;
        }
        // A preset's tiles give way to clothlab's fusion where a switch set on top takes
        // away what they need (`optimized` with normals=gather); fusion=tile named
        // explicitly is refused instead.
        let tile_needs = v.springs == Accumulate::Gather && v.normals == Normals::Frame && v.table == Table::Uniform;
        if v.fusion == Fusion::Tile && !tile_needs && !self.set.iter().any(|(k, _)| k == "fusion") {
            v.fusion = Fusion::IntoGather;
            if !self.set.iter().any(|(k, _)| k == "temporal") {
                v.temporal = Temporal::Off;
            }
        }
        v.check(caps, api)?;
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An adapter with nothing optional but the tile's workgroup memory, running a grid.
    const BARE_CAPS: Caps = Caps {
        float_atomics: false,
        immediates: false,
        table_image: false,
        subgroups: false,
        grid: true,
        tile: true,
        sdf_image: false,
        cpu: false,
    };

    const ALL_CAPS: Caps = Caps {
        float_atomics: true,
        immediates: true,
        table_image: true,
        subgroups: true,
        grid: true,
        tile: true,
        sdf_image: true,
        cpu: true,
    };

    #[test]
    fn every_switch_value_round_trips_and_bad_ones_name_the_switch() {
        for s in SWITCHES {
            for v in s.values {
                let mut x = Variant::NAIVE;
                x.set(s.key, v).unwrap();
                assert_eq!(x.get(s.key), Some(*v));
            }
        }
        let e = Variant::NAIVE.clone().set("fusion", "cuda").unwrap_err().0;
        assert!(e.contains("fusion=cuda") && e.contains("none, thesis, clothlab"), "{e}");
        assert!(Variant::preset("fast").unwrap_err().0.contains("naive, optimized, thesis"));
        assert!(VariantSpec::parse("naive", &["fusion".into()]).unwrap_err().0.contains("key=value"));
    }

    #[test]
    fn presets_fit_the_adapter_and_explicit_switches_are_refused_where_it_lacks_them() {
        let bare = BARE_CAPS;
        let opt = VariantSpec::from(Variant::OPTIMIZED).resolve(&bare, "wgpu").unwrap();
        assert_eq!((opt.constants, opt.atomics, opt.neighbours), (Constants::Uniform, Atomics::Cas, Neighbours::Load));
        // A GPU counts inline; a CPU adapter down strips; either named by hand is run.
        assert_eq!(opt.strain_counts, StrainCounts::Inline);
        let on_cpu = VariantSpec::from(Variant::OPTIMIZED).resolve(&Caps { cpu: true, ..bare }, "wgpu").unwrap();
        assert_eq!(on_cpu.strain_counts, StrainCounts::Strip);
        let strips = VariantSpec::parse("optimized", &["strain_counts=strip".into()]).unwrap();
        assert_eq!(strips.resolve(&bare, "wgpu").unwrap().strain_counts, StrainCounts::Strip);
        let thesis = VariantSpec::from(Variant::THESIS).resolve(&bare, "wgpu").unwrap();
        assert_eq!(thesis.table, Table::Storage);
        assert!(VariantSpec::exact(Variant::THESIS).resolve(&bare, "wgpu").unwrap_err().0.contains("atomics=float"));
        let strict = VariantSpec::parse("naive", &["constants=push".into()]).unwrap();
        assert!(strict.resolve(&bare, "wgpu").unwrap_err().0.contains("constants=push"));
        assert!(strict.resolve(&ALL_CAPS, "vulkan").is_ok());
        let clash = VariantSpec::parse("naive", &["fusion=clothlab".into()]).unwrap();
        let e = clash.resolve(&ALL_CAPS, "vulkan").unwrap_err().0;
        assert!(e.contains("fusion=clothlab") && e.contains("springs=scatter"), "{e}");
        let clash = VariantSpec::parse("thesis", &["normals=frame".into()]).unwrap();
        let e = clash.resolve(&ALL_CAPS, "vulkan").unwrap_err().0;
        assert!(e.contains("normals=frame") && e.contains("fusion=clothlab"), "{e}");
        assert!(
            VariantSpec::parse("optimized", &["normals=gather".into()]).unwrap().resolve(&ALL_CAPS, "wgpu").is_ok()
        );
    }

    #[test]
    fn the_ladder_climbs_from_naive_to_optimized_and_skips_what_the_adapter_lacks() {
        let rungs = ladder(&ALL_CAPS, "vulkan");
        assert_eq!(rungs.len(), LADDER.len() + 1);
        assert_eq!(rungs[0].variant, Variant::NAIVE);
        assert!(rungs.iter().all(|r| r.skipped.is_none()));
        // The rung before the tiles is the optimized preset: the preset is what the ladder
        // measured fastest on lavapipe (issue 32; the tiles lost there, issue 47), so a new
        // rung must update both.
        assert_eq!(rungs[rungs.len() - 4].variant, Variant::OPTIMIZED);
        let mut top = Variant::OPTIMIZED;
        top.set("fusion", "tile").unwrap();
        assert_eq!(rungs[rungs.len() - 3].variant, top);
        top.set("temporal", "on").unwrap();
        assert_eq!(rungs[rungs.len() - 2].variant, top);
        let mut image = top;
        image.set("sdf", "image").unwrap();
        assert_eq!(rungs.last().unwrap().variant, image);
        // Temporal blocking without the tiles: refused, and a preset's dropped.
        let e = VariantSpec::parse("optimized", &["temporal=on".into(), "fusion=clothlab".into()])
            .unwrap()
            .resolve(&ALL_CAPS, "vulkan")
            .unwrap_err();
        assert!(e.0.contains("temporal=on") && e.0.contains("fusion=tile"), "{e}");
        // An adapter without the tile's workgroup memory: the rung refused in one line, the
        // preset asking for it explicitly refused, the preset's own fitted back.
        let small = Caps { tile: false, ..ALL_CAPS };
        let rungs = ladder(&small, "vulkan");
        let e = rungs[rungs.len() - 3].skipped.clone().unwrap();
        assert!(e.contains("fusion=tile") && e.contains("32 KiB"), "{e}");
        let e =
            VariantSpec::parse("optimized", &["fusion=tile".into()]).unwrap().resolve(&small, "vulkan").unwrap_err();
        assert!(e.0.contains("workgroup memory"), "{e}");
        assert_eq!((top.fit(&small).fusion, top.fit(&small).temporal), (Fusion::IntoGather, Temporal::Off));
        // A switch that takes away what the tiles need: refused when fusion=tile is named.
        let e = VariantSpec::parse("optimized", &["fusion=tile".into(), "normals=gather".into()])
            .unwrap()
            .resolve(&ALL_CAPS, "vulkan")
            .unwrap_err();
        assert!(e.0.contains("fusion=tile") && e.0.contains("normals=frame"), "{e}");
        let bare = BARE_CAPS;
        let rungs = ladder(&bare, "wgpu");
        let skipped: Vec<String> = rungs.iter().filter(|r| r.skipped.is_some()).map(Rung::name).collect();
        assert_eq!(skipped, ["+constants=push", "+table=image", "+neighbours=shuffle", "+sdf=image"]);
        assert_eq!(rungs[0].variant.atomics, Atomics::Cas);
        // Every value of every switch the adapter has is in some covering variant.
        let cover = covering(&ALL_CAPS, "vulkan");
        for s in SWITCHES {
            for v in s.values {
                assert!(cover.iter().any(|x| x.get(s.key) == Some(*v)), "{}={v} not covered", s.key);
            }
        }
    }

    #[test]
    fn a_mesh_refuses_the_grid_only_switches_and_presets_fall_back_to_the_table() {
        let mesh = Caps { grid: false, ..ALL_CAPS };
        let opt = VariantSpec::from(Variant::OPTIMIZED).resolve(&mesh, "vulkan").unwrap();
        assert_eq!((opt.table, opt.neighbours), (Table::Storage, Neighbours::Load));
        for (set, want) in [("table=uniform", "table=uniform"), ("neighbours=shuffle", "neighbours=shuffle")] {
            let e = VariantSpec::parse("optimized", &[set.into()]).unwrap().resolve(&mesh, "vulkan").unwrap_err().0;
            assert!(e.contains(want) && e.contains("mesh"), "{e}");
        }
        // The ladder on a mesh skips the two rungs, naming the mesh.
        let rungs = ladder(&mesh, "vulkan");
        let skipped: Vec<String> = rungs.iter().filter(|r| r.skipped.is_some()).map(Rung::name).collect();
        assert_eq!(skipped, ["+table=uniform", "+neighbours=shuffle", "+fusion=tile", "+temporal=on"]);
        assert!(rungs.iter().flat_map(|r| &r.skipped).all(|e| e.contains("mesh")));
        assert!(covering(&mesh, "vulkan").iter().all(|v| v.check(&mesh, "vulkan").is_ok()));
    }

    #[test]
    fn labels_name_the_nearest_preset_and_what_differs() {
        assert_eq!(Variant::OPTIMIZED.label(), "optimized");
        let mut v = Variant::NAIVE;
        v.set("submit", "frame").unwrap();
        assert_eq!(v.label(), "naive+submit=frame");
        assert_eq!(Variant::THESIS.switches().split(',').count(), SWITCHES.len());
    }
}
