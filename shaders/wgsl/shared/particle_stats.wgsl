// One particle's statistics (needs stats.wgsl and a table).

// core::cpu::stats::particle_stats: (max strain of the springs starting at i, energy of i).
fn particle_stats(i: u32) -> vec2<f32> {
    let x4 = pos[i];
    let x = x4.xyz;
    var strain = 0.0;
    for (var s = 1u; s <= 3u; s += 2u) {
        let slot = slot_at(i, s);
        if slot.neighbor >= 0 {
            strain = max(strain, len3(pos[u32(slot.neighbor)].xyz - x) / slot.rest - 1.0);
        }
    }
    let v = vel[i].xyz;
    return vec2<f32>(strain, 0.5 * mass_with(p.particle_mass, x4.w) * dot3(v, v));
}
