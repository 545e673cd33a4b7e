// GLSL for OpenGL 4.5 core from a validated naga module: shared by build.rs (the built-in
// kernels, written at build time) and lib.rs (kernels composed at run time), through
// `include!`, so that both map bindings the same way.

/// The GLSL of `module`'s compute entry point `main`, for OpenGL 4.5 core, and where each
/// of its `@binding`s (group 0) goes: `(binding, binding point)`. GL numbers shader
/// storage blocks, uniform blocks and texture units apart, and a compute shader may use
/// only a few of each (16 storage blocks on llvmpipe), so every kind is numbered from 0
/// in binding order, over the bindings this module declares.
pub fn glsl_450(module: &naga::Module, info: &naga::valid::ModuleInfo) -> Result<(String, Vec<(u32, u8)>), String> {
    let mut points = Vec::new();
    let (mut storage, mut uniform, mut texture) = (0u8, 0u8, 0u8);
    let mut bound: Vec<(u32, &naga::GlobalVariable)> =
        module.global_variables.iter().filter_map(|(_, g)| g.binding.as_ref().map(|b| (b.binding, g))).collect();
    bound.sort_by_key(|(b, _)| *b);
    let mut binding_map = naga::back::glsl::BindingMap::default();
    for (b, g) in bound {
        let counter = match g.space {
            naga::AddressSpace::Storage { .. } => &mut storage,
            naga::AddressSpace::Uniform => &mut uniform,
            _ => &mut texture,
        };
        let point = *counter;
        *counter += 1;
        if let Some(rb) = g.binding {
            binding_map.insert(rb, point);
        }
        points.push((b, point));
    }
    let options = naga::back::glsl::Options {
        version: naga::back::glsl::Version::Desktop(450),
        writer_flags: naga::back::glsl::WriterFlags::empty(),
        binding_map,
        zero_initialize_workgroup_memory: true,
    };
    let pipeline = naga::back::glsl::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: "main".into(),
        multiview: None,
    };
    let mut text = String::new();
    let mut writer = naga::back::glsl::Writer::new(
        &mut text,
        module,
        info,
        &options,
        &pipeline,
        naga::proc::BoundsCheckPolicies::default(),
    )
    .map_err(|e| format!("GLSL output: {e}"))?;
    writer.write().map_err(|e| format!("GLSL output: {e}"))?;
    Ok((text, points))
}
