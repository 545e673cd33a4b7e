//! The scene: the cloth's size and placement, the floor, the spheres and boxes it falls on.
//!
//! The default scene is the thesis's: a square cloth held horizontally at its two top
//! corners (the edge `j = 0`), released so that it swings down and drapes over three
//! spheres resting on the floor.

use bytemuck::{Pod, Zeroable};
use serde::{Deserialize, Serialize};

use crate::params::{ParamError, finite_in};

/// Smallest cloth side, particles.
pub const MIN_N: u32 = 2;
/// Largest cloth side, particles (16.7 M particles, about 4.5 GiB of CPU state).
pub const MAX_N: u32 = 4096;
/// Most spheres / boxes a scene may hold (they live in a uniform buffer on the GPU).
pub const MAX_COLLIDERS: usize = 16;

/// A sphere collider. `#[repr(C)]`, mirrored in the shaders.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
pub struct Sphere {
    /// Centre, m.
    pub center: [f32; 3],
    /// Radius, m.
    pub radius: f32,
}

/// An axis-aligned box collider. `#[repr(C)]`, mirrored in the shaders (w unused).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable, Serialize, Deserialize)]
pub struct Aabb {
    /// Lower corner, m (w unused, 0).
    pub min: [f32; 4],
    /// Upper corner, m (w unused, 0).
    pub max: [f32; 4],
}

impl Aabb {
    /// A box from its lower and upper corners.
    pub fn new(min: [f32; 3], max: [f32; 3]) -> Self {
        Self { min: [min[0], min[1], min[2], 0.0], max: [max[0], max[1], max[2], 0.0] }
    }
}

/// Which particles are held still.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Pinning {
    /// The two corners of the top edge (`j = 0`): the thesis's scene.
    TopCorners,
    /// The whole top edge (a curtain).
    TopEdge,
    /// Nothing: the cloth falls freely.
    None,
}

/// The cloth: an `n × n` grid of particles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClothSpec {
    /// Particles per side. Default 100. Valid: 2 ..= 4096.
    pub n: u32,
    /// Side length of the square cloth, m. Default 2.
    pub size: f32,
    /// Centre of the top edge (`j = 0`), m; the cloth starts horizontal, extending from
    /// there towards +z. Default (0, 2.2, -0.9).
    pub top_center: [f32; 3],
    /// Which particles are pinned. Default [`Pinning::TopCorners`].
    pub pinning: Pinning,
}

impl Default for ClothSpec {
    fn default() -> Self {
        Self { n: 100, size: 2.0, top_center: [0.0, 2.2, -0.9], pinning: Pinning::TopCorners }
    }
}

/// The whole scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// The cloth.
    pub cloth: ClothSpec,
    /// Height of the floor plane y = floor_y, m. Default 0.
    pub floor_y: f32,
    /// Sphere colliders. Default: three spheres resting on the floor under the cloth.
    pub spheres: Vec<Sphere>,
    /// Axis-aligned box colliders. Default: none.
    pub boxes: Vec<Aabb>,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            cloth: ClothSpec::default(),
            floor_y: 0.0,
            spheres: vec![
                Sphere { center: [-0.55, 0.35, -0.35], radius: 0.35 },
                Sphere { center: [0.45, 0.45, -0.1], radius: 0.45 },
                Sphere { center: [-0.05, 0.25, 0.55], radius: 0.25 },
            ],
            boxes: Vec::new(),
        }
    }
}

impl Scene {
    /// The default scene with an `n × n` cloth.
    pub fn with_n(n: u32) -> Self {
        let mut s = Self::default();
        s.cloth.n = n;
        s
    }

    /// Number of particles, `n²`.
    pub fn num_particles(&self) -> usize {
        self.cloth.n as usize * self.cloth.n as usize
    }

    /// Checks the scene; the first bad value is reported.
    pub fn validate(&self) -> Result<(), ParamError> {
        let n = self.cloth.n;
        if !(MIN_N..=MAX_N).contains(&n) {
            return Err(ParamError::new("n", n, format!("grid side must be in {MIN_N} ..= {MAX_N}")));
        }
        finite_in("cloth.size", self.cloth.size, 1e-3, 1e3)?;
        for v in self.cloth.top_center {
            finite_in("cloth.top_center", v, -1e4, 1e4)?;
        }
        finite_in("floor_y", self.floor_y, -1e4, 1e4)?;
        if self.spheres.len() > MAX_COLLIDERS {
            return Err(ParamError::new("spheres", self.spheres.len(), format!("at most {MAX_COLLIDERS}")));
        }
        if self.boxes.len() > MAX_COLLIDERS {
            return Err(ParamError::new("boxes", self.boxes.len(), format!("at most {MAX_COLLIDERS}")));
        }
        for s in &self.spheres {
            for v in s.center {
                finite_in("sphere.center", v, -1e4, 1e4)?;
            }
            finite_in("sphere.radius", s.radius, 1e-4, 1e4)?;
        }
        for b in &self.boxes {
            for k in 0..3 {
                finite_in("box.min", b.min[k], -1e4, 1e4)?;
                finite_in("box.max", b.max[k], -1e4, 1e4)?;
                if b.max[k] <= b.min[k] {
                    return Err(ParamError::new("box.max", b.max[k], "every max must exceed its min"));
                }
            }
        }
        Ok(())
    }
}
