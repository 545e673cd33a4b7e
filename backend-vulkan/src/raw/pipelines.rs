//! Compute pipelines and the descriptor sets that bind buffers and images to them.

use std::sync::Arc;

use ash::vk;

use super::device::Alive;
use super::{Buffer, Device, Image, vk_err};
use crate::VkError;

/// A compute pipeline with its descriptor-set layout and pipeline layout.
pub struct Kernel {
    pub(super) dev: Arc<Device>,
    pub(super) set_layout: vk::DescriptorSetLayout,
    /// The pipeline layout (for binding sets and pushing constants).
    pub layout: vk::PipelineLayout,
    /// The pipeline.
    pub pipeline: vk::Pipeline,
}

impl Kernel {
    /// A pipeline for the SPIR-V `spirv` (entry `main`) with descriptor set 0 holding
    /// `bindings` and `push_size` bytes of push constants.
    pub fn new(
        dev: &Arc<Device>,
        spirv: &[u8],
        bindings: &[(u32, vk::DescriptorType)],
        push_size: u32,
    ) -> Result<Self, VkError> {
        if !spirv.len().is_multiple_of(4) {
            return Err(VkError::Vulkan { what: "loading SPIR-V", reason: "length not a multiple of 4".into() });
        }
        let words: Vec<u32> = spirv.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let d = &dev.device;
        let b: Vec<vk::DescriptorSetLayoutBinding> = bindings
            .iter()
            .map(|&(binding, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY: valid device, create infos live across each call; each object is
        // destroyed in Drop (or below, on failure) before the device.
        unsafe {
            let set_layout = d
                .create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(&b), None)
                .map_err(vk_err("creating a set layout"))?;
            let ranges =
                [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).offset(0).size(push_size)];
            let set_layouts = [set_layout];
            let mut pl_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            if push_size > 0 {
                pl_info = pl_info.push_constant_ranges(&ranges);
            }
            let layout = match d.create_pipeline_layout(&pl_info, None) {
                Ok(l) => l,
                Err(e) => {
                    d.destroy_descriptor_set_layout(set_layout, None);
                    return Err(vk_err("creating a pipeline layout")(e));
                }
            };
            let module = match d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) {
                Ok(m) => m,
                Err(e) => {
                    d.destroy_pipeline_layout(layout, None);
                    d.destroy_descriptor_set_layout(set_layout, None);
                    return Err(vk_err("creating a shader module")(e));
                }
            };
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(c"main");
            let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
            let pipeline = d.create_compute_pipelines(vk::PipelineCache::null(), &info, None);
            d.destroy_shader_module(module, None);
            let pipeline = match pipeline {
                Ok(p) => p[0],
                Err((_, e)) => {
                    d.destroy_pipeline_layout(layout, None);
                    d.destroy_descriptor_set_layout(set_layout, None);
                    return Err(vk_err("creating a compute pipeline")(e));
                }
            };
            Ok(Self { dev: dev.clone(), set_layout, layout, pipeline })
        }
    }
}

impl Drop for Kernel {
    fn drop(&mut self) {
        let (pipeline, layout, set_layout) = (self.pipeline, self.layout, self.set_layout);
        // SAFETY: retire runs this once the device is idle; reverse creation order.
        self.dev.retire(|d| unsafe {
            d.destroy_pipeline(pipeline, None);
            d.destroy_pipeline_layout(layout, None);
            d.destroy_descriptor_set_layout(set_layout, None);
        });
    }
}

/// A descriptor pool with one set per (kernel, buffer assignment).
pub struct Sets {
    pub(super) dev: Arc<Device>,
    pub(super) pool: vk::DescriptorPool,
    pub(super) alive: Alive,
}

impl Sets {
    /// A pool for `max_sets` sets of at most 32 descriptors each.
    pub fn new(dev: &Arc<Device>, max_sets: u32) -> Result<Self, VkError> {
        let sizes = [
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::STORAGE_BUFFER).descriptor_count(32 * max_sets),
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::UNIFORM_BUFFER).descriptor_count(8 * max_sets),
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::SAMPLED_IMAGE).descriptor_count(2 * max_sets),
            vk::DescriptorPoolSize::default().ty(vk::DescriptorType::SAMPLER).descriptor_count(2 * max_sets),
        ];
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(max_sets).pool_sizes(&sizes);
        // SAFETY: valid device and create info; destroyed in Drop.
        let pool =
            unsafe { dev.device.create_descriptor_pool(&info, None) }.map_err(vk_err("creating a descriptor pool"))?;
        Ok(Self { dev: dev.clone(), pool, alive: Alive::new() })
    }

    /// A set for `kernel` with `buffers[k]` (binding, type, buffer) bound whole,
    /// `images` (binding, image) as sampled images and `sampler` (binding, sampler).
    pub fn allocate(
        &self,
        kernel: &Kernel,
        buffers: &[(u32, vk::DescriptorType, &Buffer)],
        images: &[(u32, &Image)],
        sampler: Option<(u32, &super::Sampler)>,
    ) -> Result<Set, VkError> {
        let layouts = [kernel.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.pool).set_layouts(&layouts);
        // SAFETY: pool and layout belong to this device; the set lives as long as the pool.
        let set = unsafe { self.dev.device.allocate_descriptor_sets(&info) }
            .map_err(vk_err("allocating a descriptor set"))?[0];
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|(_, _, b)| [vk::DescriptorBufferInfo::default().buffer(b.buffer).offset(0).range(b.size)])
            .collect();
        let writes: Vec<vk::WriteDescriptorSet> = buffers
            .iter()
            .zip(&infos)
            .map(|((binding, ty, _), info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(*binding)
                    .descriptor_type(*ty)
                    .buffer_info(info)
            })
            .collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = images
            .iter()
            .map(|(_, img)| {
                [vk::DescriptorImageInfo::default()
                    .image_view(img.view)
                    .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
            })
            .collect();
        let sampler_info = sampler.map(|(_, s)| [vk::DescriptorImageInfo::default().sampler(s.sampler)]);
        let mut writes = writes;
        for ((binding, _), info) in images.iter().zip(&image_infos) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(*binding)
                    .descriptor_type(vk::DescriptorType::SAMPLED_IMAGE)
                    .image_info(info),
            );
        }
        if let (Some((binding, _)), Some(info)) = (sampler, &sampler_info) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(vk::DescriptorType::SAMPLER)
                    .image_info(info),
            );
        }
        // SAFETY: the writes reference live buffers and the set just allocated.
        unsafe { self.dev.device.update_descriptor_sets(&writes, &[]) };
        let mut alive = vec![self.alive.clone()];
        alive.extend(buffers.iter().map(|(_, _, b)| b.alive.clone()));
        alive.extend(images.iter().map(|(_, i)| i.alive.clone()));
        alive.extend(sampler.map(|(_, s)| s.alive.clone()));
        Ok(Set { set, layout: kernel.set_layout, alive })
    }
}

impl Drop for Sets {
    fn drop(&mut self) {
        self.alive.end();
        let pool = self.pool;
        // SAFETY: retire runs this once the device is idle; the sets it freed are refused
        // when bound (their `alive` says the pool is gone).
        self.dev.retire(|d| unsafe { d.destroy_descriptor_pool(pool, None) });
    }
}

/// A descriptor set from a [`Sets`] pool: refused when bound once its pool or anything it
/// points at was dropped, or with a pipeline of another set layout.
#[derive(Debug, Clone)]
pub struct Set {
    pub(super) set: vk::DescriptorSet,
    pub(super) layout: vk::DescriptorSetLayout,
    pub(super) alive: Vec<Alive>,
}

impl Set {
    /// Whether its pool and every object it points at are still alive.
    pub(super) fn valid(&self) -> bool {
        self.alive.iter().all(Alive::get)
    }
}
