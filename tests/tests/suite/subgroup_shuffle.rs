//! `neighbours=shuffle` really passes values between lanes: a probe kernel built on
//! shared/window_sh.wgsl records, per invocation, whether its left and right lanes hold
//! the blocks beside it and what they passed. The `_sh` kernels are checked against their
//! twins elsewhere (they would pass even if every lane fell back to loading); this test
//! shows the shuffles are used, and carry the neighbour's value.

use clothlab_core::layout::Buf;
use clothlab_core::step_params::StepParams;
use clothlab_core::{Scene, SimParams};
use clothlab_engine::kernels::{Check, Count, HostBuffers, KernelDef, Source, TwinArgs, Variants};
use clothlab_engine::recipe::run;
use clothlab_engine::validate::KernelRunner;
use clothlab_engine::{SolverOptions, Variant};
use clothlab_tests::or_skip;
use clothlab_vulkan::vulkan_solver;
use clothlab_wgpu::wgpu_solver;

/// Not compared with a twin (what lanes a subgroup has is the adapter's): the test reads
/// the buffer itself.
fn no_twin(_: &TwinArgs, _: &mut HostBuffers) {}

/// Per invocation b (one per particle; every b of a "row" of 10⁶): force = (the value the
/// left lane passed, or -1 where it holds no block b - 1; the same from the right).
static PROBE: KernelDef = KernelDef {
    source: Source::Wgsl {
        includes: &["state", "window_sh"],
        body: "
@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    p = step_params;
    let b = flat_id(id, groups);
    window_start(b, 1000000u);
    let l = from_left3(vec3<f32>(f32(b), 0.0, 0.0));
    let r = from_right3(vec3<f32>(f32(b), 0.0, 0.0));
    if b < num_particles() {
        force[b] = vec4<f32>(select(-1.0, l.x, have_left()), select(-1.0, r.x, have_right()), 0.0, 0.0);
    }
}
",
    },
    check: Check::Own("the_lanes_of_a_subgroup_pass_their_neighbours_values"),
    label: "shuffle_probe",
    variants: Variants::NONE,
    ..KernelDef::new("shuffle_probe", no_twin, Count::Particles, &[Buf::Params, Buf::Force], &[Buf::Force])
};

#[test]
fn the_lanes_of_a_subgroup_pass_their_neighbours_values() {
    let n = 64u32;
    let scene = Scene::with_n(n);
    let params = SimParams::default();
    let mut runners: Vec<Box<dyn KernelRunner>> = Vec::new();
    let opts = SolverOptions::default();
    if let Some(g) = or_skip(wgpu_solver(Variant::OPTIMIZED, scene.clone(), params.clone(), opts), "wgpu") {
        runners.push(Box::new(g));
    }
    if let Some(v) = or_skip(vulkan_solver(Variant::OPTIMIZED, scene.clone(), params.clone(), true, opts), "vulkan") {
        runners.push(Box::new(v));
    }
    let (state, topo) = clothlab_core::build(&scene, &params).unwrap();
    let faces = vec![[0.0f32; 4]; topo.triangles.len()];
    let p = StepParams::new(&params, &scene, None);
    for mut r in runners {
        let name = r.adapter();
        r.add_kernel(PROBE.plain()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut bufs = HostBuffers::new(&state, faces.clone());
        r.run_commands(&run(PROBE.plain()), &p, &mut bufs).unwrap();
        let (mut left, mut right) = (0, 0);
        for (b, f) in bufs.force.iter().enumerate() {
            if f[0] != -1.0 {
                assert_eq!(f[0], b as f32 - 1.0, "{name}: invocation {b} got {} from its left lane", f[0]);
                left += 1;
            }
            if f[1] != -1.0 {
                assert_eq!(f[1], b as f32 + 1.0, "{name}: invocation {b} got {} from its right lane", f[1]);
                right += 1;
            }
        }
        // In subgroups of s lanes, s - 1 of every s have a left (right) neighbour: 7/8 on
        // lavapipe (s = 8). Half is what subgroups of 2 give, the least that has any.
        let np = (n * n) as usize;
        assert!(left >= np / 2 && right >= np / 2, "{name}: {left} left, {right} right of {np}");
        println!("{name}: {left} of {np} invocations got a value from the left, {right} from the right");
    }
}
