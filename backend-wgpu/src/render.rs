//! The scene renderer on wgpu: a shadow pass from the light, a lit main pass (Blinn-Phong,
//! PCF shadows, textured cloth, checkered floor, spheres, boxes) with 4× MSAA into an sRGB
//! target, the cloth as triangles, lines or points, drawn from the solver's own buffers.

use clothlab_core::grid::{ClothState, ClothTopology};
use clothlab_core::render::{Frame, SAMPLES, SHADOW_SIZE, SKY, StaticVertex, cloth_lines, fabric_texture, static_mesh};
use clothlab_core::scene::Scene;
use clothlab_core::solver::{RenderError, RenderMode, View};
use wgpu::util::DeviceExt;

use crate::context::GpuContext;

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Where the cloth's positions and normals come from.
pub enum ClothSource<'a> {
    /// A GPU solver's own buffers (`[f32; 4]` per particle each): drawn with no copy.
    Gpu {
        /// Positions.
        pos: &'a wgpu::Buffer,
        /// Normals.
        normal: &'a wgpu::Buffer,
    },
    /// A CPU solver's state: uploaded once per frame.
    Cpu(&'a ClothState),
}

struct Targets {
    msaa: wgpu::TextureView,
    resolve: wgpu::Texture,
    resolve_view: wgpu::TextureView,
    /// The same image viewed as plain RGBA8 (its sRGB bytes, undecoded).
    resolve_bytes_view: wgpu::TextureView,
    /// Where the adapter cannot view a texture in another format (wgpu on GL: no
    /// `DownlevelFlags::VIEW_FORMATS`), a plain RGBA8 texture the resolved image is
    /// copied into after each frame, which `resolve_bytes_view` views instead.
    bytes_copy: Option<wgpu::Texture>,
    depth: wgpu::TextureView,
    /// Particle ids (R32Uint) and their depth, one sample per pixel.
    pick: wgpu::Texture,
    pick_view: wgpu::TextureView,
    pick_depth: wgpu::TextureView,
}

/// Offscreen renderer of one scene and its cloth.
pub struct WgpuRenderer {
    width: u32,
    height: u32,
    targets: Targets,
    shadow_view: wgpu::TextureView,
    frame: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    texture_group: wgpu::BindGroup,
    lit_static: wgpu::RenderPipeline,
    lit_cloth: wgpu::RenderPipeline,
    lines_cloth: wgpu::RenderPipeline,
    points_cloth: wgpu::RenderPipeline,
    shadow_static: wgpu::RenderPipeline,
    shadow_cloth: wgpu::RenderPipeline,
    pick_static: wgpu::RenderPipeline,
    pick_cloth: wgpu::RenderPipeline,
    static_vb: wgpu::Buffer,
    static_ib: wgpu::Buffer,
    static_count: u32,
    uv: wgpu::Buffer,
    tri_ib: wgpu::Buffer,
    tri_count: u32,
    line_ib: wgpu::Buffer,
    line_count: u32,
    num_particles: u32,
    /// Upload targets for CPU solvers.
    cpu_pos: wgpu::Buffer,
    cpu_normal: wgpu::Buffer,
}

fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<(), RenderError> {
    let max = ctx.device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::InvalidSize { width, height, reason: format!("each side must be in 1 ..= {max}") });
    }
    Ok(())
}

fn make_targets(ctx: &GpuContext, width: u32, height: u32) -> Targets {
    let view_formats = ctx.adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::VIEW_FORMATS);
    let tex = |label, format, samples, usage| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            // The resolved image is also viewed as plain RGBA8: egui samples its textures
            // as gamma-encoded bytes.
            view_formats: if view_formats && format == COLOR_FORMAT && samples == 1 {
                &[wgpu::TextureFormat::Rgba8Unorm]
            } else {
                &[]
            },
        })
    };
    let msaa = tex("color (msaa)", COLOR_FORMAT, SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT);
    // Sampled too: the app shows it as an egui image.
    let resolve = tex(
        "color",
        COLOR_FORMAT,
        1,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let depth = tex("depth", DEPTH_FORMAT, SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let pick = tex(
        "pick ids",
        wgpu::TextureFormat::R32Uint,
        1,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let pick_depth = tex("pick depth", DEPTH_FORMAT, 1, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let bytes_copy = (!view_formats).then(|| {
        tex(
            "color bytes",
            wgpu::TextureFormat::Rgba8Unorm,
            1,
            wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
        )
    });
    let bytes_view =
        wgpu::TextureViewDescriptor { format: Some(wgpu::TextureFormat::Rgba8Unorm), ..Default::default() };
    Targets {
        msaa: msaa.create_view(&Default::default()),
        resolve_view: resolve.create_view(&Default::default()),
        resolve_bytes_view: bytes_copy.as_ref().unwrap_or(&resolve).create_view(&bytes_view),
        bytes_copy,
        resolve,
        depth: depth.create_view(&Default::default()),
        pick_view: pick.create_view(&Default::default()),
        pick,
        pick_depth: pick_depth.create_view(&Default::default()),
    }
}

impl WgpuRenderer {
    /// A renderer of `scene` with its cloth `topo` on `ctx`, drawing `width × height`.
    pub fn new(
        ctx: &GpuContext,
        scene: &Scene,
        topo: &ClothTopology,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        check_size(ctx, width, height)?;
        let dev = &ctx.device;
        let shader =
            clothlab_shaders::kernel("render").ok_or_else(|| RenderError::Backend("render shader missing".into()))?;
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("render"),
            source: wgpu::ShaderSource::Wgsl(shader.wgsl.into()),
        });
        let targets = make_targets(ctx, width, height);
        let shadow = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow map"),
            size: wgpu::Extent3d { width: SHADOW_SIZE, height: SHADOW_SIZE, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let shadow_view = shadow.create_view(&Default::default());
        let fabric = dev.create_texture_with_data(
            &ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some("fabric"),
                size: wgpu::Extent3d { width: 64, height: 64, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8UnormSrgb,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &fabric_texture(),
        );
        let frame = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<Frame>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let tex_entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty,
            count: None,
        };
        let texture_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("textures"),
            entries: &[
                tex_entry(
                    0,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
                tex_entry(1, wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison)),
                tex_entry(
                    2,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                ),
                tex_entry(3, wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering)),
            ],
        });
        let frame_group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: frame.as_entire_binding() }],
        });
        let shadow_sampler = dev.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let fabric_sampler = dev.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("fabric"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let fabric_view = fabric.create_view(&Default::default());
        let texture_group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("textures"),
            layout: &texture_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&shadow_view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&shadow_sampler) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&fabric_view) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::Sampler(&fabric_sampler) },
            ],
        });
        let main_layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("main"),
            bind_group_layouts: &[Some(&frame_layout), Some(&texture_layout)],
            immediate_size: 0,
        });
        let shadow_layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });

        let static_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32];
        let static_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<StaticVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &static_attrs,
        };
        let v4 = |loc| wgpu::VertexBufferLayout {
            array_stride: 16,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: match loc {
                0 => &[wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x4, offset: 0, shader_location: 0 }],
                _ => &[wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x4, offset: 0, shader_location: 1 }],
            },
        };
        let uv_layout = wgpu::VertexBufferLayout {
            array_stride: 8,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x2,
                offset: 0,
                shader_location: 2,
            }],
        };
        let cloth_layouts = [Some(v4(0)), Some(v4(1)), Some(uv_layout)];
        let static_layouts = [Some(static_layout.clone())];
        let depth_state = |bias: wgpu::DepthBiasState| wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias,
        };
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        vs: &str,
                        buffers: &[Option<wgpu::VertexBufferLayout>],
                        fs: Option<&str>,
                        topology: wgpu::PrimitiveTopology,
                        shadow_pass: bool| {
            let color = [Some(wgpu::ColorTargetState {
                format: COLOR_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })];
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState { topology, cull_mode: None, ..Default::default() },
                depth_stencil: Some(depth_state(if shadow_pass {
                    wgpu::DepthBiasState { constant: 2, slope_scale: 2.0, clamp: 0.0 }
                } else {
                    Default::default()
                })),
                multisample: wgpu::MultisampleState {
                    count: if shadow_pass { 1 } else { SAMPLES },
                    ..Default::default()
                },
                fragment: fs.map(|fs| wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &color,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        use wgpu::PrimitiveTopology as T;
        let shadow_static_layouts = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<StaticVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &static_attrs[..1],
        })];
        let lit_static =
            pipeline("lit static", &main_layout, "vs_static", &static_layouts, Some("fs_lit"), T::TriangleList, false);
        let lit_cloth =
            pipeline("lit cloth", &main_layout, "vs_cloth", &cloth_layouts, Some("fs_lit"), T::TriangleList, false);
        let lines_cloth =
            pipeline("cloth lines", &main_layout, "vs_cloth", &cloth_layouts, Some("fs_flat"), T::LineList, false);
        let points_cloth =
            pipeline("cloth points", &main_layout, "vs_cloth", &cloth_layouts, Some("fs_flat"), T::PointList, false);
        let shadow_static = pipeline(
            "shadow static",
            &shadow_layout,
            "vs_shadow_static",
            &shadow_static_layouts,
            None,
            T::TriangleList,
            true,
        );
        let shadow_cloth = pipeline(
            "shadow cloth",
            &shadow_layout,
            "vs_shadow_cloth",
            &cloth_layouts[..1],
            None,
            T::TriangleList,
            true,
        );

        let pick_pipeline = |label: &str, vs: &str, buffers: &[Option<wgpu::VertexBufferLayout>]| {
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&shadow_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState { topology: T::TriangleList, cull_mode: None, ..Default::default() },
                depth_stencil: Some(depth_state(Default::default())),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_pick"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: wgpu::TextureFormat::R32Uint,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let pick_static = pick_pipeline("pick static", "vs_pick_static", &shadow_static_layouts);
        let pick_cloth = pick_pipeline("pick cloth", "vs_pick_cloth", &cloth_layouts[..1]);

        let (sv, si) = static_mesh(scene);
        let init = |label, contents: &[u8], usage| {
            dev.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        use wgpu::BufferUsages as U;
        let tri: Vec<u32> = topo.triangles.iter().flatten().copied().collect();
        let lines = cloth_lines(topo);
        let np = topo.num_particles() as u64;
        let vertex_buffer = |label| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: np * 16,
                usage: U::VERTEX | U::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let r = Self {
            width,
            height,
            targets,
            shadow_view,
            frame,
            frame_group,
            texture_group,
            lit_static,
            lit_cloth,
            lines_cloth,
            points_cloth,
            shadow_static,
            shadow_cloth,
            pick_static,
            pick_cloth,
            static_vb: init("static vertices", bytemuck::cast_slice(&sv), U::VERTEX | U::COPY_DST),
            static_ib: init("static indices", bytemuck::cast_slice(&si), U::INDEX),
            static_count: si.len() as u32,
            uv: init("cloth uv", bytemuck::cast_slice(&topo.render_uvs()), U::VERTEX),
            tri_ib: init("cloth triangles", bytemuck::cast_slice(&tri), U::INDEX),
            tri_count: tri.len() as u32,
            line_ib: init("cloth lines", bytemuck::cast_slice(&lines), U::INDEX),
            line_count: lines.len() as u32,
            num_particles: np as u32,
            cpu_pos: vertex_buffer("cpu positions"),
            cpu_normal: vertex_buffer("cpu normals"),
        };
        ctx.check("creating the renderer").map_err(|e| RenderError::Backend(e.to_string()))?;
        Ok(r)
    }

    /// The resolved colour target viewed as plain RGBA8 (the sRGB bytes as they are):
    /// what egui, which works on gamma-encoded colours, samples.
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.targets.resolve_bytes_view
    }

    /// Target size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Changes the target size; a zero or too large side is refused and nothing changes.
    /// Draws the colliders of `scene` from now on (moving colliders: `Scene::moved_to`);
    /// the same shapes as the renderer was made with, else refused.
    pub fn set_colliders(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), RenderError> {
        let (sv, _) = static_mesh(scene);
        let bytes: &[u8] = bytemuck::cast_slice(&sv);
        if bytes.len() as u64 != self.static_vb.size() {
            return Err(RenderError::Backend("set_colliders: the scene's colliders are not the renderer's".into()));
        }
        ctx.queue.write_buffer(&self.static_vb, 0, bytes);
        Ok(())
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<(), RenderError> {
        check_size(ctx, width, height)?;
        self.targets = make_targets(ctx, width, height);
        self.width = width;
        self.height = height;
        Ok(())
    }

    /// The cloth's position and normal buffers for `cloth` (uploading a CPU state).
    fn cloth_buffers<'a>(
        &'a self,
        ctx: &GpuContext,
        cloth: ClothSource<'a>,
    ) -> Result<(&'a wgpu::Buffer, &'a wgpu::Buffer), RenderError> {
        Ok(match cloth {
            ClothSource::Gpu { pos, normal } => (pos, normal),
            ClothSource::Cpu(state) => {
                if state.pos.len() != self.num_particles as usize {
                    return Err(RenderError::Backend("state of another grid size".into()));
                }
                ctx.queue.write_buffer(&self.cpu_pos, 0, bytemuck::cast_slice(&state.pos));
                ctx.queue.write_buffer(&self.cpu_normal, 0, bytemuck::cast_slice(&state.normal));
                (&self.cpu_pos, &self.cpu_normal)
            }
        })
    }

    /// Floor, colliders and cloth triangles with one pipeline for the static mesh and one
    /// for the cloth (positions only): the shadow and picking passes.
    fn draw_geometry(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        static_pipeline: &wgpu::RenderPipeline,
        cloth_pipeline: &wgpu::RenderPipeline,
        pos: &wgpu::Buffer,
    ) {
        pass.set_bind_group(0, &self.frame_group, &[]);
        pass.set_pipeline(static_pipeline);
        pass.set_vertex_buffer(0, self.static_vb.slice(..));
        pass.set_index_buffer(self.static_ib.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.static_count, 0, 0..1);
        pass.set_pipeline(cloth_pipeline);
        pass.set_vertex_buffer(0, pos.slice(..));
        pass.set_index_buffer(self.tri_ib.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.tri_count, 0, 0..1);
    }

    /// Uploads the camera and light of `view`.
    fn write_frame(&self, ctx: &GpuContext, view: &View) {
        let f = Frame::new(view, self.width, self.height);
        ctx.queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(&f));
    }

    /// Draws one frame of the scene with the cloth from `cloth`.
    pub fn render(&mut self, ctx: &GpuContext, view: &View, cloth: ClothSource<'_>) -> Result<(), RenderError> {
        let (pos, normal) = self.cloth_buffers(ctx, cloth)?;
        self.write_frame(ctx, view);
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("render") });
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.shadow_view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.draw_geometry(&mut pass, &self.shadow_static, &self.shadow_cloth, pos);
        }
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("main"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.targets.msaa,
                    depth_slice: None,
                    resolve_target: Some(&self.targets.resolve_view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: SKY[0] as f64,
                            g: SKY[1] as f64,
                            b: SKY[2] as f64,
                            a: SKY[3] as f64,
                        }),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.targets.depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.frame_group, &[]);
            pass.set_bind_group(1, &self.texture_group, &[]);
            pass.set_pipeline(&self.lit_static);
            pass.set_vertex_buffer(0, self.static_vb.slice(..));
            pass.set_index_buffer(self.static_ib.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.static_count, 0, 0..1);
            pass.set_vertex_buffer(0, pos.slice(..));
            pass.set_vertex_buffer(1, normal.slice(..));
            pass.set_vertex_buffer(2, self.uv.slice(..));
            match view.mode {
                RenderMode::Triangles => {
                    pass.set_pipeline(&self.lit_cloth);
                    pass.set_index_buffer(self.tri_ib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..self.tri_count, 0, 0..1);
                }
                RenderMode::Lines => {
                    pass.set_pipeline(&self.lines_cloth);
                    pass.set_index_buffer(self.line_ib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..self.line_count, 0, 0..1);
                }
                RenderMode::Points => {
                    pass.set_pipeline(&self.points_cloth);
                    pass.draw(0..self.num_particles, 0..1);
                }
            }
        }
        if let Some(bytes) = &self.targets.bytes_copy {
            // Same bytes, the sRGB-ness aside (a copy wgpu allows between the two).
            enc.copy_texture_to_texture(
                self.targets.resolve.as_image_copy(),
                bytes.as_image_copy(),
                wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
            );
        }
        ctx.queue.submit([enc.finish()]);
        ctx.check("rendering").map_err(|e| RenderError::Backend(e.to_string()))
    }

    /// The particle drawn at pixel `(x, y)` (origin top left) for this view and cloth, or
    /// `None` where no cloth is (floor, colliders and sky hide it or are there instead).
    /// The id is that of the provoking (first) vertex of the cloth triangle under the
    /// pixel: the particle itself or one of its direct neighbours.
    pub fn pick(
        &mut self,
        ctx: &GpuContext,
        view: &View,
        cloth: ClothSource<'_>,
        x: u32,
        y: u32,
    ) -> Result<Option<u32>, RenderError> {
        if x >= self.width || y >= self.height {
            return Ok(None);
        }
        let (pos, _) = self.cloth_buffers(ctx, cloth)?;
        self.write_frame(ctx, view);
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("pick") });
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("pick"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.targets.pick_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.targets.pick_depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.draw_geometry(&mut pass, &self.pick_static, &self.pick_cloth, pos);
        }
        let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pick pixel"),
            size: 256,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.targets.pick,
                mip_level: 0,
                origin: wgpu::Origin3d { x, y, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(256), rows_per_image: None },
            },
            wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
        );
        ctx.queue.submit([enc.finish()]);
        let raw = ctx.read_buffer(&buf, 0, 4).map_err(|e| RenderError::Backend(e.to_string()))?;
        let id = u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
        ctx.check("picking").map_err(|e| RenderError::Backend(e.to_string()))?;
        Ok(id.checked_sub(1))
    }

    /// The last frame as tightly packed sRGB RGBA8 rows.
    pub fn read_image(&self, ctx: &GpuContext) -> Result<Vec<u8>, RenderError> {
        let row = self.width as u64 * 4;
        let padded = row.div_ceil(256) * 256;
        let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image"),
            size: padded * self.height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("image") });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.targets.resolve,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded as u32),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        ctx.queue.submit([enc.finish()]);
        let raw = ctx.read_buffer(&buf, 0, buf.size()).map_err(|e| RenderError::Backend(e.to_string()))?;
        Ok(raw.chunks(padded as usize).flat_map(|r| r[..row as usize].iter().copied()).collect())
    }
}

impl clothlab_core::Renderer for WgpuRenderer {
    type Context = GpuContext;
    type Cloth<'a> = ClothSource<'a>;

    fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<(), RenderError> {
        WgpuRenderer::resize(self, ctx, width, height)
    }

    fn render(&mut self, ctx: &GpuContext, view: &View, cloth: ClothSource<'_>) -> Result<(), RenderError> {
        WgpuRenderer::render(self, ctx, view, cloth)
    }

    fn pick(
        &mut self,
        ctx: &GpuContext,
        view: &View,
        cloth: ClothSource<'_>,
        x: u32,
        y: u32,
    ) -> Result<Option<u32>, RenderError> {
        WgpuRenderer::pick(self, ctx, view, cloth, x, y)
    }

    fn read_image(&self, ctx: &GpuContext) -> Result<Vec<u8>, RenderError> {
        WgpuRenderer::read_image(self, ctx)
    }
}
