use clothlab_core::tri_contact::{edge_edge, motion_bounds};
use clothlab_core::{SceneFile, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use glam::Vec3;

fn main() {
    let f = SceneFile::load(std::path::Path::new("scenes/thin-heap.toml")).unwrap();
    let mut scene = f.scene.clone();
    scene.cloth.n = 128;
    let mut params = f.params.clone();
    params.self_thickness = 0.002;
    let mut s = CpuSolver::new(Exec::Parallel, scene.clone(), params.clone()).unwrap();
    s.time_kernels = false;
    let start: u32 = std::env::args().nth(1).map_or(28, |s| s.parse().unwrap());
    for _ in 0..start {
        s.step_frame().unwrap();
    }
    let single = SimParams { frame_dt: params.dt(), substeps: 1, ..params.clone() };
    s.set_params(single).unwrap();
    let v = |p: [f32; 4]| Vec3::new(p[0], p[1], p[2]);
    let tris = s.topology().triangles.clone();
    for k in 0..(16 * (33 - start) + 8) {
        let s0 = s.state_ref().clone();
        let r = edge_edge(v(s0.pos[6588]), v(s0.pos[6716]), v(s0.pos[7995]), v(s0.pos[7996]));
        let d = (r.p - r.q).length();
        if k % 4 == 0 || d < 1e-3 {
            let reach = clothlab_cpu::tri_contact::reach_of(
                &clothlab_core::StepParams::new(&params, &scene, None),
                s0.vel.iter().zip(&s0.pos).filter(|(_, x)| x[3] > 0.0).map(|(v, _)| Vec3::from_slice(&v[..3]).length()).fold(0.0, f32::max),
            );
            let b = motion_bounds(&s0.pos, &tris, reach);
            println!(
                "substep {k}: d {d:.3e} bounds {:.2e} {:.2e} {:.2e} {:.2e} vel {:.3} {:.3} y {:.4}",
                b[6588], b[6716], b[7995], b[7996],
                v(s0.vel[6588]).length(), v(s0.vel[7995]).length(), s0.pos[6588][1]
            );
        }
        s.step_frame().unwrap();
    }
}
