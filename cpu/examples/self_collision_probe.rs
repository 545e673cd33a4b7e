//! What self-collision's response reads, per particle, on the heap scene (scenes/heap.toml)
//! at grid size N with the thickness equal to the grid spacing, after the given frames:
//! rows and their buckets (how many empty), entries read (and how many the row tag
//! refuses), candidates (entries of the row outside the springs' stencil, whose distance
//! is computed) and contacts (candidates closer than the thickness), the foreign entries
//! among the candidates (from other cells hashed to the same bucket), the most entries
//! one particle reads; and what the GPU kernel reads when two row neighbours walk their
//! rows together (shaders/wgsl/self_collide.wgsl).
//!
//! `cargo run --release -p clothlab-cpu --example self_collision_probe -- 128 20,50,100`
//! (docs/scenes.md quotes its output).
use clothlab_core::Solver;
use clothlab_core::grid::V4;
use clothlab_core::scene_file::SceneFile;
use clothlab_core::step_params::StepParams;
use clothlab_cpu::self_collide::*;
use clothlab_cpu::{CpuSolver, Exec};

/// The entries in the slots of the row that starts at bucket `first` and is `len` long.
fn row_entries(cells: &[u32], first: u32, len: u32, size: u32, np: u32) -> u64 {
    row_ranges(cells, Row { first, len, tag: 0 }, size, np).iter().map(|(s, e)| u64::from(e - s)).sum()
}

/// Rows and entries per particle when the pairs (2k, 2k + 1) of each grid row walk the
/// rows either reaches once for both (cells at most one apart per axis; else one walk
/// each), and the share of pairs that cannot.
fn pair_walks(pos: &[V4], n: usize, inv: f32, cells: &[u32], size: u32) -> (f64, f64, f64) {
    let count = n * n.div_ceil(2);
    let (mut rows, mut entries, mut apart) = (0u64, 0u64, 0u64);
    for g in 0..count {
        let walks = pair_loops(pos, n, g, inv, cells, size);
        apart += u64::from(walks.len() == 2);
        rows += walks.iter().flatten().flatten().count() as u64;
        entries += walks.iter().flatten().flatten().sum::<u64>();
    }
    let per = pos.len() as f64;
    (rows as f64 / per, entries as f64 / per, 100.0 * apart as f64 / count as f64)
}

/// One pair's walk as the kernel loops it: per (z, y) loop index, the entries of the row
/// (None where the row is skipped).
fn pair_loops(pos: &[V4], n: usize, g: usize, inv: f32, cells: &[u32], size: u32) -> Vec<Vec<Option<u64>>> {
    let np = pos.len() as u32;
    let half = n.div_ceil(2);
    let (j, k) = (g / half, 2 * (g % half));
    let mut two = vec![cell_and_fraction(&pos[j * n + k], inv)];
    if k + 1 < n {
        two.push(cell_and_fraction(&pos[j * n + k + 1], inv));
    }
    let together = two.len() == 1 || (0..3).all(|a| (two[0].0[a] - two[1].0[a]).abs() <= 1);
    let walks: Vec<&[([i32; 3], [f32; 3])]> = if together { vec![&two[..]] } else { vec![&two[..1], &two[1..]] };
    let mut out = Vec::new();
    for walk in walks {
        let lo: [i32; 3] = std::array::from_fn(|a| walk.iter().map(|(c, _)| c[a]).min().unwrap() - 1);
        let hi: [i32; 3] = std::array::from_fn(|a| walk.iter().map(|(c, _)| c[a]).max().unwrap() + 1);
        let mut v = Vec::new();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let reached: Vec<(i32, i32)> = walk.iter().filter_map(|&(c, f)| reach(c, f, y, z)).collect();
                let Some(x0) = reached.iter().map(|r| r.0).min() else {
                    v.push(None);
                    continue;
                };
                let x1 = reached.iter().map(|r| r.1).max().unwrap();
                v.push(Some(row_entries(cells, bucket([x0, y, z], size), (x1 - x0 + 1) as u32, size, np)));
            }
        }
        out.push(v);
    }
    out
}

/// Entry iterations that groups of 8 lanes (llvmpipe's SIMD width, which steps its lanes
/// together: a loop runs as long as its longest lane) run per group, against the entries
/// a lane needs: (needed per lane, a loop per row of the walk's box, a loop per non-empty
/// row, one loop over all the walk's entries).
fn simd_cost(pos: &[V4], n: usize, inv: f32, cells: &[u32], size: u32) -> (f64, f64, f64, f64) {
    let count = n * n.div_ceil(2);
    let (mut need_e, mut run_e, mut flat, mut compact) = (0u64, 0u64, 0u64, 0u64);
    for g0 in (0..count).step_by(8) {
        let lanes: Vec<_> = (g0..(g0 + 8).min(count)).map(|g| pair_loops(pos, n, g, inv, cells, size)).collect();
        flat += lanes.iter().map(|l| l.iter().flatten().flatten().sum::<u64>()).max().unwrap();
        let ranges: Vec<Vec<u64>> =
            lanes.iter().map(|l| l.iter().flatten().flatten().copied().filter(|&e| e > 0).collect()).collect();
        let most = ranges.iter().map(|r| r.len()).max().unwrap();
        compact += (0..most).map(|r| ranges.iter().map(|l| l.get(r).copied().unwrap_or(0)).max().unwrap()).sum::<u64>();
        let walks = lanes.iter().map(|l| l.len()).max().unwrap();
        for w in 0..walks {
            let iters = lanes.iter().map(|l| l.get(w).map_or(0, |v| v.len())).max().unwrap();
            for it in 0..iters {
                let e: Vec<u64> =
                    lanes.iter().map(|l| l.get(w).and_then(|v| v.get(it).copied().flatten()).unwrap_or(0)).collect();
                run_e += e.iter().max().unwrap();
                need_e += e.iter().sum::<u64>();
            }
        }
    }
    let lanes = count as f64;
    let groups = count.div_ceil(8) as f64;
    (need_e as f64 / lanes, run_e as f64 / groups, compact as f64 / groups, flat as f64 / groups)
}

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
        let mut aux = vec![vec![[0.0f32; 4]; np]; clothlab_cpu::AUX];
        let mut h = hash_buffers(&mut aux);
        build_hash(&p, &st.pos, &st.vel, &mut h);
        let (cells, slots) = (&*h.cells, &*h.slots);
        let cw = hash_words(cells);
        let size = table_size(np);
        let (inv, t) = (p.inv_cell, p.self_thickness);
        let (mut rows_n, mut probed, mut empty, mut entries, mut cands, mut foreign, mut near, mut max_entries) =
            (0u64, 0u64, 0u64, 0u64, 0u64, 0u64, 0u64, 0u64);
        let mut tagged = 0u64;
        let occupied = (0..size)
            .filter(|&b| bucket_range(cw, b, size, np as u32).0 < bucket_range(cw, b, size, np as u32).1)
            .count();
        for i in 0..np {
            let x = st.pos[i];
            let me = ((i as u32 % p.n) as i32, (i as u32 / p.n) as i32);
            let c = cell_of(&x, inv);
            let mut rows = [Row::default(); 9];
            let count = rows_around(&x, inv, size, &mut rows);
            rows_n += count as u64;
            let mut mine = 0u64;
            for row in &rows[..count] {
                for o in 0..row.len {
                    let (start, end) = bucket_range(cw, row.first.wrapping_add(o) & (size - 1), size, np as u32);
                    probed += 1;
                    empty += u64::from(start == end);
                    for s in start..end {
                        entries += 1;
                        mine += 1;
                        let w = slots[s as usize][3].to_bits();
                        if slot_tag(w) != row.tag {
                            tagged += 1;
                            continue;
                        }
                        let (qi, qj) = slot_coords(w);
                        if !candidate_coords(&p, me, (qi as i32, qj as i32)) {
                            continue;
                        }
                        cands += 1;
                        let y = slots[s as usize];
                        let cy = cell_of(&y, inv);
                        foreign += u64::from((0..3).any(|a| (cy[a] - c[a]).abs() > 1));
                        let d2: f32 = (0..3).map(|a| (x[a] - y[a]) * (x[a] - y[a])).sum();
                        near += u64::from(d2 < t * t);
                    }
                }
            }
            max_entries = max_entries.max(mine);
        }
        let per = |v: u64| v as f64 / np as f64;
        println!(
            "n={n} frame {fr}: occupied buckets {occupied} of {size}; per particle: rows {:.2}, buckets {:.2} (empty {:.2}), entries read {:.2} (max {max_entries}; of another row by the tag {:.2}), candidates {:.2} (foreign {:.2}), closer than t {:.3}; lowest y {:.3}",
            per(rows_n),
            per(probed),
            per(empty),
            per(entries),
            per(tagged),
            per(cands),
            per(foreign),
            per(near),
            st.pos.iter().map(|x| x[1]).fold(f32::MAX, f32::min)
        );
        let (rows, entries, apart) = pair_walks(&st.pos, n as usize, inv, cw, size);
        println!(
            "  pairs of row neighbours walking together: rows {rows:.2}, entries read {entries:.2} per particle ({apart:.1} % of pairs too far apart for one walk)"
        );
        let (need, per_row, per_range, flat) = simd_cost(&st.pos, n as usize, inv, cw, size);
        println!(
            "  8 lanes stepping together (a lane a pair): entry iterations per lane needed {need:.2}; run: a loop per row of the box {per_row:.2}, per non-empty row {per_range:.2}, one loop over all {flat:.2}"
        );
    }
}
