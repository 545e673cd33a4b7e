// One particle's statistics (needs stats.wgsl and a table).

// core::cpu::stats::particle_stats: (max strain of the springs starting at i, energy of i):
// on a grid its slots 1 and 3, on a mesh (n = 0) every edge at it (its row's head, which
// the strain limit holds).
fn particle_stats(i: u32) -> vec2<f32> {
    let x4 = pos[i];
    let x = x4.xyz;
    var strain = 0.0;
    let mesh = p.n == 0u;
    let r = slot_row(i);
    let first = select(1u, 0u, mesh);
    let step = select(2u, 1u, mesh);
    let end = select(4u, r.head, mesh);
    for (var s = first; s < end; s += step) {
        let slot = row_slot(i, r, s);
        if slot.neighbor >= 0 {
            strain = max(strain, len3(pos[u32(slot.neighbor)].xyz - x) / slot.rest - 1.0);
        }
    }
    let v = vel[i].xyz;
    return vec2<f32>(strain, 0.5 * mass_with(p.particle_mass, x4.w) * dot3(v, v));
}
