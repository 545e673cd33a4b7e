//! The scene renderer on raw Vulkan: the same passes, shaders (render.wgsl as SPIR-V) and
//! look as the wgpu renderer — a shadow pass from the light, a lit main pass with 4× MSAA
//! into an sRGB target, the cloth as triangles, lines or points, and a picking pass —
//! drawing the cloth straight from the Vulkan solver's position and normal buffers.

use std::sync::Arc;

use ash::vk;
use clothlab_core::grid::{ClothState, ClothTopology};
use clothlab_core::render::{Frame, SAMPLES, SHADOW_SIZE, SKY, StaticVertex, cloth_lines, fabric_texture, static_mesh};
use clothlab_core::scene::Scene;
use clothlab_core::solver::{RenderError, RenderMode, View};
use gpu_allocator::MemoryLocation;

use crate::VkError;
use crate::raw::{
    Binding, Buffer, Commands, Device, GraphicsPipeline, Image, ImageDesc, PipelineDesc, PipelineLayout, Sampler, Set,
    Sets, Transition, VertexBinding,
};
use crate::solver::upload;

const COLOR_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
const PICK_FORMAT: vk::Format = vk::Format::R32_UINT;
/// Frames that may be in flight at once (each has its own constants and CPU vertices).
pub const FRAMES_IN_FLIGHT: usize = 2;

/// Where the cloth's positions and normals come from.
pub enum VkCloth<'a> {
    /// The Vulkan solver's own buffers (`[f32; 4]` per particle each): drawn with no copy.
    Gpu {
        /// Positions.
        pos: &'a Buffer,
        /// Normals.
        normal: &'a Buffer,
    },
    /// A CPU solver's state: uploaded once per frame.
    Cpu(&'a ClothState),
}

struct Targets {
    msaa: Image,
    resolve: Image,
    depth: Image,
    pick: Image,
    pick_depth: Image,
    /// Host-readable copy of the resolved image.
    readback: Buffer,
}

fn rerr(e: VkError) -> RenderError {
    RenderError::Backend(e.to_string())
}

fn check_size(dev: &Device, width: u32, height: u32) -> Result<(), RenderError> {
    let max = dev.max_image_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::InvalidSize { width, height, reason: format!("each side must be in 1 ..= {max}") });
    }
    Ok(())
}

fn make_targets(dev: &Arc<Device>, width: u32, height: u32) -> Result<Targets, VkError> {
    use vk::ImageUsageFlags as U;
    let img =
        |name, format, usage, samples| Image::with_desc(dev, name, ImageDesc { width, height, format, usage, samples });
    let one = vk::SampleCountFlags::TYPE_1;
    let msaa = vk::SampleCountFlags::from_raw(SAMPLES);
    Ok(Targets {
        msaa: img("color (msaa)", COLOR_FORMAT, U::COLOR_ATTACHMENT | U::TRANSIENT_ATTACHMENT, msaa)?,
        resolve: img("color", COLOR_FORMAT, U::COLOR_ATTACHMENT | U::TRANSFER_SRC, one)?,
        depth: img("depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT | U::TRANSIENT_ATTACHMENT, msaa)?,
        pick: img("pick ids", PICK_FORMAT, U::COLOR_ATTACHMENT | U::TRANSFER_SRC, one)?,
        pick_depth: img("pick depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT, one)?,
        readback: Buffer::new(
            dev,
            "image readback",
            width as u64 * height as u64 * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?,
    })
}

struct Slot {
    frame: Buffer,
    frame_set: Set,
    cpu_pos: Buffer,
    cpu_normal: Buffer,
    /// The floor and colliders where they are in this slot's frame, host visible (drawn
    /// once `set_colliders` moved them; the device-local `static_vb` until then).
    statics: Buffer,
}

struct Pipelines {
    lit_static: GraphicsPipeline,
    lit_cloth: GraphicsPipeline,
    lines_cloth: GraphicsPipeline,
    points_cloth: GraphicsPipeline,
    shadow_static: GraphicsPipeline,
    shadow_cloth: GraphicsPipeline,
    pick_static: GraphicsPipeline,
    pick_cloth: GraphicsPipeline,
}

fn make_pipelines(dev: &Arc<Device>, main: &PipelineLayout, shadow: &PipelineLayout) -> Result<Pipelines, VkError> {
    use vk::Format as F;
    let spirv = clothlab_shaders::kernel("render")
        .ok_or(VkError::Vulkan { what: "loading the render shader", reason: "missing from clothlab-shaders".into() })?
        .spirv;
    let stat = VertexBinding {
        stride: std::mem::size_of::<StaticVertex>() as u32,
        attributes: vec![
            (0, F::R32G32B32_SFLOAT, 0),
            (1, F::R32G32B32_SFLOAT, 12),
            (2, F::R32G32_SFLOAT, 24),
            (3, F::R32_UINT, 32),
        ],
    };
    let stat_pos = VertexBinding { stride: stat.stride, attributes: vec![(0, F::R32G32B32_SFLOAT, 0)] };
    let v4 = |loc| VertexBinding { stride: 16, attributes: vec![(loc, F::R32G32B32A32_SFLOAT, 0)] };
    let uv = VertexBinding { stride: 8, attributes: vec![(2, F::R32G32_SFLOAT, 0)] };
    let cloth = vec![v4(0), v4(1), uv];
    let four = vk::SampleCountFlags::from_raw(SAMPLES);
    let one = vk::SampleCountFlags::TYPE_1;
    use vk::PrimitiveTopology as T;
    let lit = |vs, fs, bindings, topology| PipelineDesc {
        vs,
        fs: Some(fs),
        bindings,
        topology,
        samples: four,
        color: Some(COLOR_FORMAT),
        depth: DEPTH_FORMAT,
        depth_bias: None,
    };
    let depth_only = |vs, bindings| PipelineDesc {
        vs,
        fs: None,
        bindings,
        topology: T::TRIANGLE_LIST,
        samples: one,
        color: None,
        depth: DEPTH_FORMAT,
        depth_bias: Some((2.0, 2.0)),
    };
    let pick = |vs, bindings| PipelineDesc {
        vs,
        fs: Some(c"fs_pick"),
        bindings,
        topology: T::TRIANGLE_LIST,
        samples: one,
        color: Some(PICK_FORMAT),
        depth: DEPTH_FORMAT,
        depth_bias: None,
    };
    let p = |layout, desc: PipelineDesc<'_>| GraphicsPipeline::new(dev, layout, spirv, &desc);
    Ok(Pipelines {
        lit_static: p(main, lit(c"vs_static", c"fs_lit", vec![stat], T::TRIANGLE_LIST))?,
        lit_cloth: p(main, lit(c"vs_cloth", c"fs_lit", cloth.clone(), T::TRIANGLE_LIST))?,
        lines_cloth: p(main, lit(c"vs_cloth", c"fs_flat", cloth.clone(), T::LINE_LIST))?,
        points_cloth: p(main, lit(c"vs_cloth", c"fs_flat", cloth.clone(), T::POINT_LIST))?,
        shadow_static: p(shadow, depth_only(c"vs_shadow_static", vec![stat_pos.clone()]))?,
        shadow_cloth: p(shadow, depth_only(c"vs_shadow_cloth", vec![v4(0)]))?,
        pick_static: p(shadow, pick(c"vs_pick_static", vec![stat_pos]))?,
        pick_cloth: p(shadow, pick(c"vs_pick_cloth", vec![v4(0)]))?,
    })
}

/// Offscreen renderer of one scene and its cloth on raw Vulkan.
pub struct VulkanRenderer {
    width: u32,
    height: u32,
    targets: Targets,
    pipelines: Pipelines,
    /// Per frame slot: the constants, their set, and the CPU solvers' vertices.
    slots: Vec<Slot>,
    texture_set: Set,
    static_vb: Buffer,
    static_ib: Buffer,
    static_count: u32,
    /// The colliders `set_colliders` moved to, written into each slot's `statics` by
    /// `prepare`.
    moved: Option<Vec<StaticVertex>>,
    uv: Buffer,
    tri_ib: Buffer,
    tri_count: u32,
    line_ib: Buffer,
    line_count: u32,
    num_particles: u32,
    pick_buf: Buffer,
    // Dropped after everything that refers to them.
    _sets: Sets,
    _main_layout: PipelineLayout,
    _shadow_layout: PipelineLayout,
    shadow: Image,
    _fabric: Image,
    _shadow_sampler: Sampler,
    _fabric_sampler: Sampler,
    cmds: Commands,
    dev: Arc<Device>,
}

impl VulkanRenderer {
    /// A renderer of `scene` with its cloth `topo` on `dev`, drawing `width × height`.
    pub fn new(
        dev: &crate::Device,
        scene: &Scene,
        topo: &ClothTopology,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        let dev = dev.raw();
        if !dev.dynamic_rendering {
            return Err(RenderError::Backend(format!(
                "{} cannot draw with dynamic rendering (Vulkan 1.3 with a graphics queue): use the wgpu renderer",
                dev.name
            )));
        }
        check_size(dev, width, height)?;
        Self::build(dev, scene, topo, width, height).map_err(rerr)
    }

    fn build(dev: &Arc<Device>, scene: &Scene, topo: &ClothTopology, width: u32, height: u32) -> Result<Self, VkError> {
        use vk::BufferUsageFlags as B;
        use vk::DescriptorType as D;
        use vk::ShaderStageFlags as S;
        let targets = make_targets(dev, width, height)?;
        let frame_bindings = [(0, D::UNIFORM_BUFFER, S::VERTEX | S::FRAGMENT)];
        let texture_bindings = [
            (0, D::SAMPLED_IMAGE, S::FRAGMENT),
            (1, D::SAMPLER, S::FRAGMENT),
            (2, D::SAMPLED_IMAGE, S::FRAGMENT),
            (3, D::SAMPLER, S::FRAGMENT),
        ];
        let main_layout = PipelineLayout::new(dev, &[&frame_bindings, &texture_bindings])?;
        let shadow_layout = PipelineLayout::new(dev, &[&frame_bindings])?;
        let pipelines = make_pipelines(dev, &main_layout, &shadow_layout)?;

        let shadow = Image::with_desc(
            dev,
            "shadow map",
            ImageDesc {
                width: SHADOW_SIZE,
                height: SHADOW_SIZE,
                format: DEPTH_FORMAT,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
                samples: vk::SampleCountFlags::TYPE_1,
            },
        )?;
        let fabric = Image::with_desc(
            dev,
            "fabric",
            ImageDesc {
                width: 64,
                height: 64,
                format: vk::Format::R8G8B8A8_SRGB,
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                samples: vk::SampleCountFlags::TYPE_1,
            },
        )?;
        let shadow_sampler = Sampler::new(dev, true)?;
        let fabric_sampler = Sampler::new(dev, false)?;
        let sets = Sets::new(dev, 1 + FRAMES_IN_FLIGHT as u32)?;
        let np = topo.num_particles() as u64;
        let host_vertices = |name| Buffer::new(dev, name, np * 16, B::VERTEX_BUFFER, MemoryLocation::CpuToGpu);
        let (sv, si) = static_mesh(scene);
        let sv_bytes: &[u8] = bytemuck::cast_slice(&sv);
        let mut slots = Vec::new();
        for _ in 0..FRAMES_IN_FLIGHT {
            let mut statics =
                Buffer::new(dev, "moved statics", sv_bytes.len() as u64, B::VERTEX_BUFFER, MemoryLocation::CpuToGpu)?;
            statics
                .mapped()
                .ok_or(VkError::Vulkan { what: "mapping the statics", reason: "not host visible".into() })?
                .copy_from_slice(sv_bytes);
            let size = std::mem::size_of::<Frame>() as u64;
            let frame = Buffer::new(dev, "frame", size, B::UNIFORM_BUFFER, MemoryLocation::CpuToGpu)?;
            let frame_set =
                sets.allocate_with(main_layout.sets[0], &[Binding::Buffer(0, D::UNIFORM_BUFFER, &frame)])?;
            slots.push(Slot {
                frame,
                frame_set,
                cpu_pos: host_vertices("cpu positions")?,
                cpu_normal: host_vertices("cpu normals")?,
                statics,
            });
        }
        let texture_set = sets.allocate_with(
            main_layout.sets[1],
            &[
                Binding::Image(0, &shadow),
                Binding::Sampler(1, &shadow_sampler),
                Binding::Image(2, &fabric),
                Binding::Sampler(3, &fabric_sampler),
            ],
        )?;

        // Static data, device-local through one staging buffer.
        let tri: Vec<u32> = topo.triangles.iter().flatten().copied().collect();
        let lines = cloth_lines(topo);
        let texels = fabric_texture();
        let uv = topo.render_uvs();
        let contents: [(&str, &[u8], B); 5] = [
            ("static vertices", bytemuck::cast_slice(&sv), B::VERTEX_BUFFER),
            ("static indices", bytemuck::cast_slice(&si), B::INDEX_BUFFER),
            ("cloth uv", bytemuck::cast_slice(&uv), B::VERTEX_BUFFER),
            ("cloth triangles", bytemuck::cast_slice(&tri), B::INDEX_BUFFER),
            ("cloth lines", bytemuck::cast_slice(&lines), B::INDEX_BUFFER),
        ];
        let largest = contents.iter().map(|c| c.1.len()).max().unwrap_or(0).max(texels.len()) as u64;
        let mut staging = Buffer::new(dev, "render staging", largest, B::TRANSFER_SRC, MemoryLocation::CpuToGpu)?;
        let mut cmds = Commands::new(dev, 0)?;
        let mut made = Vec::new();
        for (name, bytes, usage) in contents {
            let b = Buffer::new(dev, name, bytes.len() as u64, usage | B::TRANSFER_DST, MemoryLocation::GpuOnly)?;
            upload(&mut cmds, &mut staging, &b, bytes)?;
            made.push(b);
        }
        let map = staging
            .mapped()
            .ok_or(VkError::Vulkan { what: "mapping the staging buffer", reason: "not host visible".into() })?;
        map[..texels.len()].copy_from_slice(&texels);
        cmds.begin(0)?;
        cmds.copy_to_image(&staging, &fabric);
        // The shadow map starts readable, so that every frame transitions it the same way.
        cmds.transition(
            &shadow,
            Transition {
                old: vk::ImageLayout::UNDEFINED,
                new: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                src_stage: vk::PipelineStageFlags::TOP_OF_PIPE,
                src_access: vk::AccessFlags::empty(),
                dst_stage: vk::PipelineStageFlags::FRAGMENT_SHADER,
                dst_access: vk::AccessFlags::SHADER_READ,
            },
        );
        cmds.submit_and_wait(0)?;
        drop(staging);
        let mut it = made.into_iter();
        let mut next = || it.next().expect("one buffer per entry");
        let r = Self {
            width,
            height,
            targets,
            pipelines,
            slots,
            texture_set,
            static_vb: next(),
            static_ib: next(),
            static_count: si.len() as u32,
            moved: None,
            uv: next(),
            tri_ib: next(),
            tri_count: tri.len() as u32,
            line_ib: next(),
            line_count: lines.len() as u32,
            num_particles: np as u32,
            pick_buf: Buffer::new(dev, "pick pixel", 4, B::TRANSFER_DST, MemoryLocation::GpuToCpu)?,
            _sets: sets,
            _main_layout: main_layout,
            _shadow_layout: shadow_layout,
            shadow,
            _fabric: fabric,
            _shadow_sampler: shadow_sampler,
            _fabric_sampler: fabric_sampler,
            cmds,
            dev: dev.clone(),
        };
        r.check()?;
        Ok(r)
    }

    fn check(&self) -> Result<(), VkError> {
        let m = self.dev.take_messages();
        if m.is_empty() { Ok(()) } else { Err(VkError::Validation(m.join(" | "))) }
    }

    /// Target size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Changes the target size; a zero or too large side is refused and nothing changes.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        check_size(&self.dev, width, height)?;
        self.targets = make_targets(&self.dev, width, height).map_err(rerr)?;
        self.width = width;
        self.height = height;
        Ok(())
    }

    /// Writes the constants of `view` into frame slot `slot`, checks `cloth` against the
    /// grid, and writes a CPU state to the slot's host-visible vertex buffers. The slot's
    /// previous frame must have completed.
    pub fn prepare(&mut self, slot: usize, view: &View, cloth: &VkCloth<'_>) -> Result<(), RenderError> {
        let need = self.num_particles as u64 * 16;
        let f = Frame::new(view, self.width, self.height);
        let s = &mut self.slots[slot % FRAMES_IN_FLIGHT];
        s.frame
            .mapped()
            .ok_or_else(|| RenderError::Backend("frame buffer not host visible".into()))?
            .copy_from_slice(bytemuck::bytes_of(&f));
        if let Some(sv) = &self.moved {
            s.statics
                .mapped()
                .ok_or_else(|| RenderError::Backend("statics not host visible".into()))?
                .copy_from_slice(bytemuck::cast_slice(sv));
        }
        match cloth {
            VkCloth::Gpu { pos, normal } => {
                if pos.size < need || normal.size < need {
                    return Err(RenderError::Backend("cloth buffers of another grid size".into()));
                }
            }
            VkCloth::Cpu(state) => {
                if state.pos.len() != self.num_particles as usize || state.normal.len() != state.pos.len() {
                    return Err(RenderError::Backend("state of another grid size".into()));
                }
                for (buf, data) in [(&mut s.cpu_pos, &state.pos), (&mut s.cpu_normal, &state.normal)] {
                    let bytes: &[u8] = bytemuck::cast_slice(data);
                    buf.mapped().ok_or_else(|| RenderError::Backend("vertex buffer not host visible".into()))?
                        [..bytes.len()]
                        .copy_from_slice(bytes);
                }
            }
        }
        Ok(())
    }

    /// Draws the colliders of `scene` from the next [`VulkanRenderer::prepare`] on (moving
    /// colliders: `Scene::moved_to`); the same shapes as the renderer was made with, else
    /// refused.
    pub fn set_colliders(&mut self, scene: &Scene) -> Result<(), RenderError> {
        let (sv, _) = static_mesh(scene);
        if std::mem::size_of_val(sv.as_slice()) as u64 != self.slots[0].statics.size {
            return Err(RenderError::Backend("set_colliders: the scene's colliders are not the renderer's".into()));
        }
        self.moved = Some(sv);
        Ok(())
    }

    /// The floor and colliders' vertices drawn in slot `slot`.
    fn statics(&self, slot: usize) -> &Buffer {
        if self.moved.is_some() { &self.slots[slot % FRAMES_IN_FLIGHT].statics } else { &self.static_vb }
    }

    /// The position and normal buffers `cloth` is drawn from in slot `slot`.
    fn cloth_buffers<'a>(&'a self, slot: usize, cloth: &VkCloth<'a>) -> (&'a Buffer, &'a Buffer) {
        match cloth {
            VkCloth::Gpu { pos, normal } => (pos, normal),
            VkCloth::Cpu(_) => {
                let s = &self.slots[slot % FRAMES_IN_FLIGHT];
                (&s.cpu_pos, &s.cpu_normal)
            }
        }
    }

    /// Records the barrier that makes the solver's compute writes (and host writes)
    /// visible to vertex input and uniform reads; first in every drawing command buffer.
    pub fn record_inputs_barrier(cmds: &Commands) {
        cmds.memory_barrier(
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::HOST,
            vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE | vk::AccessFlags::HOST_WRITE,
            vk::PipelineStageFlags::VERTEX_INPUT
                | vk::PipelineStageFlags::VERTEX_SHADER
                | vk::PipelineStageFlags::FRAGMENT_SHADER,
            vk::AccessFlags::VERTEX_ATTRIBUTE_READ | vk::AccessFlags::INDEX_READ | vk::AccessFlags::UNIFORM_READ,
        );
    }

    fn begin(cmds: &mut Commands) -> Result<(), VkError> {
        cmds.begin(0)?;
        Self::record_inputs_barrier(cmds);
        Ok(())
    }

    /// Floor, colliders and cloth triangles: the shadow and picking passes.
    fn draw_geometry(
        &self,
        c: &Commands,
        slot: usize,
        stat: &GraphicsPipeline,
        cloth: &GraphicsPipeline,
        pos: &Buffer,
    ) {
        let frame_set = &self.slots[slot % FRAMES_IN_FLIGHT].frame_set;
        c.bind_graphics(stat, &[frame_set]);
        c.bind_vertices(&[self.statics(slot)], Some(&self.static_ib));
        c.draw(self.static_count, true);
        c.bind_graphics(cloth, &[frame_set]);
        c.bind_vertices(&[pos], Some(&self.tri_ib));
        c.draw(self.tri_count, true);
    }

    /// Draws one frame of the scene with the cloth from `cloth` and keeps a copy for
    /// [`VulkanRenderer::read_image`].
    pub fn render(&mut self, view: &View, cloth: VkCloth<'_>) -> Result<(), RenderError> {
        self.prepare(0, view, &cloth)?;
        Self::begin(&mut self.cmds).map_err(rerr)?;
        self.record(&self.cmds, 0, view, &cloth);
        let t = &self.targets;
        self.cmds.copy_image_to_buffer(&t.resolve, 0, 0, self.width, self.height, &t.readback);
        self.cmds.submit_and_wait(0).map_err(rerr)?;
        self.check().map_err(rerr)
    }

    /// The resolved scene image (TRANSFER_SRC_OPTIMAL after [`VulkanRenderer::record`]).
    pub fn image(&self) -> &Image {
        &self.targets.resolve
    }

    /// Records one frame of the scene into `c` from frame slot `slot` (written by
    /// [`VulkanRenderer::prepare`]); leaves the resolved image in TRANSFER_SRC_OPTIMAL.
    pub fn record(&self, c: &Commands, slot: usize, view: &View, cloth: &VkCloth<'_>) {
        let (pos, normal) = self.cloth_buffers(slot, cloth);
        let frame_set = &self.slots[slot % FRAMES_IN_FLIGHT].frame_set;
        let t = &self.targets;
        use vk::AccessFlags as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags as P;
        let tests = P::EARLY_FRAGMENT_TESTS | P::LATE_FRAGMENT_TESTS;
        let depth_rw = A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE;
        // Shadow pass: depth from the light.
        c.transition(
            &self.shadow,
            Transition {
                old: L::UNDEFINED,
                new: L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                src_stage: P::FRAGMENT_SHADER,
                src_access: A::empty(),
                dst_stage: tests,
                dst_access: depth_rw,
            },
        );
        c.begin_rendering(None, &self.shadow);
        self.draw_geometry(c, slot, &self.pipelines.shadow_static, &self.pipelines.shadow_cloth, pos);
        c.end_rendering();
        c.transition(
            &self.shadow,
            Transition {
                old: L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                new: L::SHADER_READ_ONLY_OPTIMAL,
                src_stage: tests,
                src_access: A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                dst_stage: P::FRAGMENT_SHADER,
                dst_access: A::SHADER_READ,
            },
        );
        // Main pass: 4× MSAA colour resolved into the sRGB target.
        let to_color = |img: &Image, src_stage| {
            Transition {
                old: L::UNDEFINED,
                new: L::COLOR_ATTACHMENT_OPTIMAL,
                src_stage,
                src_access: A::empty(),
                dst_stage: P::COLOR_ATTACHMENT_OUTPUT,
                dst_access: A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
            }
            .apply(c, img)
        };
        to_color(&t.msaa, P::COLOR_ATTACHMENT_OUTPUT);
        to_color(&t.resolve, P::TRANSFER);
        c.transition(&t.depth, Transition::fresh_depth());
        c.begin_rendering(Some((&t.msaa, Some(&t.resolve), vk::ClearColorValue { float32: SKY })), &t.depth);
        let p = &self.pipelines;
        c.bind_graphics(&p.lit_static, &[frame_set, &self.texture_set]);
        c.bind_vertices(&[self.statics(slot)], Some(&self.static_ib));
        c.draw(self.static_count, true);
        match view.mode {
            RenderMode::Triangles => {
                c.bind_graphics(&p.lit_cloth, &[frame_set, &self.texture_set]);
                c.bind_vertices(&[pos, normal, &self.uv], Some(&self.tri_ib));
                c.draw(self.tri_count, true);
            }
            RenderMode::Lines => {
                c.bind_graphics(&p.lines_cloth, &[frame_set, &self.texture_set]);
                c.bind_vertices(&[pos, normal, &self.uv], Some(&self.line_ib));
                c.draw(self.line_count, true);
            }
            RenderMode::Points => {
                c.bind_graphics(&p.points_cloth, &[frame_set, &self.texture_set]);
                c.bind_vertices(&[pos, normal, &self.uv], None);
                c.draw(self.num_particles, false);
            }
        }
        c.end_rendering();
        // The resolved image, ready to be read back.
        c.transition(&t.resolve, Transition::color_to_transfer_src());
    }

    /// The particle drawn at pixel `(x, y)` (origin top left) for this view and cloth, or
    /// `None` where no cloth is: the provoking vertex of the cloth triangle under the pixel
    /// (the particle or a direct neighbour), as on wgpu.
    pub fn pick(&mut self, view: &View, cloth: VkCloth<'_>, x: u32, y: u32) -> Result<Option<u32>, RenderError> {
        if x >= self.width || y >= self.height {
            return Ok(None);
        }
        self.prepare(0, view, &cloth)?;
        Self::begin(&mut self.cmds).map_err(rerr)?;
        let (pos, _) = self.cloth_buffers(0, &cloth);
        let c = &self.cmds;
        let t = &self.targets;
        use vk::AccessFlags as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags as P;
        c.transition(
            &t.pick,
            Transition {
                old: L::UNDEFINED,
                new: L::COLOR_ATTACHMENT_OPTIMAL,
                src_stage: P::TRANSFER,
                src_access: A::empty(),
                dst_stage: P::COLOR_ATTACHMENT_OUTPUT,
                dst_access: A::COLOR_ATTACHMENT_WRITE,
            },
        );
        c.transition(&t.pick_depth, Transition::fresh_depth());
        c.begin_rendering(Some((&t.pick, None, vk::ClearColorValue { uint32: [0; 4] })), &t.pick_depth);
        self.draw_geometry(c, 0, &self.pipelines.pick_static, &self.pipelines.pick_cloth, pos);
        c.end_rendering();
        c.transition(&t.pick, Transition::color_to_transfer_src());
        c.copy_image_to_buffer(&t.pick, x, y, 1, 1, &self.pick_buf);
        c.submit_and_wait(0).map_err(rerr)?;
        self.check().map_err(rerr)?;
        let raw = self.pick_buf.bytes().ok_or_else(|| RenderError::Backend("pick buffer not host visible".into()))?;
        let id = u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
        Ok(id.checked_sub(1))
    }

    /// The last frame as tightly packed sRGB RGBA8 rows (copied at the end of `render`).
    pub fn read_image(&self) -> Result<Vec<u8>, RenderError> {
        let len = self.width as usize * self.height as usize * 4;
        let map =
            self.targets.readback.bytes().ok_or_else(|| RenderError::Backend("readback not host visible".into()))?;
        Ok(map[..len].to_vec())
    }

    /// The device it draws on.
    pub fn device(&self) -> crate::Device {
        crate::Device::from_raw(&self.dev)
    }
}

impl Transition {
    fn apply(self, c: &Commands, image: &Image) {
        c.transition(image, self);
    }
}

impl clothlab_core::Renderer for VulkanRenderer {
    type Context = ();
    type Cloth<'a> = VkCloth<'a>;

    fn resize(&mut self, _: &(), width: u32, height: u32) -> Result<(), RenderError> {
        VulkanRenderer::resize(self, width, height)
    }

    fn render(&mut self, _: &(), view: &View, cloth: VkCloth<'_>) -> Result<(), RenderError> {
        VulkanRenderer::render(self, view, cloth)
    }

    fn pick(&mut self, _: &(), view: &View, cloth: VkCloth<'_>, x: u32, y: u32) -> Result<Option<u32>, RenderError> {
        VulkanRenderer::pick(self, view, cloth, x, y)
    }

    fn read_image(&self, _: &()) -> Result<Vec<u8>, RenderError> {
        VulkanRenderer::read_image(self)
    }
}
