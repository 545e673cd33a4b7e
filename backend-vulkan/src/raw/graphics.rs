//! The drawing half of the raw layer: samplers, pipeline layouts, graphics pipelines with
//! dynamic rendering (Vulkan 1.3, no render-pass objects), descriptor sets that mix
//! buffers, images and samplers, and the recording of passes and draws.

use std::ffi::CStr;

use std::sync::Arc;

use super::pipelines::Set;
use super::*;

/// A sampler.
pub struct Sampler {
    dev: Arc<Device>,
    /// The Vulkan sampler.
    pub sampler: vk::Sampler,
    pub(super) alive: super::device::Alive,
}

impl Sampler {
    /// A linear sampler: a depth comparison (≤) clamped to the edge when `compare`, else a
    /// repeating colour sampler.
    pub fn new(dev: &Arc<Device>, compare: bool) -> Result<Self, VkError> {
        let address = if compare { vk::SamplerAddressMode::CLAMP_TO_EDGE } else { vk::SamplerAddressMode::REPEAT };
        Self::with(dev, address, compare)
    }

    /// A trilinear sampler clamped to the edge, no comparison (the bodies' distance
    /// fields, `sdf=image`).
    pub fn clamped(dev: &Arc<Device>) -> Result<Self, VkError> {
        Self::with(dev, vk::SamplerAddressMode::CLAMP_TO_EDGE, false)
    }

    fn with(dev: &Arc<Device>, address: vk::SamplerAddressMode, compare: bool) -> Result<Self, VkError> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(address)
            .address_mode_v(address)
            .address_mode_w(address)
            .compare_enable(compare)
            .compare_op(vk::CompareOp::LESS_OR_EQUAL)
            .max_lod(0.25);
        // SAFETY: valid device and create info; destroyed in Drop.
        let sampler = unsafe { dev.device.create_sampler(&info, None) }.map_err(vk_err("creating a sampler"))?;
        Ok(Self { dev: dev.clone(), sampler, alive: super::device::Alive::new() })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        self.alive.end();
        let sampler = self.sampler;
        // SAFETY: retire runs this once the device is idle.
        self.dev.retire(|d| unsafe { d.destroy_sampler(sampler, None) });
    }
}

/// Descriptor-set layouts and the pipeline layout over them (no push constants).
pub struct PipelineLayout {
    dev: Arc<Device>,
    /// One layout per set, in set order.
    pub sets: Vec<vk::DescriptorSetLayout>,
    /// The pipeline layout.
    pub layout: vk::PipelineLayout,
}

impl PipelineLayout {
    /// `sets[k]` lists set k's bindings: (binding, type, stages).
    pub fn new(
        dev: &Arc<Device>,
        sets: &[&[(u32, vk::DescriptorType, vk::ShaderStageFlags)]],
    ) -> Result<Self, VkError> {
        let mut me = Self { dev: dev.clone(), sets: Vec::new(), layout: vk::PipelineLayout::null() };
        for set in sets {
            let b: Vec<vk::DescriptorSetLayoutBinding> = set
                .iter()
                .map(|&(binding, ty, stages)| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(binding)
                        .descriptor_type(ty)
                        .descriptor_count(1)
                        .stage_flags(stages)
                })
                .collect();
            // SAFETY: valid device and create info; destroyed in Drop (also on failure below).
            let l = unsafe {
                dev.device
                    .create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&b), None)
            }
            .map_err(vk_err("creating a set layout"))?;
            me.sets.push(l);
        }
        // SAFETY: the set layouts are live.
        me.layout = unsafe {
            dev.device.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().set_layouts(&me.sets), None)
        }
        .map_err(vk_err("creating a pipeline layout"))?;
        Ok(me)
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        let (layout, sets) = (self.layout, std::mem::take(&mut self.sets));
        // SAFETY: retire runs this once the device is idle; null handles are ignored.
        self.dev.retire(|d| unsafe {
            d.destroy_pipeline_layout(layout, None);
            for l in &sets {
                d.destroy_descriptor_set_layout(*l, None);
            }
        });
    }
}

/// One vertex buffer binding: stride and (location, format, offset) per attribute.
#[derive(Debug, Clone)]
pub struct VertexBinding {
    /// Bytes per vertex.
    pub stride: u32,
    /// The attributes read from it.
    pub attributes: Vec<(u32, vk::Format, u32)>,
}

/// What a graphics pipeline draws.
pub struct PipelineDesc<'a> {
    /// Vertex entry point.
    pub vs: &'a CStr,
    /// Fragment entry point (none: depth only).
    pub fs: Option<&'a CStr>,
    /// Vertex buffers, bound at 0, 1, …
    pub bindings: Vec<VertexBinding>,
    /// Points, lines or triangles.
    pub topology: vk::PrimitiveTopology,
    /// Samples per pixel.
    pub samples: vk::SampleCountFlags,
    /// Colour target format (none: depth only).
    pub color: Option<vk::Format>,
    /// Depth target format (tested with <, written).
    pub depth: vk::Format,
    /// Constant and slope depth bias (the shadow pass).
    pub depth_bias: Option<(f32, f32)>,
}

/// A graphics pipeline for dynamic rendering; viewport and scissor are dynamic.
pub struct GraphicsPipeline {
    dev: Arc<Device>,
    /// The pipeline.
    pub pipeline: vk::Pipeline,
    /// Its layout (owned by a [`PipelineLayout`]).
    pub layout: vk::PipelineLayout,
}

impl GraphicsPipeline {
    /// A pipeline from the SPIR-V module `spirv` (entry points named in `desc`).
    pub fn new(
        dev: &Arc<Device>,
        layout: &PipelineLayout,
        spirv: &[u8],
        desc: &PipelineDesc<'_>,
    ) -> Result<Self, VkError> {
        if !spirv.len().is_multiple_of(4) {
            return Err(VkError::Vulkan { what: "loading SPIR-V", reason: "length not a multiple of 4".into() });
        }
        let words: Vec<u32> = spirv.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let d = &dev.device;
        let mut stages =
            vec![vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).name(desc.vs)];
        if let Some(fs) = desc.fs {
            stages.push(vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).name(fs));
        }
        let bindings: Vec<vk::VertexInputBindingDescription> = desc
            .bindings
            .iter()
            .enumerate()
            .map(|(k, b)| {
                vk::VertexInputBindingDescription::default()
                    .binding(k as u32)
                    .stride(b.stride)
                    .input_rate(vk::VertexInputRate::VERTEX)
            })
            .collect();
        let attributes: Vec<vk::VertexInputAttributeDescription> = desc
            .bindings
            .iter()
            .enumerate()
            .flat_map(|(k, b)| {
                b.attributes.iter().map(move |&(location, format, offset)| {
                    vk::VertexInputAttributeDescription::default()
                        .binding(k as u32)
                        .location(location)
                        .format(format)
                        .offset(offset)
                })
            })
            .collect();
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes);
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let (bias_on, (bias_constant, bias_slope)) = (desc.depth_bias.is_some(), desc.depth_bias.unwrap_or((0.0, 0.0)));
        // Counter-clockwise front faces and no culling, as the wgpu renderer: the shaders
        // are compiled with the same y flip wgpu applies (naga's ADJUST_COORDINATE_SPACE).
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0)
            .depth_bias_enable(bias_on)
            .depth_bias_constant_factor(bias_constant)
            .depth_bias_slope_factor(bias_slope);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(desc.samples);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS);
        let blend_attachments = [vk::PipelineColorBlendAttachmentState::default().color_write_mask(
            if desc.color == Some(vk::Format::R32_UINT) {
                vk::ColorComponentFlags::R
            } else {
                vk::ColorComponentFlags::RGBA
            },
        )];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(if desc.color.is_some() {
            &blend_attachments[..]
        } else {
            &[]
        });
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let color_formats: Vec<vk::Format> = desc.color.into_iter().collect();
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&color_formats)
            .depth_attachment_format(desc.depth);
        // SAFETY: valid device; every create info lives across its call; the module is
        // destroyed once the pipeline exists (or failed), the pipeline in Drop.
        unsafe {
            let module = d
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
                .map_err(vk_err("creating a shader module"))?;
            for st in &mut stages {
                *st = st.module(module);
            }
            let info = [vk::GraphicsPipelineCreateInfo::default()
                .stages(&stages)
                .vertex_input_state(&vertex_input)
                .input_assembly_state(&input_assembly)
                .viewport_state(&viewport)
                .rasterization_state(&raster)
                .multisample_state(&multisample)
                .depth_stencil_state(&depth)
                .color_blend_state(&blend)
                .dynamic_state(&dynamic)
                .layout(layout.layout)
                .push_next(&mut rendering)];
            let pipeline = d.create_graphics_pipelines(vk::PipelineCache::null(), &info, None);
            d.destroy_shader_module(module, None);
            let pipeline = pipeline.map_err(|(_, e)| vk_err("creating a graphics pipeline")(e))?[0];
            Ok(Self { dev: dev.clone(), pipeline, layout: layout.layout })
        }
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        let pipeline = self.pipeline;
        // SAFETY: retire runs this once the device is idle.
        self.dev.retire(|d| unsafe { d.destroy_pipeline(pipeline, None) });
    }
}

/// One descriptor of a set.
pub enum Binding<'a> {
    /// A whole buffer.
    Buffer(u32, vk::DescriptorType, &'a Buffer),
    /// A sampled image in SHADER_READ_ONLY_OPTIMAL.
    Image(u32, &'a Image),
    /// A sampler.
    Sampler(u32, &'a Sampler),
}

impl Sets {
    /// A set of layout `layout` with `bindings` written.
    pub fn allocate_with(&self, layout: vk::DescriptorSetLayout, bindings: &[Binding<'_>]) -> Result<Set, VkError> {
        let layouts = [layout];
        let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.pool).set_layouts(&layouts);
        // SAFETY: pool and layout belong to this device; the set lives as long as the pool.
        let set = unsafe { self.dev.device.allocate_descriptor_sets(&info) }
            .map_err(vk_err("allocating a descriptor set"))?[0];
        let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .iter()
            .map(|b| match b {
                Binding::Buffer(_, _, buf) => [vk::DescriptorBufferInfo::default().buffer(buf.buffer).range(buf.size)],
                _ => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let images: Vec<[vk::DescriptorImageInfo; 1]> = bindings
            .iter()
            .map(|b| match b {
                Binding::Image(_, img) => [vk::DescriptorImageInfo::default()
                    .image_view(img.view)
                    .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)],
                Binding::Sampler(_, s) => [vk::DescriptorImageInfo::default().sampler(s.sampler)],
                Binding::Buffer(..) => [vk::DescriptorImageInfo::default()],
            })
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = bindings
            .iter()
            .enumerate()
            .map(|(k, b)| {
                let w = vk::WriteDescriptorSet::default().dst_set(set);
                match b {
                    Binding::Buffer(binding, ty, _) => {
                        w.dst_binding(*binding).descriptor_type(*ty).buffer_info(&buffers[k])
                    }
                    Binding::Image(binding, _) => w
                        .dst_binding(*binding)
                        .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                        .image_info(&images[k]),
                    Binding::Sampler(binding, _) => {
                        w.dst_binding(*binding).descriptor_type(vk::DescriptorType::SAMPLER).image_info(&images[k])
                    }
                }
            })
            .collect();
        // SAFETY: the writes reference live objects and the set just allocated.
        unsafe { self.dev.device.update_descriptor_sets(&writes, &[]) };
        let mut alive = vec![self.alive.clone()];
        alive.extend(bindings.iter().map(|b| match b {
            Binding::Buffer(_, _, buf) => buf.alive.clone(),
            Binding::Image(_, img) => img.alive.clone(),
            Binding::Sampler(_, s) => s.alive.clone(),
        }));
        Ok(Set { set, layout, alive })
    }
}

/// An image layout transition with the stages and accesses on each side.
pub struct Transition {
    /// Layout before (UNDEFINED discards the contents).
    pub old: vk::ImageLayout,
    /// Layout after.
    pub new: vk::ImageLayout,
    /// Stages that must finish first.
    pub src_stage: vk::PipelineStageFlags,
    /// Their writes to make available.
    pub src_access: vk::AccessFlags,
    /// Stages that wait.
    pub dst_stage: vk::PipelineStageFlags,
    /// Their accesses that see the result.
    pub dst_access: vk::AccessFlags,
}

impl Transition {
    /// A depth attachment to be cleared and tested (its old contents discarded).
    pub fn fresh_depth() -> Self {
        let tests = vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        Transition {
            old: vk::ImageLayout::UNDEFINED,
            new: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            src_stage: tests,
            src_access: vk::AccessFlags::empty(),
            dst_stage: tests,
            dst_access: vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
                | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
        }
    }

    /// A colour attachment just written, to be copied out.
    pub fn color_to_transfer_src() -> Self {
        Transition {
            old: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            new: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            src_stage: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            src_access: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            dst_stage: vk::PipelineStageFlags::TRANSFER,
            dst_access: vk::AccessFlags::TRANSFER_READ,
        }
    }
}

impl Commands {
    /// Records a layout transition of `image`.
    pub fn transition(&self, image: &Image, t: Transition) {
        self.transition_handle(image.image, image.aspect, t);
    }

    /// Records a layout transition of the image `image` (ours or a swapchain's).
    pub(crate) fn transition_handle(&self, image: vk::Image, aspect: vk::ImageAspectFlags, t: Transition) {
        let b = [vk::ImageMemoryBarrier::default()
            .old_layout(t.old)
            .new_layout(t.new)
            .src_access_mask(t.src_access)
            .dst_access_mask(t.dst_access)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image)
            .subresource_range(range(aspect))];
        // SAFETY: recording state; the image is live (ours, or a live swapchain's).
        unsafe {
            self.dev.device.cmd_pipeline_barrier(
                self.cmd(),
                t.src_stage,
                t.dst_stage,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &b,
            )
        };
    }

    /// A global memory barrier.
    pub fn memory_barrier(
        &self,
        src_stage: vk::PipelineStageFlags,
        src_access: vk::AccessFlags,
        dst_stage: vk::PipelineStageFlags,
        dst_access: vk::AccessFlags,
    ) {
        let mb = [vk::MemoryBarrier::default().src_access_mask(src_access).dst_access_mask(dst_access)];
        // SAFETY: recording state.
        unsafe {
            self.dev.device.cmd_pipeline_barrier(
                self.cmd(),
                src_stage,
                dst_stage,
                vk::DependencyFlags::empty(),
                &mb,
                &[],
                &[],
            )
        };
    }

    /// Begins dynamic rendering over `depth`'s extent into `color` (cleared to
    /// `clear`, resolved into `resolve` when given) and `depth` (cleared to 1); sets the
    /// viewport and scissor to the whole target. Attachments must be in the attachment
    /// layouts.
    pub fn begin_rendering(&self, color: Option<(&Image, Option<&Image>, vk::ClearColorValue)>, depth: &Image) {
        let extent = vk::Extent2D { width: depth.width, height: depth.height };
        let color_att: Vec<vk::RenderingAttachmentInfo> = color
            .iter()
            .map(|(img, resolve, clear)| {
                let a = vk::RenderingAttachmentInfo::default()
                    .image_view(img.view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .clear_value(vk::ClearValue { color: *clear });
                match resolve {
                    Some(r) => a
                        .store_op(vk::AttachmentStoreOp::DONT_CARE)
                        .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                        .resolve_image_view(r.view)
                        .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL),
                    None => a.store_op(vk::AttachmentStoreOp::STORE),
                }
            })
            .collect();
        let depth_att = vk::RenderingAttachmentInfo::default()
            .image_view(depth.view)
            .image_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(if color.is_some() { vk::AttachmentStoreOp::DONT_CARE } else { vk::AttachmentStoreOp::STORE })
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&color_att)
            .depth_attachment(&depth_att);
        let d = &self.dev.device;
        // SAFETY: recording state, outside any rendering; dynamic rendering is enabled on
        // this device (the renderer checks); the views are live.
        unsafe {
            d.cmd_begin_rendering(self.cmd(), &info);
            d.cmd_set_viewport(
                self.cmd(),
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: extent.width as f32,
                    height: extent.height as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(self.cmd(), 0, &[vk::Rect2D { offset: vk::Offset2D::default(), extent }]);
        }
    }

    /// Ends dynamic rendering.
    pub fn end_rendering(&self) {
        // SAFETY: recording state, inside rendering begun by `begin_rendering`.
        unsafe { self.dev.device.cmd_end_rendering(self.cmd()) };
    }

    /// Binds a graphics pipeline and its descriptor sets from set 0.
    pub fn bind_graphics(&self, pipeline: &GraphicsPipeline, sets: &[&Set]) {
        if sets.iter().any(|s| !s.valid()) {
            self.poison("a descriptor set whose buffer, image or pool was dropped");
            return;
        }
        let sets: Vec<vk::DescriptorSet> = sets.iter().map(|s| s.set).collect();
        let sets = &sets[..];
        let d = &self.dev.device;
        // SAFETY: recording state; pipeline and sets are live and compatible.
        unsafe {
            d.cmd_bind_pipeline(self.cmd(), vk::PipelineBindPoint::GRAPHICS, pipeline.pipeline);
            if !sets.is_empty() {
                d.cmd_bind_descriptor_sets(self.cmd(), vk::PipelineBindPoint::GRAPHICS, pipeline.layout, 0, sets, &[]);
            }
        }
    }

    /// Binds `buffers` as vertex buffers 0, 1, … and `index` (u32) when given.
    pub fn bind_vertices(&self, buffers: &[&Buffer], index: Option<&Buffer>) {
        let handles: Vec<vk::Buffer> = buffers.iter().map(|b| b.buffer).collect();
        let offsets = vec![0u64; handles.len()];
        let d = &self.dev.device;
        // SAFETY: recording state; the buffers are live with VERTEX / INDEX usage.
        unsafe {
            d.cmd_bind_vertex_buffers(self.cmd(), 0, &handles, &offsets);
            if let Some(ib) = index {
                d.cmd_bind_index_buffer(self.cmd(), ib.buffer, 0, vk::IndexType::UINT32);
            }
        }
    }

    /// Draws `count` indices (indexed) or `count` vertices.
    pub fn draw(&self, count: u32, indexed: bool) {
        let d = &self.dev.device;
        // SAFETY: recording state inside rendering, with a pipeline and buffers bound that
        // hold `count` indices or vertices (the renderer sizes them).
        unsafe {
            if indexed {
                d.cmd_draw_indexed(self.cmd(), count, 1, 0, 0, 0);
            } else {
                d.cmd_draw(self.cmd(), count, 1, 0, 0);
            }
        }
    }

    /// Copies the `w × h` texels at `(x, y)` of `image` (in TRANSFER_SRC_OPTIMAL) into
    /// `dst`, tightly packed.
    pub fn copy_image_to_buffer(&self, image: &Image, x: u32, y: u32, w: u32, h: u32, dst: &Buffer) {
        let region = [vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(image.aspect).layer_count(1))
            .image_offset(vk::Offset3D { x: x as i32, y: y as i32, z: 0 })
            .image_extent(vk::Extent3D { width: w, height: h, depth: 1 })];
        // SAFETY: recording state; the region lies within the image and `dst` is large
        // enough (the renderer checks both).
        unsafe {
            self.dev.device.cmd_copy_image_to_buffer(
                self.cmd(),
                image.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.buffer,
                &region,
            )
        };
    }
}
