//! Each GPU API (wgpu, raw Vulkan under the Khronos validation layer, raw GL) against the
//! CPU twins: every kernel flavor the adapter offers, the solver's own kernels at sizes
//! that are not multiples of a workgroup, rollouts of each preset, parameters changed
//! while running, the spring table from storage, uniforms and an image, the GPU
//! statistics. Written once over [`Api::ALL`]; what differs between the APIs is data (the
//! rows below) or an assertion on the adapter's caps. Any validation message, GL error or
//! GL debug message of medium or high severity fails the test that caused it
//! ([`assert_api_clean`]). Bounds and their reasons: the rows of `clothlab_engine::kernels`.

use clothlab_core::{Scene, SimParams, Solver, SolverError};
use clothlab_cpu::validate::{compare, validate_rollout};
use clothlab_engine::kernels::{self as k, Check};
use clothlab_engine::recipe::StatsMode;
use clothlab_engine::validate::{COMPARED_BUFFERS, flavors, validate_kernels};
use clothlab_engine::{SolverOptions, Variant, VariantSpec};
use clothlab_tests::{AnyGpuSolver, Api, assert_api_clean, assert_checks, one_switch_at_a_time, or_skip};

/// A solver of `spec` on `api` for the default scene at `n` (validation on).
fn solver(api: Api, spec: impl Into<VariantSpec>, n: u32) -> Option<Box<dyn AnyGpuSolver>> {
    api.solver(spec, &Scene::with_n(n), &SimParams::default())
}

/// The sizes at which each API's own kernels (the optimized recipe and the plain flavor
/// of each) are checked besides n = 64's every flavor: sizes that are not a multiple of a
/// workgroup, the last block partly empty. wgpu takes three (one below, one above, one
/// of several blocks); the raw APIs share its kernels' WGSL and take one.
fn odd_sizes(api: Api) -> &'static [u32] {
    match api {
        Api::Wgpu => &[63, 65, 257],
        Api::Vulkan | Api::Gl => &[65],
    }
}

/// The presets each API rolls out: every one on the raw APIs; on wgpu the thesis's is
/// rolled out by the table test below, after its image is rewritten.
fn presets(api: Api) -> &'static [Variant] {
    match api {
        Api::Wgpu => &[Variant::NAIVE, Variant::OPTIMIZED],
        Api::Vulkan | Api::Gl => &[Variant::NAIVE, Variant::OPTIMIZED, Variant::THESIS],
    }
}

/// Where each API reads the spring table from in the table test: the thesis's image on
/// every API, storage on the raw APIs, uniform blocks on GL (the one API whose uniform
/// path differs from its storage path in more than the binding: std140 arrays).
fn tables(api: Api) -> &'static [&'static str] {
    match api {
        Api::Wgpu => &["image"],
        Api::Vulkan => &["storage", "image"],
        Api::Gl => &["storage", "uniform", "image"],
    }
}

/// The largest odd size at which the self-collision contact kernels are checked. The
/// kernel checks' disturbed cloth keeps its 1 m and the contact thickness, so a particle's
/// neighbours within it grow as n²: at n = 257 these two kernels took 107 of the test's
/// 118 s on lavapipe (the CPU twin alone 36 s). Their partial last workgroup is checked at
/// 63 and 65, every flavor at 64, and their walk through the hash in self_collision.rs.
const CONTACTS_UP_TO: u32 = 128;
const CONTACTS: [&k::KernelDef; 2] = [&k::SELF_COLLIDE, &k::SELF_COLLIDE_FRICTION];

/// The kernels every API builds, by name: each must be offered, and with every flavor its
/// storage (`_sto`) flavor and its push-constant (`_imm`) flavor exactly where the adapter
/// has immediates (GL never).
const ALWAYS: [&k::KernelDef; 13] = [
    &k::FORCES,
    &k::SPRINGS,
    &k::SPRINGS_SCATTER,
    &k::INTEGRATE,
    &k::COLLIDE,
    &k::FORCES_INTEGRATE_COLLIDE,
    &k::TRI_NORMALS_SCATTER,
    &k::VERTEX_NORMALS_NAIVE,
    &k::FORCES_SPRINGS,
    &k::INTEGRATE_COLLIDE,
    &k::STRAIN_LIMIT,
    &k::TRI_NORMALS,
    &k::VERTEX_NORMALS,
];

fn kernels_match_on(api: Api, n: u32, every_flavor: bool) {
    let Some(mut g) = solver(api, Variant::OPTIMIZED, n) else { return };
    let caps = g.caps();
    if api == Api::Gl {
        assert!(!caps.immediates, "GL has no push constants: no `_imm` flavor may be offered");
    }
    // Every flavor (every switch: where constants, colliders live, which atomics), or the
    // kernels the solver offers: the optimized recipe's and the plain flavor of each.
    // On wgpu, every flavor one switch from the plain one ([`one_switch_at_a_time`]).
    let full = every_flavor && api != Api::Wgpu;
    let mut kernels = match (every_flavor, api) {
        (false, _) => g.kernels(),
        (true, Api::Wgpu) => one_switch_at_a_time(flavors(&caps, false), false),
        (true, _) => flavors(&caps, false),
    };
    if n > CONTACTS_UP_TO {
        kernels.retain(|k| !CONTACTS.contains(&k.def));
    }
    let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
    let has = |n: &str| names.iter().any(|k| k == n);
    for def in ALWAYS {
        assert!(has(def.name), "{}: kernel {} missing", api.name(), def.name);
        if every_flavor {
            assert!(has(&format!("{}_sto", def.name)), "{}: {}_sto missing", api.name(), def.name);
            assert_eq!(has(&format!("{}_imm", def.name)), caps.immediates, "{}: {}_imm", api.name(), def.name);
        }
    }
    assert!(names.iter().all(|k| caps.immediates || !k.ends_with("_imm")), "{names:?}");
    if every_flavor {
        assert!(has("integrate_collide_cu"), "{names:?}");
        if full {
            assert!(has("forces_integrate_collide_cu_sto"), "{names:?}");
            assert_eq!(has("forces_integrate_collide_cu_imm"), caps.immediates, "{names:?}");
        }
        if caps.float_atomics {
            assert!(has("springs_scatter_f32") && (!full || has("tri_normals_scatter_f32_sto")), "{names:?}");
        } else {
            println!("{}: no float atomics on this adapter: only the compare-exchange path is tested", api.name());
        }
    }
    let checks = validate_kernels(g.runner(), &kernels, n, 0x5eed + n as u64).unwrap();
    // Those with a bound that run on a grid (the mesh's XPBD pass is mesh_gpu.rs's).
    let bounded = kernels
        .iter()
        .filter(|k| matches!(k.def.check, Check::Bound { .. }) && k.def.cloths != k::Cloths::Mesh)
        .count();
    // The kernels without a bound have tests of their own: the hash's scatter
    // (self_collision.rs) and the statistics (below).
    let own: Vec<String> =
        kernels.iter().filter(|k| !matches!(k.def.check, Check::Bound { .. })).map(|k| k.shader_name()).collect();
    assert!(own.iter().all(|k| k.starts_with("hash_scatter") || k.starts_with("stats")), "{own:?}");
    // 13 kernels at least: a recipe or flavor list that lost kernels fails here.
    assert!(bounded >= 13, "{}: {bounded} kernels with a bound: {names:?}", api.name());
    assert_eq!(checks.len(), COMPARED_BUFFERS * bounded, "{}", api.name());
    assert_checks(&format!("{} n = {n}", api.name()), &checks);
    assert_api_clean(&mut *g);
}

clothlab_tests::per_api!(every_kernel_flavor_matches_its_cpu_twin_at_n_64);

fn every_kernel_flavor_matches_its_cpu_twin_at_n_64(api: Api) {
    kernels_match_on(api, 64, true);
}

clothlab_tests::per_api!(the_solvers_kernels_match_their_twins_at_sizes_that_are_not_multiples_of_a_workgroup);

fn the_solvers_kernels_match_their_twins_at_sizes_that_are_not_multiples_of_a_workgroup(api: Api) {
    for &n in odd_sizes(api) {
        kernels_match_on(api, n, false);
    }
}

clothlab_tests::per_api!(rollouts_of_112_substeps_of_every_preset_stay_close_to_the_cpu);

fn rollouts_of_112_substeps_of_every_preset_stay_close_to_the_cpu(api: Api) {
    // 7 frames, 112 substeps of the default 16 per frame: every kernel of each preset's
    // recipe runs in every substep, and the bound grows with the substeps (1e-6 m each),
    // so a kernel left out, doubled or rounding otherwise shows from its first substep
    // at least as clearly as over 208 (on llvmpipe the optimized presets end 0.0 m off,
    // the naive ones within rounding). 13 frames were 18 s of the suite on lavapipe.
    let frames = 7;
    let mut ends = Vec::new();
    for &variant in presets(api) {
        let Some(mut s) = solver(api, variant, 64) else { return };
        let c = validate_rollout(&mut *s, frames).unwrap();
        assert_checks(s.name(), std::slice::from_ref(&c));
        assert_api_clean(&mut *s);
        ends.push((c.bound, s.state().unwrap().pos));
    }
    // Naive against optimized: both differ from the CPU within the bound, so from each
    // other within twice of it.
    let mut ab = compare("naive vs opt", "pos", &ends[0].1, &ends[1].1, false, 0.0);
    ab.bound = 2.0 * ends[0].0;
    ab.error = ab.max_abs;
    assert_checks(&format!("{} rollout", api.name()), &[ab]);
}

clothlab_tests::per_api!(changed_parameters_reach_the_kernels);

fn changed_parameters_reach_the_kernels(api: Api) {
    // Stiffer bend springs, two strain passes and wind: a rollout with them must still
    // match the CPU solver given the same parameters (bound as in validate_rollout).
    let params = SimParams { bend_stiffness: 0.1, strain_iterations: 2, wind: [2.0, 0.0, 1.0], ..SimParams::default() };
    // Wind and gravity alone leave the spring tables as they are (no upload): they must
    // still reach the kernels through the frame's constants. (A gustier scene, wind
    // (-1.5, 0.5, 2) with gravity -6, makes the naive scatter's rounding grow to 3.1e-4 m
    // in 128 substeps, over ROLLOUT_BOUND_PER_SUBSTEP, with or without a table upload:
    // measured on lavapipe; the optimized variants stay bit-exact.)
    let light = SimParams { wind: [2.0, 0.0, 1.0], gravity: [0.0, -9.0, 0.0], ..SimParams::default() };
    for (what, p) in [("tables", &params), ("constants only", &light)] {
        for variant in [Variant::NAIVE, Variant::OPTIMIZED] {
            let Some(mut s) = solver(api, variant, 48) else { return };
            s.set_params(p.clone()).unwrap();
            let c = validate_rollout(&mut *s, 8).unwrap();
            assert_checks(&format!("{} set_params {what}", s.name()), &[c]);
            assert_api_clean(&mut *s);
        }
    }
}

clothlab_tests::per_api!(the_spring_table_from_storage_uniforms_or_an_image_gives_the_twins_results);

fn the_spring_table_from_storage_uniforms_or_an_image_gives_the_twins_results(api: Api) {
    // With the interior's uniform constants off, every particle reads its slots from the
    // table ([`tables`]): from read-only storage buffers, uniform blocks, or a sampled
    // image (the thesis's texture memory). Same arithmetic as the twins, so the kernel bounds of
    // validate_kernels apply; and a rollout stays within the rollout bound.
    for &table in tables(api) {
        let spec = VariantSpec::parse("optimized", &[format!("table={table}")]).unwrap();
        let Some(mut s) = solver(api, spec.clone(), 65) else { return };
        // With the image: its `_tex` flavors (every other flavor is the same kernel as
        // in the every-flavor test, which does not read the table's image).
        let kernels = if table == "image" {
            let tex = flavors(&s.caps(), true).into_iter().filter(|k| k.flavor.table_image).collect();
            // On wgpu, those one switch from the plain `_tex` one ([`one_switch_at_a_time`]).
            if api == Api::Wgpu { one_switch_at_a_time(tex, true) } else { tex }
        } else {
            s.kernels()
        };
        if table == "image" {
            let names: Vec<String> = kernels.iter().map(|k| k.shader_name()).collect();
            assert!(names.iter().any(|k| k == "forces_springs_tex_sto"), "{names:?}");
            assert!(names.iter().any(|k| k.starts_with("strain_limit_tex")), "{names:?}");
            let tex = kernels.iter().filter(|k| k.flavor.table_image).count();
            assert!(tex >= 9, "{}: {tex} `_tex` flavors: {names:?}", api.name());
            // Every kernel of the recipe that reads the table reads it from the image.
            let recipe = s.recipe_kernels();
            assert!(recipe.iter().all(|k| !k.def.variants.table_image || k.flavor.table_image), "{recipe:?}");
        }
        let checks = validate_kernels(s.runner(), &kernels, 65, 0x7ab1e).unwrap();
        assert_checks(&format!("{} table={table}", api.name()), &checks);
        assert_api_clean(&mut *s);
        // A fresh solver: the kernel checks left the disturbed state in this one.
        let Some(mut s) = solver(api, spec, 65) else { return };
        let c = validate_rollout(&mut *s, 6).unwrap();
        assert_checks(&format!("{} table={table} rollout", api.name()), &[c]);
        assert_api_clean(&mut *s);
    }
    // The thesis preset (springs scattered, the strain limit reading the image) rolled
    // out after stiffer springs are set, so that the image is rewritten (the raw APIs
    // roll it out in the rollouts' test).
    if api != Api::Wgpu {
        return;
    }
    let Some(mut t) = solver(api, Variant::THESIS, 48) else { return };
    assert_eq!(t.name(), format!("{}-thesis", api.name()));
    t.set_params(SimParams { bend_stiffness: 0.1, ..SimParams::default() }).unwrap();
    let c = validate_rollout(&mut *t, 8).unwrap();
    assert_checks(&format!("{} thesis rollout", api.name()), &[c]);
    assert_api_clean(&mut *t);
}

/// A solver with GPU statistics in `stats` mode, or `None` where the adapter refuses the
/// mode (in one line: subgroup arithmetic missing, as on GL on llvmpipe) or has none.
fn with_stats(api: Api, variant: Variant, stats: StatsMode) -> Option<Box<dyn AnyGpuSolver>> {
    let (sc, p, o) = (Scene::with_n(65), SimParams::default(), SolverOptions { stats });
    let r: Result<Box<dyn AnyGpuSolver>, SolverError> = match api {
        Api::Wgpu => clothlab_wgpu::wgpu_solver(variant, sc, p, o).map(|s| Box::new(s) as _),
        Api::Vulkan => clothlab_vulkan::vulkan_solver(variant, sc, p, true, o).map(|s| Box::new(s) as _),
        Api::Gl => clothlab_gl::gl_solver(variant, sc, p, o).map(|s| Box::new(s) as _),
    };
    match r {
        Err(e @ SolverError::Unsupported(_)) => {
            assert_eq!(stats, StatsMode::Subgroups, "{e}");
            assert!(!e.to_string().contains('\n'), "{e}");
            eprintln!("{}: refused {stats:?}: {e}", api.name());
            None
        }
        r => or_skip(r, api.name()),
    }
}

clothlab_tests::per_api!(gpu_statistics_match_the_cpu_twin_by_subgroups_and_by_atomics);

fn gpu_statistics_match_the_cpu_twin_by_subgroups_and_by_atomics(api: Api) {
    // n = 65: 4225 particles, the last workgroup partly empty. The max strain is a max of
    // the same f32 values the twin computes (length and a division: within 4 ulps of
    // ~1.1, so 1e-6 absolute). The energy is a sum of 4225 positive terms in another
    // order than the twin's f64 sum: by atomics in any order, relative error below
    // N·2^-24 = 2.5e-4; by subgroups a tree of depth ~log2(N) plus 67 partials in
    // sequence, so below 1e-4 too (measured on lavapipe: ~1e-7 both).
    for (variant, stats, energy_bound) in [
        (Variant::OPTIMIZED, StatsMode::Subgroups, 1e-4),
        (Variant::OPTIMIZED, StatsMode::Atomics, 2.5e-4),
        (Variant::NAIVE, StatsMode::Atomics, 2.5e-4),
    ] {
        let Some(mut s) = with_stats(api, variant, stats) else { return };
        s.stats_match_twin(energy_bound);
        assert_api_clean(&mut *s);
    }
}

#[test]
fn push_constants_are_refused_on_gl_in_one_line() {
    let spec = VariantSpec::parse("optimized", &["constants=push".to_string()]).unwrap();
    match clothlab_gl::gl_solver(spec, Scene::with_n(16), SimParams::default(), SolverOptions::default()) {
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.contains('\n') && msg.contains("immediates"), "{msg}");
        }
        Ok(_) => panic!("constants=push accepted on GL, which has no push constants"),
    }
}

#[test]
fn dropping_a_vulkan_solver_frees_every_allocation() {
    let options = SolverOptions { stats: StatsMode::Atomics };
    let spec = VariantSpec::parse("naive", &["table=image".into()]).unwrap();
    let r = clothlab_vulkan::vulkan_solver(spec, Scene::with_n(33), SimParams::default(), true, options);
    let Some(mut v): Option<clothlab_vulkan::VulkanSolver> = or_skip(r, "vulkan solver") else { return };
    v.step_frame().unwrap();
    let dev = v.engine().device();
    // 24 buffers (state, tables, constants, statistics, staging) and the table image.
    assert!(dev.live_allocations() >= 25, "{} allocations", dev.live_allocations());
    drop(v);
    assert_eq!(dev.live_allocations(), 0, "gpu-allocator still holds allocations after the solver is gone");
}
