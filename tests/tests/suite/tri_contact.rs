//! The contact between triangles on every GPU API: each of its kernels against its twin
//! on a piled thin heap, and the scene run on every API gives the CPU's bits.

use std::path::Path;

use clothlab_core::{SceneFile, Solver};
use clothlab_cpu::{CpuSolver, Exec};
use clothlab_engine::Variant;
use clothlab_engine::kernels::TRI_CONTACT_KERNELS;
use clothlab_engine::validate::validate_kernels_with;
use clothlab_tests::{Api, assert_checks};

/// scenes/thin-heap.toml at n = `n`, piled by `frames` frames on the CPU: the scene with
/// the piled state as its cloth's start is not something a scene can say, so the kernel
/// checks start from the scene's own disturbed drape (validate.rs) with the heap's
/// parameters.
fn thin_heap(n: u32) -> SceneFile {
    let mut f = SceneFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/thin-heap.toml")).unwrap();
    f.scene.cloth.n = n;
    f
}

clothlab_tests::per_api!(every_kernel_of_the_contact_between_triangles_matches_its_twin);

fn every_kernel_of_the_contact_between_triangles_matches_its_twin(api: Api) {
    // The kernel checks' disturbed drape (validate.rs) with the heap's parameters: its
    // velocities put the reach at its cap, so every owner has pairs to find and push.
    let f = thin_heap(16);
    let input = clothlab_engine::validate::KernelInput::for_scene(&f.scene, 5, &f.params).unwrap();
    let b = input.for_kernel(clothlab_engine::kernels::TRI_IMPULSE_COUNT.plain());
    let ints: Vec<u32> = b.tri_ints.iter().flat_map(|v| v.map(f32::to_bits)).collect();
    let pairs = ints[clothlab_cpu::tri_contact::at::PAIRS];
    println!("the kernels' input: {pairs} pairs");
    assert!(pairs > 500, "{pairs} pairs: the kernel checks would hold little");
    let Some(mut gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { return };
    let kernels: Vec<_> = TRI_CONTACT_KERNELS.iter().map(|d| d.plain()).collect();
    let checks = validate_kernels_with(gpu.runner(), &kernels, &f.scene, 5, &f.params).unwrap();
    assert_eq!(checks.len(), kernels.len() * clothlab_engine::validate::COMPARED_BUFFERS);
    assert_checks(api.name(), &checks);
}

/// The contact's outcome at each frame's end, the final state and the triangles.
type HeapRun = (Vec<clothlab_core::ContactStats>, clothlab_core::ClothState, Vec<[u32; 3]>);

/// The thin heap `f` on the serial CPU solver for `frames` frames ([`HeapRun`]): computed
/// once for the API rows.
fn thin_heap_on_the_cpu(f: &SceneFile, frames: usize) -> &'static HeapRun {
    static RUN: std::sync::OnceLock<HeapRun> = std::sync::OnceLock::new();
    RUN.get_or_init(|| {
        let mut cpu = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
        let mut want = Vec::new();
        for _ in 0..frames {
            cpu.step_frame().unwrap();
            want.push(cpu.contact_stats().unwrap().outcome());
        }
        (want, cpu.state().unwrap(), cpu.topology().triangles.clone())
    })
}

clothlab_tests::per_api!(the_thin_heap_runs_with_the_cpu_bits);

fn the_thin_heap_runs_with_the_cpu_bits(api: Api) {
    // 24 × 24, 90 frames: the heap lands and piles (pairs within the reach, impulses,
    // pushes and cuts at the frames' ends); every API's state and the contact's counts
    // at every frame's end are the CPU's bits (every sum is an integer sum, and every
    // expression is written as core computes it).
    const FRAMES: usize = 90;
    let f = thin_heap(24);
    let (want, state, triangles) = thin_heap_on_the_cpu(&f, FRAMES);
    let most = want.iter().map(|s| s.pairs).max().unwrap();
    let acted = want.iter().filter(|s| s.slowed + s.pushed + s.clamped > 0).count();
    println!("cpu: at most {most} pairs, the contact acting at {acted} of {FRAMES} frames' ends");
    assert!(most > 100 && acted > 5, "the heap did not pile: the test would hold little");
    let Some(gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { return };
    let mut s = gpu.into_solver();
    for (frame, w) in want.iter().enumerate() {
        s.step_frame().unwrap();
        let got = s.contact_stats().unwrap().outcome();
        assert_eq!(got, *w, "{} frame {frame}", api.name());
    }
    let got = s.state().unwrap();
    let crossed = clothlab_core::crossings::count(&got.pos, triangles).pairs;
    println!("{}: {crossed} crossings, CPU's bits: {}", api.name(), got.pos == state.pos && got.vel == state.vel);
    assert_eq!(crossed, 0, "{}: the heap crossed itself", api.name());
    assert!(got.pos == state.pos && got.vel == state.vel, "{}: not the CPU's bits", api.name());
}

#[test]
fn owners_over_their_slots_keep_their_nearest_pairs_on_every_api() {
    // The heap piled 60 frames at n = 24, its velocities 40 times the pile's (the reach at
    // its cap, two spacings beyond the thickness: thousands of owners find more pairs
    // than their 32 slots): the start stage (speed, start, grid, pairs) on each API
    // against the CPU engine's twins — the kept pairs (the nearest, in the slots the
    // kernel's walk leaves them), their distances, counts and bounds, exactly.
    use clothlab_core::{StepParams, build};
    use clothlab_engine::cpu::{CpuEngine, start_buffers};
    use clothlab_engine::recipe::{Command, KernelRunner};
    let f = thin_heap(24);
    let mut cpu = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    for _ in 0..60 {
        cpu.step_frame().unwrap();
    }
    let mut state = cpu.state().unwrap();
    for v in &mut state.vel {
        for c in v.iter_mut().take(3) {
            *c *= 40.0;
        }
    }
    let (_, topo) = build(&f.scene, &f.params).unwrap();
    let engine = CpuEngine::new(Exec::Serial, f.scene.clone(), topo);
    let p = StepParams::new(&f.params, &f.scene, None);
    let start = start_buffers(Exec::Serial, &p, engine.topology(), &state);
    let until_pairs = |commands: &[Command]| -> Vec<Command> {
        let end = commands.iter().position(|c| c.kernel().is_some_and(|k| k.def.name == "tri_pairs")).unwrap();
        commands[..=end].to_vec()
    };
    let words = |v: &[[f32; 4]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<u32>>();
    let options = clothlab_engine::SolverOptions::default;
    let mut runners: Vec<(&str, Box<dyn KernelRunner>, Vec<Command>)> = Vec::new();
    let (sc, pa) = (f.scene.clone(), f.params.clone());
    if let Some(g) = clothlab_tests::or_skip(
        clothlab_wgpu::wgpu_solver(Variant::OPTIMIZED, sc.clone(), pa.clone(), options()),
        "wgpu",
    ) {
        let c = until_pairs(&g.commands());
        runners.push(("wgpu", Box::new(g), c));
    }
    if let Some(g) = clothlab_tests::or_skip(
        clothlab_vulkan::vulkan_solver(Variant::OPTIMIZED, sc.clone(), pa.clone(), true, options()),
        "vulkan",
    ) {
        let c = until_pairs(&g.commands());
        runners.push(("vulkan", Box::new(g), c));
    }
    if let Some(g) = clothlab_tests::or_skip(clothlab_gl::gl_solver(Variant::OPTIMIZED, sc, pa, options()), "gl") {
        let c = until_pairs(&g.commands());
        runners.push(("gl", Box::new(g), c));
    }
    for (name, mut r, commands) in runners {
        let mut want = start.clone();
        engine.run(&commands, &p, 0, &mut want);
        let ints = words(&want.tri_ints);
        let over = ints[clothlab_cpu::tri_contact::at::OVERFLOW];
        println!("{name}: {} pairs, {over} beyond the owners' slots", ints[clothlab_cpu::tri_contact::at::PAIRS]);
        assert!(over > 1000, "{over} pairs beyond the slots: the test would hold little");
        let mut got = start.clone();
        r.run_commands(&commands, &p, &mut got).unwrap();
        assert!(words(&got.tri_pairs) == words(&want.tri_pairs), "{name}: the kept pairs differ");
        assert!(words(&got.tri_ints) == ints, "{name}: the counts or the grid differ");
        assert!(words(&got.tri_floats) == words(&want.tri_floats), "{name}: the bounds differ");
    }
}

#[test]
fn xpbd_takes_the_contact_as_constraints_of_each_iteration_with_the_cpu_bits_on_vulkan_and_gl() {
    // XPBD with four iterations, the separation after each: 40 frames of the thin heap at
    // n = 24 (landing from frame 30) give the CPU's bits and no crossing (a
    // GL run of 90 frames left them at substep 930 until a side's weights were made
    // opaque to Mesa's lerp rewrite in Σ w² / m too: checked by hand, 90 frames).
    const FRAMES: usize = 40;
    let mut f = thin_heap(24);
    f.params.integrator = clothlab_core::Integrator::Xpbd;
    f.params.xpbd_iterations = 4;
    let mut cpu = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let (mut most, mut pushed) = (0, 0);
    for _ in 0..FRAMES {
        cpu.step_frame().unwrap();
        let s = cpu.contact_stats().unwrap();
        (most, pushed) = (most.max(s.pairs), pushed + s.pushed);
    }
    let (state, stats) = (cpu.state().unwrap(), cpu.contact_stats().unwrap().outcome());
    println!("cpu: at most {most} pairs, {pushed} pushes at the frames' last substeps");
    assert!(most > 1000 && pushed > 100, "the heap did not pile: the test would hold little");
    let triangles = cpu.topology().triangles.clone();
    // Raw Vulkan and GL: wgpu compiles the same WGSL through the same SPIR-V path as raw
    // Vulkan (the thin-heap test above holds all three), and the suite's time is budgeted.
    for api in [Api::Vulkan, Api::Gl] {
        let Some(gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { continue };
        let mut s = gpu.into_solver();
        for _ in 0..FRAMES {
            s.step_frame().unwrap();
        }
        let got = s.state().unwrap();
        let crossed = clothlab_core::crossings::count(&got.pos, &triangles).pairs;
        assert_eq!(crossed, 0, "{}: the heap crossed itself", api.name());
        assert!(got.pos == state.pos && got.vel == state.vel, "{}: not the CPU's bits", api.name());
        assert_eq!(s.contact_stats().unwrap().outcome(), stats, "{}", api.name());
    }
}

#[test]
fn vbd_takes_the_contact_inside_its_solves_with_the_cpu_bits_on_vulkan_and_gl() {
    // The thin heap at n = 24 piled by 45 frames of Verlet on the CPU, then 3 frames of VBD
    // (8 sweeps a substep, each colour's contact terms found at the iterate before its
    // solves) from that state on the CPU and on raw Vulkan and GL (wgpu shares raw Vulkan's
    // SPIR-V path; the kernel checks above hold all three to the twins): the contact's
    // counts at every frame's end and the final state the CPU's bits (integer sums, and
    // the block's sums kept from the compiler's rewrites: shared/vbd.wgsl's `kept`), no
    // crossing at any frame's end, and no two primitives closer than a quarter of the
    // thickness (the core tests measure 0.86–0.96 t on the CPU).
    const FRAMES: usize = 3;
    let f = thin_heap(24);
    let mut pile = CpuSolver::new(Exec::Parallel, f.scene.clone(), f.params.clone()).unwrap();
    for _ in 0..45 {
        pile.step_frame().unwrap();
    }
    let piled = pile.state().unwrap();
    let triangles = pile.topology().triangles.clone();
    let t = f.params.self_thickness;
    let mut params = f.params.clone();
    params.integrator = clothlab_core::Integrator::Vbd;
    let run = |name: &str, s: &mut dyn Solver| {
        s.set_state(&piled).unwrap();
        let mut stats = Vec::new();
        for _ in 0..FRAMES {
            s.step_frame().unwrap();
            let st = s.state().unwrap();
            assert_eq!(
                clothlab_core::crossings::count(&st.pos, &triangles).pairs,
                0,
                "{name}: the heap crossed itself"
            );
            stats.push(s.contact_stats().unwrap().outcome());
        }
        (s.state().unwrap(), stats)
    };
    let (want, want_stats) = run("cpu", &mut CpuSolver::new(Exec::Parallel, f.scene.clone(), params.clone()).unwrap());
    let most = want_stats.iter().map(|s| s.pairs).max().unwrap();
    let closest = clothlab_core::tri_contact::closest_pair(&want.pos, &triangles);
    println!("cpu: at most {most} pairs, closest pair {:.2} t", closest / t);
    // (Measured 500–1400 pairs within the reach at a frame's last substep.)
    assert!(most > 300, "{most} pairs: the heap is not piled, the test would hold little");
    assert!(closest > 0.25 * t, "two primitives {closest} m apart, thickness {t}");
    assert!(want.pos.iter().chain(&want.vel).all(|v| v.iter().all(|c| c.is_finite())), "not finite");
    for api in [Api::Vulkan, Api::Gl] {
        let Some(gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &params) else { continue };
        let (got, got_stats) = run(api.name(), &mut *gpu.into_solver());
        assert_eq!(got_stats, want_stats, "{}: the contact's counts", api.name());
        assert!(got.pos == want.pos && got.vel == want.vel, "{}: not the CPU's bits", api.name());
    }
}
