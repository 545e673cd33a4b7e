//! The sizes of the per-particle tables every solver reads: a module of its own, without
//! dependencies, so that the grid builder and the mesh reader share them without
//! depending on each other.

/// Spring slots per particle in the gather table.
pub const SLOTS: usize = 12;
/// Slots `0 .. STRAIN_SLOTS` (a grid's structural and shear springs, a mesh's edges) are
/// held by the strain limit.
pub const STRAIN_SLOTS: usize = 8;
/// Face slots per particle: a regular grid vertex touches at most six triangles.
pub const FACE_SLOTS: usize = 6;
/// Tether slots per particle (long-range attachments to pins).
pub const TETHER_SLOTS: usize = 2;
/// The most particles a mesh may have for self-collision: a hash slot's word holds the
/// particle's index in 24 bits (`cpu::self_collide::slot_word`).
pub const SELF_COLLISION_MAX_PARTICLES: usize = 1 << 24;
