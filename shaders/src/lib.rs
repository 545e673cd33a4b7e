//! clothlab-shaders: the WGSL kernels of the step, validated by naga when this crate
//! builds, as WGSL (for wgpu) and SPIR-V 1.3 (for Vulkan).
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
}

include!(concat!(env!("OUT_DIR"), "/kernels.rs"));

pub mod recipe;

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
        let imm = kernel("forces_springs_imm").expect("immediates twin");
        assert!(
            imm.wgsl.contains("var<immediate> step_params: StepParams;")
                && !imm.wgsl.contains("var<uniform> step_params")
        );
    }
}
