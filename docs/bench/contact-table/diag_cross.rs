//! Temporary diagnostic: the first substep where the thin heap at n = 128, t = 2 mm crosses.
use clothlab_core::crossings::{edges, segment_crosses_triangle};
use clothlab_core::tri_contact::{edge_edge, motion_bounds, point_triangle};
use clothlab_core::{SceneFile, SimParams, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use glam::{DVec3, Vec3};

fn main() {
    let f = SceneFile::load(std::path::Path::new("scenes/thin-heap.toml")).unwrap();
    let mut scene = f.scene.clone();
    scene.cloth.n = 128;
    let mut params = f.params.clone();
    params.self_thickness = 0.002;
    let frames: u32 = std::env::args().nth(1).map_or(32, |s| s.parse().unwrap());
    let mut s = CpuSolver::new(Exec::Parallel, scene.clone(), params.clone()).unwrap();
    s.time_kernels = false;
    for _ in 0..frames {
        s.step_frame().unwrap();
    }
    let tris = s.topology().triangles.clone();
    let es = edges(&tris);
    println!("after {frames} frames: {} crossings", clothlab_core::crossings::count(&s.state_ref().pos, &tris).pairs);
    let single = SimParams { frame_dt: params.dt(), substeps: 1, ..params.clone() };
    s.set_params(single).unwrap();
    let d = |p: [f32; 4]| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    let v = |p: [f32; 4]| Vec3::new(p[0], p[1], p[2]);
    for k in 0..(16 * 20) {
        let s0 = s.state_ref().clone();
        s.step_frame().unwrap();
        let s1 = s.state_ref().clone();
        let c = clothlab_core::crossings::count(&s1.pos, &tris).pairs;
        if c == 0 {
            continue;
        }
        println!("substep {k} after frame {frames}: {c} crossings");
        let reach = clothlab_cpu::tri_contact::reach_of(
                &clothlab_core::StepParams::new(&params, &scene, None),
                s0.vel.iter().zip(&s0.pos).filter(|(_, x)| x[3] > 0.0).map(|(v, _)| Vec3::from_slice(&v[..3]).length()).fold(0.0, f32::max),
            );
        let bounds = motion_bounds(&s0.pos, &tris, reach);
        println!("reach {reach}");
        let mut shown = 0;
        for e in &es {
            for (ti, t) in tris.iter().enumerate() {
                if t.contains(&e[0]) || t.contains(&e[1]) {
                    continue;
                }
                let [a, b, cc] = *t;
                let p1 = |i: u32| d(s1.pos[i as usize]);
                if !segment_crosses_triangle(p1(e[0]), p1(e[1]), p1(a), p1(b), p1(cc)) {
                    continue;
                }
                shown += 1;
                if shown > 3 {
                    continue;
                }
                println!("edge {e:?} through triangle {ti} {t:?}");
                for &x in e.iter().chain(t.iter()) {
                    let m = (v(s1.pos[x as usize]) - v(s0.pos[x as usize])).length();
                    println!("  vertex {x}: moved {m:.3e}, bound {:.3e}, w {}", bounds[x as usize], s0.pos[x as usize][3]);
                }
                let p0 = |i: u32| v(s0.pos[i as usize]);
                for &x in e {
                    let r = point_triangle(p0(x), p0(a), p0(b), p0(cc));
                    println!("  at start: vertex {x} – triangle: {:.3e}", (r.point - p0(x)).length());
                }
                for f in [[a, b], [b, cc], [cc, a]] {
                    let r = edge_edge(p0(e[0]), p0(e[1]), p0(f[0]), p0(f[1]));
                    println!("  at start: edge {e:?} – edge {f:?}: {:.3e}", (r.p - r.q).length());
                }
            }
        }
        break;
    }
}
