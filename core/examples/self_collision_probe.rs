//! What self-collision's response reads, per particle, on the heap scene (scenes/heap.toml)
//! at grid size N with the thickness equal to the grid spacing, after the given frames:
//! buckets probed (and how many were empty or skipped by their grid-coordinate box),
//! entries read, candidates (entries outside the springs' stencil, whose positions are
//! loaded) and contacts (candidates closer than the thickness).
//!
//! `cargo run --release -p clothlab-core --example self_collision_probe -- 128 20,50,100`
//! (docs/scenes.md quotes its output).
use clothlab_core::cpu::self_collide::*;
use clothlab_core::grid::StepParams;
use clothlab_core::scene_file::SceneFile;
use clothlab_core::{CpuSolver, Exec, Solver};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u32 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(128);
    let frames: Vec<u32> =
        args.get(2).map(|s| s.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![20, 50, 100]);
    let f = SceneFile::load(std::path::Path::new("scenes/heap.toml")).unwrap();
    let mut scene = f.scene.clone();
    scene.cloth.n = n;
    let mut params = f.params.clone();
    params.self_thickness = scene.cloth.size / (n - 1) as f32;
    let mut s = CpuSolver::new(Exec::Parallel, scene.clone(), params.clone()).unwrap();
    let mut done = 0;
    for &fr in &frames {
        while done < fr {
            s.step_frame().unwrap();
            done += 1;
        }
        let st = s.state_ref();
        let p = StepParams::new(&params, &scene, None);
        let np = st.pos.len();
        let mut cells = vec![[0.0f32; 4]; np];
        let mut sorted = vec![[0.0f32; 4]; np];
        hash_count(&p, &st.pos, &mut cells, &mut sorted);
        hash_scan_blocks(&mut cells);
        hash_scan_top(&mut cells);
        hash_scan_add(&mut cells);
        hash_scatter(&p, &mut cells, &mut sorted);
        hash_sort(&mut cells, &mut sorted);
        let size = table_size(np);
        let inv = p.inv_cell;
        let t = p.self_thickness;
        let (mut probed, mut skipped_empty, mut skipped_box, mut entries, mut cands, mut near, mut max_entries) =
            (0u64, 0u64, 0u64, 0u64, 0u64, 0u64, 0u64);
        // What a bucket sorted by height would let a particle skip: entries farther than t
        // in y (read only up to the window's end), and the candidates within it.
        let (mut in_window, mut window_cands) = (0u64, 0u64);
        let occupied = cells.iter().filter(|c| c[0].to_bits() > 0).count();
        for i in 0..np {
            let x = st.pos[i];
            let c = cell_of(&x, inv);
            let side: [i32; 3] = std::array::from_fn(|a| if x[a] * inv - c[a] as f32 >= 0.5 { 1 } else { -1 });
            let me = ((i as u32 % p.n) as i32, (i as u32 / p.n) as i32);
            let mut bs = vec![];
            let mut mine = 0u64;
            for k in 0..8 {
                let cc: [i32; 3] = std::array::from_fn(|a| c[a] + if k >> a & 1 == 1 { side[a] } else { 0 });
                let b = bucket(cc, size);
                if bs.contains(&b) {
                    continue;
                }
                bs.push(b);
                probed += 1;
                let cell = cells[b as usize];
                let count = cell[0].to_bits() as usize;
                let start = cell[1].to_bits() as usize;
                if count == 0 {
                    skipped_empty += 1;
                    continue;
                }
                let (lo, hi) = (slot_coords(cell[2].to_bits()), slot_coords(cell[3].to_bits()));
                if lo.0 as i32 >= me.0 - 2
                    && lo.1 as i32 >= me.1 - 2
                    && hi.0 as i32 <= me.0 + 2
                    && hi.1 as i32 <= me.1 + 2
                {
                    skipped_box += 1;
                    continue;
                }
                for s in &sorted[start..start + count] {
                    entries += 1;
                    mine += 1;
                    let (qi, qj) = slot_coords(s[1].to_bits());
                    let y = st.pos[(qj * p.n + qi) as usize];
                    let in_y = (y[1] - x[1]).abs() < t;
                    in_window += u64::from(in_y);
                    if !candidate_coords(&p, me, (qi as i32, qj as i32)) {
                        continue;
                    }
                    cands += 1;
                    window_cands += u64::from(in_y);
                    let d2: f32 = (0..3).map(|a| (x[a] - y[a]) * (x[a] - y[a])).sum();
                    if d2 < t * t {
                        near += 1;
                    }
                }
            }
            max_entries = max_entries.max(mine);
        }
        let per = |v: u64| v as f64 / np as f64;
        // SIMD-8 groups of consecutive particles: the loop runs the max of its lanes.
        println!(
            "n={n} frame {fr}: occupied buckets {occupied} ({:.2} of {np}); per particle: probed {:.2}, empty {:.2}, box-skipped {:.2}, entries read {:.2} (max {max_entries}), candidates {:.2}, closer than t {:.3}; within t in y {:.2} (candidates {:.2}); lowest y {:.3}",
            occupied as f64 / np as f64,
            per(probed),
            per(skipped_empty),
            per(skipped_box),
            per(entries),
            per(cands),
            per(near),
            per(in_window),
            per(window_cands),
            st.pos.iter().map(|x| x[1]).fold(f32::MAX, f32::min)
        );
    }
}
