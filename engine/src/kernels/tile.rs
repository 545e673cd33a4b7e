//! The tiled substep (`fusion=tile`): forces, integration and the strain passes of a
//! region in workgroup memory.

use super::*;

/// The tiled substep (`fusion=tile`): what forces_springs_wind, integrate_collide and
/// `strain_passes` × (strain_count, strain_limit) leave, `tile_substeps` times — the new
/// positions in the other buffer of the pair, the new velocities in aux0; the positions,
/// velocities and forces it read untouched (it keeps the forces and counts in
/// workgroup memory).
fn substep_tile(a: &TwinArgs, b: &mut HostBuffers) {
    let (pos, vel, force) = (b.pos.clone(), b.vel.clone(), b.force.clone());
    for _ in 0..a.p.tile_substeps.max(1) {
        (FORCES_SPRINGS_WIND.twin)(a, b);
        (INTEGRATE_COLLIDE.twin)(a, b);
        for _ in 0..a.p.strain_passes {
            (STRAIN_COUNT.twin)(a, b);
            (STRAIN_LIMIT.twin)(a, b);
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

/// The Verlet substep of a regular grid in one dispatch over workgroup-memory tiles
/// (`fusion=tile`): a workgroup per tile of `32 − 2·halo` points a side, the halo 2 + 2
/// per strain pass deep (times `tile_substeps`). Dispatched as a range of
/// [`crate::recipe::tile_command`] (its count of tiles depends on the pass count).
pub static SUBSTEP_TILE: KernelDef = KernelDef {
    check: TILE_CHECK,
    pure: &[PosOut, TILE_NEW_VEL],
    label: timing::SUBSTEP_TILE,
    variants: IMM_CU,
    cloths: Cloths::Grid,
    dispatches: Dispatches::Tiles,
    ..KernelDef::new(
        "substep_tile",
        substep_tile,
        Count::Particles,
        &[Params, Pos, Vel, Interior, Spheres, Boxes, Shapes, Tethers],
        &[PosOut, TILE_NEW_VEL],
    )
};
/// The tiled substep's new velocities (aux0) into place, after the swap.
pub static TILE_VEL: KernelDef = KernelDef {
    pure: &[Vel],
    label: timing::SUBSTEP_TILE,
    ..KernelDef::new("tile_vel", tile_vel, Count::Particles, &[Params, TILE_NEW_VEL], &[Vel])
};
/// Workgroup memory the tiled substep needs (its 32 × 32 region of positions,
/// velocities and strain counts).
pub const TILE_WORKGROUP_BYTES: u32 = 32 * 32 * 32;
/// The side of the tiled substep's region (tile and halo), points.
pub const TILE_REGION: u32 = 32;

/// This family's kernels, in the registry's order ([`super::ALL`]).
pub(super) const ROWS: &[&KernelDef] = &[&SUBSTEP_TILE, &TILE_VEL];
