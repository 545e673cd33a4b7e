//! The wgpu engine: buffers; per set of bindings the kernels use, a bind group layout and
//! two bind groups (one per position parity) — one layout for all the step's bindings
//! would hold 25 storage buffers, past the 16 a stage may have on wgpu's GL backend —;
//! a compute pipeline per kernel, one compute pass per
//! dispatch (timestamps through the pass), writes through the queue. wgpu places its own
//! barriers, so [`Engine::barrier`] records nothing. The solver itself is
//! [`clothlab_engine::GpuSolver`]: [`WgpuSolver`] is it on this engine.

use std::collections::HashMap;

use clothlab_core::SolverError;
use clothlab_core::layout::{BindKind, Buf, TABLE_WIDTH};
use clothlab_engine::gpu::{BufferId, Dispatch, Engine, EngineInfo, Finished};
use clothlab_engine::kernels::{self, KernelRef};
use clothlab_engine::solver::MAX_QUERIES;
use clothlab_engine::{GpuSolver, SolverOptions, VariantSpec};
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};

/// The cloth solver on wgpu.
pub type WgpuSolver = GpuSolver<WgpuEngine>;

fn backend(e: GpuError) -> SolverError {
    match e {
        GpuError::NoAdapter => SolverError::NoAdapter(e.to_string()),
        e => SolverError::Driver(e.to_string()),
    }
}

/// The buffers bound at each binding, per position parity.
type Sets = [Vec<(Buf, BufferId)>; 2];

/// One set of bindings: its layout, its bind group per parity, its pipeline layouts by
/// immediate size.
struct Layout {
    layout: wgpu::BindGroupLayout,
    groups: [wgpu::BindGroup; 2],
    pipeline_layouts: HashMap<u32, wgpu::PipelineLayout>,
}

struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
}

/// The API's part of the wgpu solver.
pub struct WgpuEngine {
    ctx: GpuContext,
    info: EngineInfo,
    buffers: Vec<wgpu::Buffer>,
    /// What the solver bound (per parity) and the table image's view.
    sets: Option<(Sets, Option<wgpu::TextureView>)>,
    /// The layouts and groups made so far, by the bindings they hold.
    layouts: Vec<Layout>,
    layout_of: HashMap<Vec<u32>, usize>,
    /// Each kernel's pipeline and its layout (an index into `layouts`).
    pipelines: HashMap<KernelRef, (wgpu::ComputePipeline, usize)>,
    timestamps: Option<Timestamps>,
    encoder: Option<wgpu::CommandEncoder>,
    /// Something was recorded into `encoder` since `begin`: a queue write would land
    /// before it, so later writes are staged and copied in order.
    recorded: bool,
    readbacks: Vec<(BufferId, u64)>,
    /// The spring table as a texture (`table=image`), and its height.
    table: Option<(wgpu::Texture, u32)>,
    /// The bodies' distance fields as a 3-D texture (`sdf=image`), and (once bound) its
    /// view and trilinear sampler.
    sdf: Option<wgpu::Texture>,
    sdf_bound: Option<(wgpu::TextureView, wgpu::Sampler)>,
}

impl WgpuEngine {
    /// An engine on the first adapter wgpu finds.
    pub fn new() -> Result<Self, SolverError> {
        Ok(Self::on(GpuContext::new().map_err(backend)?))
    }

    /// An engine on `ctx` (a window's device: the renderer draws the solver's buffers).
    pub fn on(ctx: GpuContext) -> Self {
        let limits = ctx.device.limits();
        let info = EngineInfo {
            api: "wgpu",
            adapter: ctx.describe(),
            float_atomics: ctx.float_atomics,
            immediates: ctx.immediates,
            timestamps: ctx.timestamps,
            timestamp_period_ns: ctx.queue.get_timestamp_period() as f64,
            max_binding: limits.max_storage_buffer_binding_size.min(limits.max_buffer_size),
            subgroup_arithmetic: ctx.subgroups,
            subgroup_shuffle: ctx.subgroups,
            cpu: ctx.info.device_type == wgpu::DeviceType::Cpu,
            table_image: true,
            sdf_image: ctx.float32_filterable,
            workgroup_memory: limits.max_compute_workgroup_storage_size,
        };
        let timestamps = ctx.timestamps.then(|| Timestamps {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_QUERIES,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: MAX_QUERIES as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        });
        Self {
            ctx,
            info,
            buffers: Vec::new(),
            sets: None,
            layouts: Vec::new(),
            layout_of: HashMap::new(),
            pipelines: HashMap::new(),
            timestamps,
            encoder: None,
            recorded: false,
            readbacks: Vec::new(),
            table: None,
            sdf: None,
            sdf_bound: None,
        }
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    fn buf(&self, id: BufferId) -> Result<&wgpu::Buffer, SolverError> {
        self.buffers.get(id.0 as usize).ok_or_else(|| SolverError::Invalid(format!("no wgpu buffer {}", id.0)))
    }

    fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        let dev = &self.ctx.device;
        self.encoder
            .get_or_insert_with(|| dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") }))
    }
}

impl WgpuEngine {
    /// The layout of the bindings `uses` and its bind group for each parity.
    fn make_layout(&self, uses: &[u32]) -> Result<Layout, String> {
        let (sets, view) = self.sets.as_ref().ok_or("kernels are built after the buffers are bound")?;
        let mut entries = Vec::new();
        for &b in uses {
            let buf = Buf::from_binding(b).ok_or_else(|| format!("binding {b} is no buffer of the step"))?;
            let ty = match buf.kind() {
                BindKind::Image => {
                    view.as_ref().ok_or("it reads the table image, which the solver did not make")?;
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    }
                }
                BindKind::Volume => {
                    self.sdf_bound
                        .as_ref()
                        .ok_or("it reads the distance-field image, which the solver did not make")?;
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D3,
                        multisampled: false,
                    }
                }
                BindKind::Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                BindKind::Uniform => wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                BindKind::Storage => wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: !written(buf) },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            };
            entries.push(wgpu::BindGroupLayoutEntry {
                binding: b,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty,
                count: None,
            });
        }
        let dev = &self.ctx.device;
        let layout =
            dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("cloth"), entries: &entries });
        let group = |parity: usize| -> Result<wgpu::BindGroup, String> {
            let mut entries = Vec::new();
            for &b in uses {
                let resource = match Buf::from_binding(b) {
                    Some(Buf::Table) if view.is_some() => {
                        wgpu::BindingResource::TextureView(view.as_ref().expect("checked"))
                    }
                    Some(Buf::SdfImage) if self.sdf_bound.is_some() => {
                        wgpu::BindingResource::TextureView(&self.sdf_bound.as_ref().expect("checked").0)
                    }
                    Some(Buf::SdfSampler) if self.sdf_bound.is_some() => {
                        wgpu::BindingResource::Sampler(&self.sdf_bound.as_ref().expect("checked").1)
                    }
                    buf => {
                        let id =
                            sets[parity].iter().find(|(x, _)| Some(*x) == buf).map(|&(_, id)| id).ok_or_else(|| {
                                format!("it uses binding {b} ({buf:?}), which the solver did not bind")
                            })?;
                        self.buffers[id.0 as usize].as_entire_binding()
                    }
                };
                entries.push(wgpu::BindGroupEntry { binding: b, resource });
            }
            Ok(dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(if parity == 0 { "cloth (pos0)" } else { "cloth (pos1)" }),
                layout: &layout,
                entries: &entries,
            }))
        };
        let groups = [group(0)?, group(1)?];
        Ok(Layout { layout, groups, pipeline_layouts: HashMap::new() })
    }
}

/// Whether any kernel of the registry writes `buf` (the others are bound read-only).
fn written(buf: Buf) -> bool {
    kernels::ALL.iter().any(|d| d.writes.contains(&buf))
}

impl Engine for WgpuEngine {
    type Buffer = wgpu::Buffer;

    fn info(&self) -> &EngineInfo {
        &self.info
    }

    fn create_buffer(&mut self, buf: Buf, label: &str, contents: &[u8], vertex: bool) -> Result<BufferId, SolverError> {
        use wgpu::BufferUsages as U;
        let usage = match buf.kind() {
            BindKind::Uniform => U::UNIFORM,
            _ => U::STORAGE,
        } | if vertex { U::VERTEX } else { U::empty() }
            | if buf == Buf::Triangles { U::INDEX } else { U::empty() }
            | U::COPY_SRC
            | U::COPY_DST;
        // wgpu refuses empty buffers; a binding is at least one word.
        let mut bytes = contents.to_vec();
        bytes.resize(bytes.len().max(4), 0);
        let b = self.ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &bytes,
            usage,
        });
        self.buffers.push(b);
        Ok(BufferId(self.buffers.len() as u32 - 1))
    }

    fn buffer(&self, id: BufferId) -> &wgpu::Buffer {
        &self.buffers[id.0 as usize]
    }

    /// The table as an `Rgba32Uint` texture, TABLE_WIDTH texels a row (the thesis's
    /// texture memory), written through the queue; rewritten in place when the
    /// constants change.
    fn set_table_image(&mut self, texels: &[[u32; 4]], height: u32) -> Result<(), SolverError> {
        let max = self.ctx.device.limits().max_texture_dimension_2d;
        if height > max {
            return Err(SolverError::Unsupported(format!(
                "table=image: this grid's spring table needs a {TABLE_WIDTH}×{height} image, taller than the {max} texels {} allows; use table=storage or table=uniform",
                self.info.adapter
            )));
        }
        if self.table.as_ref().is_none_or(|(_, h)| *h != height) {
            if self.sets.is_some() {
                return Err(SolverError::Invalid("the spring-table image cannot change size once bound".into()));
            }
            let texture = self.ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("spring table"),
                size: wgpu::Extent3d { width: TABLE_WIDTH, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Uint,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            self.table = Some((texture, height));
        }
        let (texture, _) = self.table.as_ref().expect("made above");
        let mut bytes: Vec<u8> = bytemuck::cast_slice(texels).to_vec();
        bytes.resize((TABLE_WIDTH * height * 16) as usize, 0);
        self.ctx.queue.write_texture(
            texture.as_image_copy(),
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(TABLE_WIDTH * 16),
                rows_per_image: Some(height),
            },
            wgpu::Extent3d { width: TABLE_WIDTH, height, depth_or_array_layers: 1 },
        );
        self.ctx.check("uploading the spring-table image").map_err(backend)
    }

    /// The fields as an `R32Float` 3-D texture (the thesis's texture memory, where the
    /// hardware interpolates), written once through the queue; a trilinear sampler
    /// clamped to the edge.
    fn set_sdf_image(&mut self, values: &[f32], dims: [u32; 3]) -> Result<(), SolverError> {
        let [w, h, d] = dims;
        let max = self.ctx.device.limits().max_texture_dimension_3d;
        if !self.info.sdf_image {
            return Err(SolverError::Unsupported(format!(
                "sdf=image: {} cannot filter 32-bit float textures (no FLOAT32_FILTERABLE); use sdf=storage",
                self.info.adapter
            )));
        }
        if values.len() != (w * h * d) as usize {
            return Err(SolverError::Invalid(format!("{} values for a {w}×{h}×{d} image", values.len())));
        }
        if w.max(h).max(d) > max {
            return Err(SolverError::Unsupported(format!(
                "sdf=image: the bodies' fields need a {w}×{h}×{d} image, more than the {max} texels a side {} allows; use sdf=storage",
                self.info.adapter
            )));
        }
        if self.sets.is_some() {
            return Err(SolverError::Invalid("the distance-field image is made before the buffers are bound".into()));
        }
        let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: d };
        let texture = self.ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("distance fields"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        self.ctx.queue.write_texture(
            texture.as_image_copy(),
            bytemuck::cast_slice(values),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * 4), rows_per_image: Some(h) },
            size,
        );
        self.sdf = Some(texture);
        self.ctx.check("uploading the distance-field image").map_err(backend)
    }

    fn bind(&mut self, sets: [Vec<(Buf, BufferId)>; 2]) -> Result<(), SolverError> {
        for &(_, id) in sets.iter().flatten() {
            self.buf(id)?;
        }
        self.sdf_bound = self.sdf.as_ref().map(|t| {
            let sampler = self.ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("distance fields, trilinear"),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                address_mode_w: wgpu::AddressMode::ClampToEdge,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            });
            (t.create_view(&wgpu::TextureViewDescriptor::default()), sampler)
        });
        let view = self.table.as_ref().map(|(t, _)| t.create_view(&wgpu::TextureViewDescriptor::default()));
        self.sets = Some((sets, view));
        Ok(())
    }

    fn build(&mut self, k: KernelRef, immediates: u32) -> Result<(), SolverError> {
        if self.pipelines.contains_key(&k) {
            return Ok(());
        }
        if self.sets.is_none() {
            return Err(SolverError::Invalid("kernels are built after the buffers are bound".into()));
        }
        let name = k.shader_name();
        let wgsl = k.wgsl()?;
        let builtin = matches!(k.def.source, kernels::Source::Builtin);
        let refuse = |reason: String| SolverError::Shader { kernel: name.clone(), reason };
        if !builtin {
            // naga's message, with the line, before wgpu sees it.
            clothlab_shaders::compile_spirv(&name, &wgsl).map_err(refuse)?;
        }
        let uses = match clothlab_shaders::kernel(&name).filter(|_| builtin) {
            Some(kernel) => kernel.uses.to_vec(),
            None => clothlab_shaders::uses(&name, &wgsl).map_err(refuse)?,
        };
        let index = match self.layout_of.get(&uses) {
            Some(&i) => i,
            None => {
                let layout = self.make_layout(&uses).map_err(refuse)?;
                self.layouts.push(layout);
                self.layout_of.insert(uses, self.layouts.len() - 1);
                self.layouts.len() - 1
            }
        };
        let dev = &self.ctx.device;
        let set = &mut self.layouts[index];
        let bind_group_layout = &set.layout;
        let pipeline_layout = set.pipeline_layouts.entry(immediates).or_insert_with(|| {
            dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("cloth"),
                bind_group_layouts: &[Some(bind_group_layout)],
                immediate_size: immediates,
            })
        });
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&name),
            source: wgpu::ShaderSource::Wgsl(wgsl),
        });
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&name),
            layout: Some(pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: wgpu::PipelineCompilationOptions {
                zero_initialize_workgroup_memory: clothlab_shaders::zero_workgroup_memory(k.def.name),
                ..Default::default()
            },
            cache: None,
        });
        self.pipelines.insert(k, (pipeline, index));
        Ok(())
    }

    fn kernels(&self) -> Vec<KernelRef> {
        self.pipelines.keys().copied().collect()
    }

    fn write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError> {
        let b = self.buf(id)?;
        self.ctx.queue.write_buffer(b, 0, bytes);
        Ok(())
    }

    fn read(&mut self, id: BufferId) -> Result<Vec<u8>, SolverError> {
        let b = self.buf(id)?;
        self.ctx.read_buffer(b, 0, b.size()).map_err(backend)
    }

    fn begin(&mut self, _index: usize, _queries: u32) -> Result<(), SolverError> {
        self.encoder = None;
        self.recorded = false;
        self.encoder();
        Ok(())
    }

    /// A queue write (it lands before the submission being recorded runs) while nothing
    /// is recorded yet; after that a staging buffer copied in order (moving colliders
    /// write theirs before every substep of one submission).
    fn record_write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError> {
        if !self.recorded {
            return self.write(id, bytes);
        }
        let dst = self.buf(id)?.clone();
        let staged = self.ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("staged write"),
            contents: bytes,
            usage: wgpu::BufferUsages::COPY_SRC,
        });
        self.encoder().copy_buffer_to_buffer(&staged, 0, &dst, 0, bytes.len() as u64);
        Ok(())
    }

    fn clear(&mut self, id: BufferId) {
        let Some(b) = self.buffers.get(id.0 as usize).cloned() else { return };
        self.recorded = true;
        self.encoder().clear_buffer(&b, 0, None);
    }

    fn copy(&mut self, src: BufferId, dst: BufferId, size: u64) {
        let (Some(a), Some(b)) = (self.buffers.get(src.0 as usize).cloned(), self.buffers.get(dst.0 as usize).cloned())
        else {
            return;
        };
        let size = size.min(a.size()).min(b.size());
        self.recorded = true;
        self.encoder().copy_buffer_to_buffer(&a, 0, &b, 0, size);
    }

    /// wgpu tracks the hazards between passes itself.
    fn barrier(&mut self, _after_all: bool) {}

    fn dispatch(&mut self, d: &Dispatch<'_>) {
        self.recorded = true;
        let Self { ctx, pipelines, layouts, timestamps, encoder, .. } = self;
        let Some((pipeline, index)) = pipelines.get(&d.kernel) else { return };
        let group = &layouts[*index].groups[d.parity & 1];
        let timestamp_writes = match (timestamps.as_ref(), d.timestamps) {
            (Some(ts), Some(q)) if q + 2 <= MAX_QUERIES => Some(wgpu::ComputePassTimestampWrites {
                query_set: &ts.set,
                beginning_of_pass_write_index: Some(q),
                end_of_pass_write_index: Some(q + 1),
            }),
            _ => None,
        };
        let enc = encoder.get_or_insert_with(|| {
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") })
        });
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(d.kernel.def.label), timestamp_writes });
        pass.set_pipeline(pipeline);
        if !d.immediates.is_empty() {
            pass.set_immediates(0, d.immediates);
        }
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(d.groups.0, d.groups.1, d.groups.2);
    }

    /// Read after the wait (wgpu maps a copy of the buffer then).
    fn readback(&mut self, id: BufferId, size: u64) -> Result<(), SolverError> {
        let size = size.min(self.buf(id)?.size());
        self.readbacks.push((id, size));
        Ok(())
    }

    fn submit(&mut self, _last: bool) -> Result<(), SolverError> {
        let enc = self.encoder.take().unwrap_or_else(|| {
            self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") })
        });
        self.ctx.queue.submit([enc.finish()]);
        Ok(())
    }

    /// Returns at once when nothing must come back: the queue orders whatever follows.
    fn wait(&mut self, queries: u32) -> Result<Finished, SolverError> {
        let mut done = Finished::default();
        if let Some(ts) = self.timestamps.as_ref().filter(|_| queries > 0) {
            let q = queries.min(MAX_QUERIES);
            let mut enc =
                self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("timestamps") });
            enc.resolve_query_set(&ts.set, 0..q, &ts.resolve, 0);
            self.ctx.queue.submit([enc.finish()]);
            let raw = self.ctx.read_buffer(&ts.resolve, 0, q as u64 * 8).map_err(backend)?;
            done.ticks = raw.chunks_exact(8).map(bytemuck::pod_read_unaligned::<u64>).collect();
        }
        for (id, size) in std::mem::take(&mut self.readbacks) {
            let b = self.buf(id)?;
            done.readbacks.push(self.ctx.read_buffer(b, 0, size).map_err(backend)?);
        }
        Ok(done)
    }

    fn finish(&mut self) -> Result<(), SolverError> {
        self.ctx.wait_idle().map_err(backend)
    }

    fn check(&mut self, what: &'static str) -> Result<(), SolverError> {
        self.ctx.check(what).map_err(backend)
    }
}

/// The wgpu solver of `variant` on the first adapter wgpu finds.
pub fn wgpu_solver(
    variant: impl Into<VariantSpec>,
    scene: clothlab_core::Scene,
    params: clothlab_core::SimParams,
    options: SolverOptions,
) -> Result<WgpuSolver, SolverError> {
    GpuSolver::new(WgpuEngine::new()?, variant, scene, params, options)
}
