// GLSL for OpenGL 4.5 core from a validated naga module: shared by build.rs (the built-in
// kernels, written at build time) and lib.rs (kernels composed at run time), through
// `include!`, so that both map bindings the same way.

/// What [`glsl_450`] writes: the text, the binding points, the immediates' uniforms.
pub type GlslOut = (String, Vec<(u32, u8)>, Vec<(String, u32, char, u8)>);

/// The GLSL of `module`'s compute entry point `main`, for OpenGL 4.5 core, and where each
/// of its `@binding`s (group 0) goes: `(binding, binding point)`. GL numbers shader
/// storage blocks, uniform blocks and texture units apart, and a compute shader may use
/// only a few of each (16 storage blocks on llvmpipe), so every kind is numbered from 0
/// in binding order, over the bindings the entry point uses.
///
/// GL has no push constants: naga writes a module's immediates as plain uniforms, one per
/// scalar or vector, set with `glUniform*` before each dispatch. The third part lists them:
/// `(uniform name, byte offset in the immediates, kind 'u' | 'i' | 'f', components)`.
pub fn glsl_450(module: &naga::Module, info: &naga::valid::ModuleInfo, zero_workgroup: bool) -> Result<GlslOut, String> {
    let mut points = Vec::new();
    let (mut storage, mut uniform, mut texture) = (0u8, 0u8, 0u8);
    // Only what `main` uses: a kernel's includes declare more than it reads (the state's
    // buffers, the contact's), and each declared block would take one of the few points.
    let uses = module
        .entry_points
        .iter()
        .position(|e| e.stage == naga::ShaderStage::Compute && e.name == "main")
        .map(|index| info.get_entry_point(index));
    let mut bound: Vec<(u32, &naga::GlobalVariable)> = module
        .global_variables
        .iter()
        .filter(|(h, _)| uses.is_none_or(|u| !u[*h].is_empty()))
        .filter_map(|(_, g)| g.binding.as_ref().map(|b| (b.binding, g)))
        .collect();
    bound.sort_by_key(|(b, _)| *b);
    let mut binding_map = naga::back::glsl::BindingMap::default();
    for (b, g) in bound {
        let counter = match (&g.space, &module.types[g.ty].inner) {
            (naga::AddressSpace::Storage { .. }, _) => &mut storage,
            (naga::AddressSpace::Uniform, _) => &mut uniform,
            // naga combines a texture with the sampler it is sampled with: the sampler has
            // no point of its own (the solver sets the filtering on the texture's unit).
            (_, naga::TypeInner::Sampler { .. }) => continue,
            _ => &mut texture,
        };
        let point = *counter;
        *counter += 1;
        if let Some(rb) = g.binding {
            binding_map.insert(rb, point);
        }
        points.push((b, point));
    }
    let (text, reflection) = write_450(module, info, naga::ShaderStage::Compute, "main", binding_map, zero_workgroup)?;
    let mut uniforms = Vec::new();
    for item in reflection.immediates_items {
        use naga::back::glsl::{GlslScalarKind as K, GlslUniformType as T};
        let (scalar, components) = match item.ty {
            T::Scalar(s) => (s, 1),
            T::Vector { size, scalar } => (scalar, size as u8),
            T::Matrix { .. } => return Err(format!("immediate {}: a matrix (not set on GL)", item.access_path)),
        };
        if scalar.width != 4 {
            return Err(format!("immediate {}: {}-byte scalars (not set on GL)", item.access_path, scalar.width));
        }
        let kind = match scalar.kind {
            K::Uint => 'u',
            K::Sint => 'i',
            K::Float => 'f',
        };
        uniforms.push((item.access_path, item.offset, kind, components));
    }
    Ok((text, points, uniforms))
}

/// The GLSL 4.50 core of one vertex or fragment entry point of a render module (the
/// renderer's `render.wgsl`), for the OpenGL renderer. Its resources go to binding points
/// numbered per kind from 0 in `(group, binding)` order: uniform blocks, then textures
/// (texture units; naga combines each texture with the sampler it is sampled with, so a
/// sampler has no point of its own — the renderer binds a sampler object to the texture's
/// unit). Written as wgpu's clip space is (y up, depth 0 to 1): the renderer sets
/// `glClipControl(GL_UPPER_LEFT, GL_ZERO_TO_ONE)`, which makes GL's window and depth
/// conventions those of wgpu and Vulkan, so the shaders need no change.
pub fn glsl_450_stage(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    stage: naga::ShaderStage,
    entry: &str,
) -> Result<String, String> {
    let mut bound: Vec<(naga::ResourceBinding, &naga::GlobalVariable)> =
        module.global_variables.iter().filter_map(|(_, g)| g.binding.map(|b| (b, g))).collect();
    bound.sort_by_key(|(b, _)| (b.group, b.binding));
    let mut binding_map = naga::back::glsl::BindingMap::default();
    let (mut uniform, mut texture) = (0u8, 0u8);
    for (b, g) in bound {
        let counter = match (&g.space, &module.types[g.ty].inner) {
            (naga::AddressSpace::Uniform, _) => &mut uniform,
            (_, naga::TypeInner::Image { .. }) => &mut texture,
            _ => continue,
        };
        binding_map.insert(b, *counter);
        *counter += 1;
    }
    Ok(write_450(module, info, stage, entry, binding_map, false)?.0)
}

/// naga's GLSL 4.50 core of entry point `entry` (of `stage`) with `binding_map`, and its
/// reflection; workgroup memory zeroed as WGSL requires where `zero_workgroup` (a compute
/// kernel that writes all it reads first may go without: shaders/build.rs).
fn write_450(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    stage: naga::ShaderStage,
    entry: &str,
    binding_map: naga::back::glsl::BindingMap,
    zero_workgroup: bool,
) -> Result<(String, naga::back::glsl::ReflectionInfo), String> {
    let options = naga::back::glsl::Options {
        version: naga::back::glsl::Version::Desktop(450),
        writer_flags: naga::back::glsl::WriterFlags::empty(),
        binding_map,
        zero_initialize_workgroup_memory: zero_workgroup && stage == naga::ShaderStage::Compute,
    };
    let pipeline = naga::back::glsl::PipelineOptions { shader_stage: stage, entry_point: entry.into(), multiview: None };
    let mut text = String::new();
    let mut writer = naga::back::glsl::Writer::new(
        &mut text,
        module,
        info,
        &options,
        &pipeline,
        naga::proc::BoundsCheckPolicies::default(),
    )
    .map_err(|e| format!("GLSL output of {entry}: {e}"))?;
    let reflection = writer.write().map_err(|e| format!("GLSL output of {entry}: {e}"))?;
    Ok((text, reflection))
}

/// The `@binding`s (group 0) the compute entry point `main` of `module` uses in any way,
/// ascending (none for a module without one).
pub fn used_bindings(module: &naga::Module, info: &naga::valid::ModuleInfo) -> Result<Vec<u32>, String> {
    let Some(index) = module.entry_points.iter().position(|e| e.stage == naga::ShaderStage::Compute && e.name == "main")
    else {
        return Ok(Vec::new());
    };
    let uses = info.get_entry_point(index);
    let mut out: Vec<u32> = module
        .global_variables
        .iter()
        .filter(|(h, _)| !uses[*h].is_empty())
        .filter_map(|(_, g)| g.binding.filter(|b| b.group == 0).map(|b| b.binding))
        .collect();
    out.sort_unstable();
    Ok(out)
}

/// Whether kernel `name`'s workgroup memory is zeroed before it runs (WGSL's rule, which
/// naga writes as a store of the whole variable by one invocation). The tiled substep
/// writes every element it reads first (its load stage the whole region; the counts
/// before the pass that reads them), and its 32 KiB zeroed that way cost on llvmpipe two
/// minutes of compiling and 6× its running time (measured: 10 100 against 1 630 ns per
/// particle-substep at n = 64, what wgpu's driver-side zeroing ran at). The build writes
/// the SPIR-V and GLSL so; the wgpu backend asks wgpu for the same (its GL backend zeroes
/// by the polyfill too).
pub fn zero_workgroup_memory(name: &str) -> bool {
    !name.starts_with("substep_tile")
}
