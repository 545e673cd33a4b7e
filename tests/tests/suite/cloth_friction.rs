//! Coulomb friction between cloths (self-collision's contacts with `static_friction` and
//! `kinetic_friction`; `core::cpu::self_collide::pair_friction`), on every backend: a
//! napkin thrown across a held sheet stops where Coulomb says, and without friction slides
//! much further; two free cloths that meet keep their momentum while friction hands its
//! sideways part from one to the other; the tablecloth trick (scenes/tablecloth-pull.toml,
//! scenes/tablecloth-trick.toml): pulled slowly the napkin leaves with the tablecloth,
//! pulled fast it stays on the table.

use clothlab_core::{ClothState, SceneFile, SimParams};
use clothlab_tests::{assert_checks, backend, backends};

const G: f64 = 9.81;
const MU_K: f64 = 0.3;
/// The napkin's throw, m/s.
const V0: f64 = 1.0;

/// `extra` (cloth tables and parameters) with self-collision at 2.2 cm and still air;
/// `coulomb`: μs 0.5, μk 0.3 (without them contacts between cloths have no friction).
fn scene(extra: &str, coulomb: bool) -> (clothlab_core::Scene, SimParams) {
    let friction = if coulomb { "static_friction = 0.5\nkinetic_friction = 0.3\n" } else { "" };
    let (cloths, params) = extra.split_once("[params]").unwrap_or((extra, ""));
    let text = format!(
        "{cloths}\n[params]\nself_collision = true\nself_thickness = 0.022\ndamping = 0.0\nair_drag = 0.0\nwind = [0.0, 0.0, 0.0]\n{friction}{params}"
    );
    let file = SceneFile::parse(&text, "cloth-friction.toml").unwrap();
    (file.scene, file.params)
}

/// A 40 × 40 sheet of 1 m (spacing 2.56 cm) held flat and still at y = 0.5 by a `[[pins]]`
/// group, and on it an 8 × 8 napkin of 0.2 m (spacing 2.86 cm) thrown along x at V0, 0.9
/// of the thickness above it. The thickness, 2.2 cm, is above 0.71 of both spacings (no
/// particle fits between four others) and below both (half the closest spring-free pair).
const THROWN_NAPKIN: &str = r#"
[[cloth]]
n = 40
size = 1.0
top_center = [0.0, 0.5, -0.5]
pinning = "none"

[[cloth]]
n = 8
size = 0.2
top_center = [-0.2, 0.5198, -0.1]
pinning = "none"
velocity = [1.0, 0.0, 0.0]

[[pins]]
min = [-0.6, 0.49, -0.6]
max = [0.6, 0.51, 0.6]
"#;

/// The napkin's (the last 64 particles') mean of `f`.
fn napkin(st: &ClothState, f: impl Fn(usize) -> f64) -> f64 {
    (st.pos.len() - 64..st.pos.len()).map(f).sum::<f64>() / 64.0
}

clothlab_tests::per_backend!(a_napkin_thrown_across_a_held_sheet_stops_where_coulomb_says);

fn a_napkin_thrown_across_a_held_sheet_stops_where_coulomb_says(name: &str) {
    // On a plane the napkin would slow at μk g (the contacts' normal impulses sum to its
    // weight, g dt a substep): 1 − μk g t = 0.411 m/s at 0.2 s, still after V0/(μk g) =
    // 0.34 s, having slid V0²/(2 μk g) = 0.170 m. The sheet is a lattice of particles, not
    // a plane: the napkin lands on it from 0.9 t (a bounce) and rides over its bumps, which
    // also slow it. Bounds: 0.06 m/s at 0.2 s and 20 % of the distance (measured on the CPU
    // 0.433 m/s and 0.180 m); at 0.5 s below 0.05 m/s (5 % of the throw: the bounce on the
    // lattice leaves a jiggle of a few mm/s, measured −0.004 m/s at 1 s). Without friction
    // the bumps alone slow it: it slides more than twice as far as the longest slide with
    // friction on any backend (measured 0.39 m in 1 s, still creeping).
    let mut failed = Vec::new();
    let mut slid_with = 0.0f64;
    for coulomb in [true, false] {
        let (sc, params) = scene(THROWN_NAPKIN, coulomb);
        if let Some(mut s) = backend(name, &sc, &params) {
            let start = s.state().unwrap();
            let x0 = napkin(&start, |i| start.pos[i][0] as f64);
            for _ in 0..12 {
                s.step_frame().unwrap();
            }
            let st = s.state().unwrap();
            let early = napkin(&st, |i| st.vel[i][0] as f64);
            // 0.5 s: the napkin has been still for 0.16 s (it stops at 0.34 s), as long a
            // wait as it takes a stopped napkin to show a creep; without friction it slides on.
            for _ in 12..30 {
                s.step_frame().unwrap();
            }
            let st = s.state().unwrap();
            let (late, dx) = (napkin(&st, |i| st.vel[i][0] as f64), napkin(&st, |i| st.pos[i][0] as f64) - x0);
            let low = st.pos[st.pos.len() - 64..].iter().map(|x| x[1]).fold(f32::INFINITY, f32::min);
            let (want_v, want_dx) = (V0 - MU_K * G * 0.2, V0 * V0 / (2.0 * MU_K * G));
            let label = if coulomb { "coulomb" } else { "none" };
            println!(
                "{label:8} {name:16} vx(0.2 s) {early:.4} m/s ({want_v:.3}), vx(0.5 s) {late:.4}, slid {dx:.4} m ({want_dx:.3}), lowest {low:.4} m"
            );
            if coulomb {
                slid_with = slid_with.max(dx);
            }
            if low < 0.5 {
                failed.push(format!("{name} {label}: the napkin went through the sheet (lowest {low} m)"));
            }
            if coulomb && ((early - want_v).abs() > 0.06 || (dx - want_dx).abs() > 0.2 * want_dx || late.abs() > 0.05) {
                failed.push(format!("{name} Coulomb: {early} m/s at 0.2 s, {late} m/s at 0.5 s, slid {dx} m"));
            }
        }
    }
    let slid_without = napkin_slides_without_friction();
    if slid_without < 2.0 * slid_with {
        failed.push(format!("{name}: without friction the napkin slid {slid_without} m in 1 s, with it {slid_with} m"));
    }
    assert!(failed.is_empty(), "{failed:?}");
}

/// Without friction the napkin creeps on: its distance at 1 s on cpu-par (the comparison
/// with each backend's slide with friction is of physics, not of a backend), computed
/// once for the rows.
fn napkin_slides_without_friction() -> f64 {
    static SLID: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *SLID.get_or_init(|| {
        let (sc, params) = scene(THROWN_NAPKIN, false);
        let mut s = backend("cpu-par", &sc, &params).unwrap();
        let start = s.state().unwrap();
        let x0 = napkin(&start, |i| start.pos[i][0] as f64);
        for _ in 0..60 {
            s.step_frame().unwrap();
        }
        let st = s.state().unwrap();
        napkin(&st, |i| st.pos[i][0] as f64) - x0
    })
}

/// In free space (no gravity, no floor): a 20 × 20 sheet of 0.5 m at rest, and 3 cm over
/// it an 8 × 8 napkin of 0.2 m moving at (1, −0.3, 0.2) m/s, so that it meets the sheet
/// slantwise and slides across it; the napkin weighs a quarter of the sheet.
const SLANTWISE: &str = r#"
[[cloth]]
n = 20
size = 0.5
top_center = [0.0, 0.5, -0.25]
pinning = "none"

[[cloth]]
n = 8
size = 0.2
top_center = [-0.15, 0.53, -0.1]
pinning = "none"
velocity = [1.0, -0.3, 0.2]
mass = 0.25

[params]
gravity = [0.0, 0.0, 0.0]
"#;

/// The total momentum (Σ vᵢ/wᵢ, the masses' unit) and the sheet's (the first 400) x part.
fn momentum(st: &ClothState) -> ([f64; 3], f64) {
    let mut total = [0.0f64; 3];
    let mut sheet_x = 0.0;
    for (i, (x, v)) in st.pos.iter().zip(&st.vel).enumerate() {
        let m = 1.0 / x[3] as f64;
        for a in 0..3 {
            total[a] += m * v[a] as f64;
        }
        if i < 400 {
            sheet_x += m * v[0] as f64;
        }
    }
    (total, sheet_x)
}

clothlab_tests::per_backend!(two_free_cloths_that_meet_keep_their_momentum_while_friction_drags_one_along);

fn two_free_cloths_that_meet_keep_their_momentum_while_friction_drags_one_along(name: &str) {
    // Only the cloths act on each other (no gravity, drag, damping, wind or floor): the
    // total momentum must stay the napkin's, whatever the contacts do. A contact's push and
    // its friction are one fixed-point value with two signs at its two ends, each end
    // moved by its own mobility times the pair's share (its inverse mass): equal and
    // opposite momenta, to the rounding of the velocities they land on (the napkin's
    // particles weigh 0.25 × 400 / 64 = 1.56 of the sheet's, so the roundings do not
    // cancel pair by pair). Bound 1e-5 of the napkin's momentum (rounding of 1,000
    // substeps; measured below 2e-7 on every backend). Friction acted: the sheet took more
    // of the napkin's x momentum with it than without (measured: see the output).
    let mut failed = Vec::new();
    let mut taken = [0.0f64; 2];
    for coulomb in [true, false] {
        let (sc, params) = scene(SLANTWISE, coulomb);
        if let Some(mut s) = backend(name, &sc, &params) {
            let (p0, _) = momentum(&s.state().unwrap());
            let scale = (p0[0] * p0[0] + p0[1] * p0[1] + p0[2] * p0[2]).sqrt();
            let mut worst = 0.0f64;
            for _ in 0..60 {
                s.step_frame().unwrap();
                let (p, _) = momentum(&s.state().unwrap());
                worst = worst.max((0..3).map(|a| (p[a] - p0[a]).abs()).fold(0.0, f64::max) / scale);
            }
            let (_, sheet_x) = momentum(&s.state().unwrap());
            let label = if coulomb { "coulomb" } else { "none" };
            println!(
                "{label:8} {name:16} momentum drift {worst:.2e} of the napkin's, sheet took {:.4} of its x momentum",
                sheet_x / p0[0]
            );
            taken[usize::from(!coulomb)] = sheet_x / p0[0];
            if worst > 1e-5 {
                failed.push(format!("{name} {label}: momentum drifted {worst:e} of the napkin's"));
            }
        }
    }
    if taken[0] <= taken[1] {
        failed.push(format!(
            "the sheet took {} of the napkin's x momentum with friction, {} without",
            taken[0], taken[1]
        ));
    }
    assert!(failed.is_empty(), "{failed:?}");
}

#[test]
fn friction_between_cloths_is_the_cpus_on_every_optimized_recipe() {
    // Self-collision with Coulomb's coefficients on a grid (the heap: the grid's response,
    // self_collide) and on two cloths (one particle array without grid coordinates:
    // self_collide_mesh): each optimized recipe's kernels against their twins — the
    // velocities' copy in hash_scatter, the response's friction from random velocities —
    // and the two cloths meeting, 12 frames rolled out bit for bit on llvmpipe (the CPU's
    // bits: the same operations in the same order, summed in fixed point).
    let heap = SceneFile::parse(&std::fs::read_to_string("../scenes/heap.toml").unwrap(), "heap.toml").unwrap();
    let mut hp = heap.params.clone();
    hp.static_friction = 0.5;
    hp.kinetic_friction = 0.3;
    assert_checks("heap", &clothlab_tests::optimized_kernel_checks(&heap.scene, &hp, 0xf1u64));
    let (two, params) = scene(SLANTWISE, true);
    assert_checks("two cloths", &clothlab_tests::optimized_kernel_checks(&two, &params, 0xf2u64));
    clothlab_tests::assert_rollouts(clothlab_tests::optimized_rollout_solvers(&two, &params), 12);
}

/// A scene file of `scenes/`.
fn scene_file(name: &str) -> SceneFile {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name);
    SceneFile::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_tablecloth_trick_pulled_slowly_the_napkin_leaves_with_the_cloth_pulled_fast_it_stays() {
    // The tablecloth's edge pulled 2.4 m in 1.2 s (scenes/tablecloth-pull.toml) or in 0.3 s
    // (scenes/tablecloth-trick.toml), the napkin (the last 64 particles) on it, μk 0.4
    // between the cloths. Kinetic friction moves the napkin at most μk g t²/2 while the
    // cloth slides under it: the fast pull clears the table in about 0.25 s (12 cm at
    // most; measured 9.4 cm on the CPU) and leaves the napkin on the table top (its lowest
    // particle at 0.81 m: the top and the margin); the slow one carries it off the table
    // (measured: on the floor by 2 s). Without friction between the cloths (the share
    // model) the slow pull leaves it on the table too (moved 3.9 cm): friction is what
    // carries it. The slow pulls at 1.75 s (105 frames), the trick at 1 s (60 frames: the
    // pull ended at 0.8 s), on the CPU: what is checked here is the model. Every API's
    // optimized recipe computes the CPU's bits for friction between cloths
    // (friction_between_cloths_is_the_cpus_on_every_optimized_recipe: each kernel against
    // its twin, two cloths meeting rolled out bit for bit) and for these two scene files
    // (scenes.rs); the trick on wgpu was 16.6 s of this test's 29 s on lavapipe.
    let mut failed = Vec::new();
    for (file, coulomb, leaves, frames) in [
        ("tablecloth-pull.toml", true, true, 105),
        ("tablecloth-trick.toml", true, false, 60),
        ("tablecloth-pull.toml", false, false, 105),
    ] {
        let keep = |n: &str| n == "cpu-par";
        let f = scene_file(file);
        let mut params = f.params.clone();
        if !coulomb {
            (params.static_friction, params.kinetic_friction) = (0.0, 0.0);
        }
        for (name, mut s) in backends(&f.scene, &params, keep) {
            let start = s.state().unwrap();
            let z0 = napkin(&start, |i| start.pos[i][2] as f64);
            for _ in 0..frames {
                s.step_frame().unwrap();
            }
            let st = s.state().unwrap();
            let napkin_pos = &st.pos[st.pos.len() - 64..];
            let low = napkin_pos.iter().map(|x| x[1]).fold(f32::INFINITY, f32::min);
            let high = napkin_pos.iter().map(|x| x[1]).fold(f32::NEG_INFINITY, f32::max);
            let moved = napkin(&st, |i| st.pos[i][2] as f64) - z0;
            let label = if coulomb { "coulomb" } else { "share" };
            println!("{file:22} {label:8} {name:16} napkin at {low:.4}..{high:.4} m high, moved {moved:.4} m");
            // On the table: every particle on its top (0.8 m and the margin; a particle
            // lies on the top or on a fold of the napkin, 0.1 m at most). Off it: below the
            // top.
            let on_table = low >= 0.8 && high < 0.9 && moved.abs() < 0.12;
            if leaves == on_table || (leaves && high > 0.8) {
                failed.push(format!("{file} {label} {name}: napkin at {low}..{high} m, moved {moved} m"));
            }
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}
