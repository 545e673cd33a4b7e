//! The contact between triangles on every GPU API: each of its kernels against its twin
//! on a piled thin heap, and the scene run on every API gives the CPU's bits.

use std::path::Path;

use clothlab_core::{CpuSolver, Exec, SceneFile, Solver};
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

#[test]
fn every_kernel_of_the_contact_between_triangles_matches_its_twin_on_every_api() {
    // The kernel checks' disturbed drape (validate.rs) with the heap's parameters: its
    // velocities put the reach at its cap, so every owner has pairs to find and push.
    let f = thin_heap(16);
    let input = clothlab_engine::validate::KernelInput::for_scene(&f.scene, 5, &f.params).unwrap();
    let b = input.for_kernel(clothlab_engine::kernels::TRI_IMPULSE_COUNT.plain());
    let ints: Vec<u32> = b.tri_ints.iter().flat_map(|v| v.map(f32::to_bits)).collect();
    let pairs = ints[clothlab_core::cpu::tri_contact::at::PAIRS];
    println!("the kernels' input: {pairs} pairs");
    assert!(pairs > 500, "{pairs} pairs: the kernel checks would hold little");
    for api in Api::ALL {
        let Some(mut gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { continue };
        let kernels: Vec<_> = TRI_CONTACT_KERNELS.iter().map(|d| d.plain()).collect();
        let checks = validate_kernels_with(gpu.runner(), &kernels, &f.scene, 5, &f.params).unwrap();
        assert_eq!(checks.len(), kernels.len() * clothlab_engine::validate::COMPARED_BUFFERS);
        assert_checks(api.name(), &checks);
    }
}

#[test]
fn the_thin_heap_runs_on_every_api_with_the_cpu_bits() {
    // 24 × 24, 90 frames: the heap lands and piles (pairs within the reach, impulses,
    // pushes and cuts at the frames' ends); every API's state and the contact's counts
    // at every frame's end are the CPU's bits (every sum is an integer sum, and every
    // expression is written as core computes it).
    const FRAMES: usize = 90;
    let f = thin_heap(24);
    let mut cpu = CpuSolver::new(Exec::Serial, f.scene.clone(), f.params.clone()).unwrap();
    let mut want = Vec::new();
    for _ in 0..FRAMES {
        cpu.step_frame().unwrap();
        want.push(cpu.contact_stats().unwrap());
    }
    let state = cpu.state().unwrap();
    let most = want.iter().map(|s| s.pairs).max().unwrap();
    let acted = want.iter().filter(|s| s.slowed + s.pushed + s.clamped > 0).count();
    println!("cpu: at most {most} pairs, the contact acting at {acted} of {FRAMES} frames' ends");
    assert!(most > 100 && acted > 5, "the heap did not pile: the test would hold little");
    let triangles = cpu.topology().triangles.clone();
    for api in Api::ALL {
        let Some(gpu) = api.solver(Variant::OPTIMIZED, &f.scene, &f.params) else { continue };
        let mut s = gpu.into_solver();
        for (frame, w) in want.iter().enumerate() {
            s.step_frame().unwrap();
            let got = s.contact_stats().unwrap();
            assert_eq!(got, *w, "{} frame {frame}", api.name());
        }
        let got = s.state().unwrap();
        let crossed = clothlab_core::crossings::count(&got.pos, &triangles).pairs;
        println!("{}: {crossed} crossings, CPU's bits: {}", api.name(), got.pos == state.pos && got.vel == state.vel);
        assert_eq!(crossed, 0, "{}: the heap crossed itself", api.name());
        assert!(got.pos == state.pos && got.vel == state.vel, "{}: not the CPU's bits", api.name());
    }
}
