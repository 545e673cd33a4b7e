//! clothlab-shaders: the WGSL kernels of the step, validated by naga when this crate
//! builds, as WGSL (for wgpu), SPIR-V 1.3 (for Vulkan) and GLSL 4.50 core (for OpenGL;
//! every compute flavor, with its binding points: [`Kernel::gl_points`]).
//!
//! Sources live in `wgsl/`: one file per kernel (its entry point is `main`), `shared/`
//! for the structs that mirror clothlab-core's `#[repr(C)]` types and for functions
//! several kernels use. A kernel's first line `//! include: a, b` names the shared files
//! it needs; `shared/types.wgsl` is always first. The build fails on a WGSL error and
//! on a shared struct whose size or field offsets differ from core's. Every kernel that
//! reads the step constants `p` from the uniform buffer (binding 0) also exists as
//! `<name>_imm`, reading them from immediates (push constants) instead; every kernel that
//! includes `atomic_cas` (float addition by compare-exchange) also exists as
//! `<name>_f32`, using float atomics.
#![forbid(unsafe_code)]

/// One compiled kernel.
#[derive(Debug, Clone, Copy)]
pub struct Kernel {
    /// File stem, e.g. `forces`.
    pub name: &'static str,
    /// The complete WGSL source (shared files included).
    pub wgsl: &'static str,
    /// SPIR-V 1.3, little-endian words as bytes.
    pub spirv: &'static [u8],
    /// GLSL 4.50 core for OpenGL, written by naga from the same module (empty for the
    /// render shader, which is not a compute kernel).
    pub glsl: &'static str,
    /// Where the GLSL's bindings go: `(@binding, GL binding point)`, each kind (storage
    /// blocks, uniform blocks, textures) numbered from 0 in binding order.
    pub gl_points: &'static [(u32, u8)],
    /// Its immediates as GL uniforms (GL has no push constants; naga writes them as
    /// uniforms): `(name, byte offset, 'u' | 'i' | 'f', components)`.
    pub gl_uniforms: &'static [(&'static str, u32, char, u8)],
    /// The `@binding` numbers (group 0) its entry point reads (atomics included), as naga
    /// finds them; each checked against `clothlab_core::layout::Buf` by the build.
    pub reads: &'static [u32],
    /// The `@binding` numbers it writes.
    pub writes: &'static [u32],
    /// Every `@binding` (group 0) its compute entry point uses in any way (reads, writes,
    /// atomics, `arrayLength`): what a pipeline layout of its own must hold (wgpu on GL,
    /// whose 16 storage blocks per stage cannot hold every binding of the step at once).
    pub uses: &'static [u32],
}

include!(concat!(env!("OUT_DIR"), "/kernels.rs"));

include!(concat!(env!("OUT_DIR"), "/render_glsl.rs"));

include!("glsl_out.rs");

/// What every kernel starts with: the constants generated from `clothlab_core::layout`,
/// then `shared/types.wgsl`.
pub const PRELUDE: &str = include_str!(concat!(env!("OUT_DIR"), "/prelude.wgsl"));

/// A kernel's complete WGSL as the build composes it: [`PRELUDE`], the shared files named
/// in `includes` (file stems of `shared/`, e.g. `state`), then `body`. For kernels given
/// at run time; an unknown include is refused.
pub fn compose(includes: &[&str], body: &str) -> Result<String, String> {
    let mut source = String::from(PRELUDE);
    for inc in includes {
        let (_, text) = SHARED.iter().find(|(name, _)| name == inc).ok_or_else(|| {
            let known: Vec<&str> = SHARED.iter().map(|(n, _)| *n).collect();
            format!("no shared file `{inc}` (there are: {})", known.join(", "))
        })?;
        source.push_str(&format!("\n// ---- shared/{inc}.wgsl\n"));
        source.push_str(text);
    }
    source.push_str("\n// ---- kernel\n");
    source.push_str(body);
    Ok(source)
}

/// Parses and validates `wgsl` with naga and writes SPIR-V 1.3 (what the build does for the
/// built-in kernels, at run time); the error is naga's message with the source location.
pub fn compile_spirv(name: &str, wgsl: &str) -> Result<Vec<u32>, String> {
    let path = format!("{name}.wgsl");
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.emit_to_string_with_path(wgsl, &path))?;
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    let info = validator.validate(&module).map_err(|e| e.emit_to_string_with_path(wgsl, &path))?;
    let options = naga::back::spv::Options { lang_version: (1, 3), ..Default::default() };
    naga::back::spv::write_vec(&module, &info, &options, None).map_err(|e| format!("SPIR-V output: {e}"))
}

/// Parses and validates `wgsl` with naga and writes GLSL 4.50 for OpenGL with its binding
/// points (what the build does for the built-in kernels, at run time).
pub fn compile_glsl(name: &str, wgsl: &str) -> Result<GlslOut, String> {
    let path = format!("{name}.wgsl");
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.emit_to_string_with_path(wgsl, &path))?;
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    let info = validator.validate(&module).map_err(|e| e.emit_to_string_with_path(wgsl, &path))?;
    glsl_450(&module, &info, true)
}

/// The `@binding`s (group 0) the compute entry point `main` of `wgsl` uses, as
/// [`Kernel::uses`] lists them for the built-in kernels (for kernels given at run time).
pub fn uses(name: &str, wgsl: &str) -> Result<Vec<u32>, String> {
    let path = format!("{name}.wgsl");
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.emit_to_string_with_path(wgsl, &path))?;
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    let info = validator.validate(&module).map_err(|e| e.emit_to_string_with_path(wgsl, &path))?;
    used_bindings(&module, &info)
}

/// The kernel called `name`.
pub fn kernel(name: &str) -> Option<&'static Kernel> {
    KERNELS.iter().find(|k| k.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kernel_is_there_with_spirv() {
        for name in [
            "forces",
            "springs",
            "springs_scatter",
            "forces_springs",
            "integrate",
            "collide",
            "integrate_collide",
            "strain_limit",
            "tri_normals",
            "tri_normals_scatter",
            "vertex_normals",
            "vertex_normals_naive",
        ] {
            let k = kernel(name).unwrap_or_else(|| panic!("no kernel {name}"));
            assert!(k.wgsl.contains("fn main("), "{name} has no entry point");
            // SPIR-V magic number, little-endian.
            assert_eq!(&k.spirv[..4], &[0x03, 0x02, 0x23, 0x07], "{name}");
            assert_eq!(k.spirv.len() % 4, 0);
        }
        let forces = kernel("forces").expect("forces");
        assert_eq!((forces.reads, forces.writes), (&[0, 1, 2, 3][..], &[3][..]));
        let imm = kernel("forces_springs_imm").expect("immediates twin");
        assert!(
            imm.wgsl.contains("var<immediate> step_params: StepParams;")
                && !imm.wgsl.contains("var<uniform> step_params")
        );
    }

    #[test]
    fn every_compute_kernel_has_glsl_450_with_a_binding_point_for_each_binding_it_uses() {
        let mut most = 0;
        for k in KERNELS.iter().filter(|k| k.wgsl.contains("@compute")) {
            assert!(k.glsl.starts_with("#version 450 core"), "{}: {}", k.name, &k.glsl[..k.glsl.len().min(40)]);
            assert!(k.glsl.contains("void main()"), "{}", k.name);
            for b in k.reads.iter().chain(k.writes) {
                // (A sampler has none: naga combines it with the texture it samples, and
                // the texture's unit carries the filtering.)
                let sampler = clothlab_core::layout::Buf::from_binding(*b)
                    .is_some_and(|buf| buf.kind() == clothlab_core::layout::BindKind::Sampler);
                assert!(
                    sampler || k.gl_points.iter().any(|(x, _)| x == b),
                    "{}: binding {b} has no GL binding point",
                    k.name
                );
            }
            // Each kind numbered from 0 without gaps: the points of a kind are 0..count.
            let mut pts: Vec<u8> = k.gl_points.iter().map(|p| p.1).collect();
            pts.sort_unstable();
            assert_eq!(pts[0], 0, "{}", k.name);
            most = most.max(k.gl_points.len());
            // llvmpipe (Mesa 22.3.6) offers 16 storage blocks to a compute shader
            // (GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS, glxinfo 2026-11-24). The points are
            // numbered over the storage bindings a kernel declares (its includes'), not only
            // those it reads: vbd_colour declares 16, at the limit (the capsules share the
            // bodies' `shapes` binding for that: a 17th made GL refuse the VBD sweep). GL
            // 4.5 guarantees only 8: a GL engine must refuse the kernels above its limit in
            // one line.
            let storage = k
                .gl_points
                .iter()
                .filter(|(b, _)| {
                    clothlab_core::layout::Buf::from_binding(*b)
                        .is_some_and(|buf| buf.kind() == clothlab_core::layout::BindKind::Storage)
                })
                .count();
            assert!(storage <= 16, "{}: {storage} storage blocks, more than llvmpipe's 16", k.name);
        }
        assert!(most > 0);
        // The same mapping at run time as at build time.
        let forces = kernel("forces").unwrap();
        let (text, points, uniforms) = compile_glsl("forces", forces.wgsl).unwrap();
        assert_eq!((text.as_str(), points.as_slice()), (forces.glsl, forces.gl_points));
        assert!(uniforms.is_empty() && forces.gl_uniforms.is_empty());
        // The statistics' substep index (a u32 immediate) is one uniform at offset 0; the
        // `_imm` twins' step constants are many.
        assert_eq!(kernel("stats_atomic").unwrap().gl_uniforms, &[("_immediates_binding_cs.substep", 0, 'u', 1)]);
        let imm = kernel("forces_imm").unwrap().gl_uniforms;
        assert!(imm.len() > 8 && imm.windows(2).all(|w| w[0].1 < w[1].1), "{imm:?}");
    }

    #[test]
    fn kernels_compose_and_compile_at_run_time_and_errors_say_where() {
        let body = "@compute @workgroup_size(WORKGROUP)\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {\n    p = step_params;\n}\n";
        let src = compose(&["state"], body).expect("state is a shared file");
        let words = compile_spirv("ok", &src).expect("valid WGSL compiles");
        assert_eq!(words[0], 0x0723_0203);
        let bad = compose(&["state"], "fn main() { let x: f32 = 1u; }").unwrap();
        let e = compile_spirv("bad", &bad).unwrap_err();
        assert!(e.contains("bad.wgsl"), "{e}");
        assert!(compose(&["nonexistent"], body).unwrap_err().contains("nonexistent"));
    }
}
