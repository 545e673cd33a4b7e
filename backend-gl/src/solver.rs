//! The OpenGL engine: buffer objects with immutable storage, one compute program per
//! kernel (naga's GLSL of the kernel's WGSL), its storage blocks, uniform blocks and the
//! table texture bound per dispatch at the points the GLSL declares, `glMemoryBarrier`
//! where the generic solver places a barrier, `glQueryCounter` timestamps. GL runs
//! commands in the order they are issued, so a recorded write is a `glBufferSubData` and
//! a submission is a `glFlush`; readbacks are copied into a staging buffer when recorded
//! and read at the wait, as on Vulkan. The solver itself is
//! [`clothlab_engine::GpuSolver`]: [`GlSolver`] is it on this engine.

use std::collections::HashMap;

use clothlab_core::layout::{BindKind, Buf, TABLE_WIDTH};
use clothlab_core::solver::SolverError;
use clothlab_engine::gpu::{BufferId, Dispatch, Engine, EngineInfo, Finished};
use clothlab_engine::kernels::{self, KernelRef};
use clothlab_engine::{GpuSolver, SolverOptions, VariantSpec};

use crate::GlContext;
use crate::GlError;
use crate::raw::{DispatchDesc, TexFormat, Value};

/// The cloth solver on raw OpenGL.
pub type GlSolver = GpuSolver<GlEngine>;

/// `GL_SUBGROUP_FEATURE_{ARITHMETIC,SHUFFLE,SHUFFLE_RELATIVE}_BIT_KHR`.
const SUBGROUP_ARITHMETIC: u32 = 0x4;
const SUBGROUP_SHUFFLES: u32 = 0x10 | 0x20;
/// What a dispatch's writes must be made visible to before the next dispatch reads them
/// (storage blocks; the uniform blocks and the table are written only by GL commands,
/// which GL orders itself).
const DISPATCH_BARRIER: u32 = glow::SHADER_STORAGE_BARRIER_BIT;
/// Before a GL command reads or rewrites a buffer a dispatch wrote (clears, copies,
/// uploads, reads), and before the renderer draws from one.
const TRANSFER_BARRIER: u32 = glow::BUFFER_UPDATE_BARRIER_BIT
    | glow::VERTEX_ATTRIB_ARRAY_BARRIER_BIT
    | glow::ELEMENT_ARRAY_BARRIER_BIT
    | glow::SHADER_STORAGE_BARRIER_BIT;

fn backend(e: GlError) -> SolverError {
    match e {
        GlError::NoGl(_) => SolverError::NoAdapter(e.to_string()),
        e => SolverError::Driver(e.to_string()),
    }
}

/// A buffer of the GL engine (what the GL renderer draws from).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GlBuffer {
    pub(crate) index: usize,
    /// The context it lives in ([`crate::raw::Gl::id`]).
    pub(crate) context: u64,
    /// Its size, bytes.
    pub size: u64,
}

/// A built kernel: its program and what it binds where.
/// What it binds is resolved once, when it is built (the buffers are bound before any
/// kernel is built and never change), so a dispatch only walks these lists.
struct Program {
    index: usize,
    /// `(GL binding point, raw buffer)` of its storage blocks, per position parity.
    storage: [Vec<(u32, usize)>; 2],
    /// The same for its uniform blocks.
    uniform: [Vec<(u32, usize)>; 2],
    /// `(texture unit, raw texture)` of the table image and the distance fields' image,
    /// those it reads.
    texture: Vec<(u32, usize)>,
    /// Its immediates as uniforms: `(byte offset, kind, components)`, by location index.
    uniforms: Vec<(u32, char, u8)>,
}

/// The API's part of the OpenGL solver.
pub struct GlEngine {
    gl: GlContext,
    info: EngineInfo,
    buffers: Vec<GlBuffer>,
    sets: [Vec<(Buf, BufferId)>; 2],
    bound: bool,
    /// The table texture and its height.
    table: Option<(usize, u32)>,
    /// The bodies' distance fields as a 3-D texture (`sdf=image`).
    sdf: Option<usize>,
    programs: HashMap<KernelRef, Program>,
    /// Readback staging: (buffer, size); the cursor; what the frame's readbacks copied.
    staging: Option<GlBuffer>,
    cursor: u64,
    readbacks: Vec<(u64, u64)>,
    /// A dispatch wrote since the last transfer barrier.
    dirty: bool,
    /// The first error of a recording method (reported by the next submit or check).
    error: Option<GlError>,
}

impl GlEngine {
    /// An engine on a new headless OpenGL 4.5 core context.
    pub fn new() -> Result<Self, SolverError> {
        Self::with_context(&GlContext::headless().map_err(backend)?)
    }

    /// An engine in `ctx` (a window's context: its buffers are drawn by the renderer made
    /// in the same context, with no copy).
    pub fn with_context(ctx: &GlContext) -> Result<Self, SolverError> {
        let gl = ctx.clone();
        let l = gl.gl().limits();
        let subgroups = l.subgroup_features;
        let info = EngineInfo {
            api: "gl",
            adapter: ctx.adapter(),
            float_atomics: l.has("GL_NV_shader_atomic_float"),
            // GL has no push constants (naga would write them as plain uniforms).
            immediates: false,
            timestamps: true,
            timestamp_period_ns: 1.0,
            max_binding: l.storage_block_size,
            subgroup_arithmetic: subgroups & SUBGROUP_ARITHMETIC != 0,
            subgroup_shuffle: subgroups & (SUBGROUP_ARITHMETIC | SUBGROUP_SHUFFLES)
                == SUBGROUP_ARITHMETIC | SUBGROUP_SHUFFLES,
            // GL names no device type: Mesa's and Google's software renderers by name.
            cpu: ["llvmpipe", "softpipe", "SwiftShader"].iter().any(|r| l.renderer.contains(r)),
            table_image: true,
            // Desktop GL filters R32F textures (GL 4.5 core §8.17).
            sdf_image: true,
            workgroup_memory: l.shared_memory,
        };
        Ok(Self {
            gl,
            info,
            buffers: Vec::new(),
            sets: [Vec::new(), Vec::new()],
            bound: false,
            table: None,
            sdf: None,
            programs: HashMap::new(),
            staging: None,
            cursor: 0,
            readbacks: Vec::new(),
            dirty: false,
            error: None,
        })
    }

    /// The context it computes in (a renderer made in it draws its buffers).
    pub fn context(&self) -> &GlContext {
        &self.gl
    }

    /// The driver's limits and extensions, in lines (for `clothlab info`-like reports).
    pub fn describe(&self) -> String {
        let l = self.gl.gl().limits();
        format!(
            "{}; {} storage blocks per compute shader, {} MiB per block, {} KiB per uniform block; float atomics: {}; subgroups: {}; robust access: {}",
            self.info.adapter,
            l.storage_blocks,
            l.storage_block_size >> 20,
            l.uniform_block_size >> 10,
            if self.info.float_atomics { "GL_NV_shader_atomic_float" } else { "no" },
            if l.subgroup_size > 0 { format!("{} lanes", l.subgroup_size) } else { "no".into() },
            if self.gl.gl().robust() { "yes" } else { "no" },
        )
    }

    fn buf(&self, id: BufferId) -> Result<GlBuffer, SolverError> {
        self.buffers.get(id.0 as usize).copied().ok_or_else(|| SolverError::Invalid(format!("no GL buffer {}", id.0)))
    }

    /// Makes the writes of earlier dispatches visible to GL commands (once per run of
    /// dispatches).
    fn settle(&mut self) -> Result<(), GlError> {
        if self.dirty {
            self.gl.gl().memory_barrier(TRANSFER_BARRIER)?;
            self.dirty = false;
        }
        Ok(())
    }

    /// Keeps the first error of a method that cannot return one.
    fn note(&mut self, r: Result<(), GlError>) {
        if let Err(e) = r {
            self.error.get_or_insert(e);
        }
    }

    fn take_error(&mut self) -> Result<(), SolverError> {
        match self.error.take() {
            Some(e) => Err(backend(e)),
            None => Ok(()),
        }
    }

    /// The GLSL the driver compiles: naga's, with what naga leaves out for GL.
    fn patch(&self, text: &str) -> String {
        let l = self.gl.gl().limits();
        let mut out = String::with_capacity(text.len() + 128);
        for (i, line) in text.lines().enumerate() {
            // naga declares every subgroup extension for a module that uses any (the
            // statistics' shared code); a driver without them compiles a kernel that calls
            // none once the lines are gone (one that calls them fails, and is refused
            // before that by the caps).
            if line.starts_with("#extension GL_KHR_shader_subgroup") && l.subgroup_features == 0 {
                continue;
            }
            out.push_str(line);
            out.push('\n');
            // Float atomicAdd on storage buffers is GL_NV_shader_atomic_float's; naga
            // writes the call but not the extension line.
            if i == 0 && self.info.float_atomics {
                out.push_str("#extension GL_NV_shader_atomic_float : enable\n");
            }
        }
        out
    }
}

impl Engine for GlEngine {
    type Buffer = GlBuffer;

    fn info(&self) -> &EngineInfo {
        &self.info
    }

    fn create_buffer(
        &mut self,
        _buf: Buf,
        _label: &str,
        contents: &[u8],
        _vertex: bool,
    ) -> Result<BufferId, SolverError> {
        let index = self.gl.gl().create_buffer(contents).map_err(backend)?;
        let size = self.gl.gl().buffer_size(index).map_err(backend)?;
        self.buffers.push(GlBuffer { index, size, context: self.gl.gl().id() });
        Ok(BufferId(self.buffers.len() as u32 - 1))
    }

    fn buffer(&self, id: BufferId) -> &GlBuffer {
        &self.buffers[id.0 as usize]
    }

    /// The table as an RGBA32UI texture read with `texelFetch` (the thesis's texture
    /// memory), rewritten in place when the constants change.
    fn set_table_image(&mut self, texels: &[[u32; 4]], height: u32) -> Result<(), SolverError> {
        let max = self.gl.gl().limits().texture_size;
        if height > max {
            return Err(SolverError::Unsupported(format!(
                "table=image: this grid's spring table needs a {TABLE_WIDTH}×{height} image, taller than the {max} texels {} allows; use table=storage or table=uniform",
                self.info.adapter
            )));
        }
        if self.table.is_none_or(|(_, h)| h != height) {
            if self.bound {
                return Err(SolverError::Invalid("the spring-table image cannot change size once bound".into()));
            }
            let t = self.gl.gl().create_texture(TexFormat::Rgba32ui, TABLE_WIDTH, height, 1).map_err(backend)?;
            self.table = Some((t, height));
        }
        let (t, _) = self.table.expect("made above");
        let mut all = texels.to_vec();
        all.resize((TABLE_WIDTH * height) as usize, [0; 4]);
        self.gl.gl().write_texture(t, bytemuck::cast_slice(&all)).map_err(backend)?;
        self.gl.gl().check("uploading the spring-table image").map_err(backend)
    }

    /// The fields as an `R32F` 3-D texture, filtered linearly and clamped to the edge (the
    /// thesis's texture memory, where the hardware interpolates), written once.
    fn set_sdf_image(&mut self, values: &[f32], dims: [u32; 3]) -> Result<(), SolverError> {
        if self.bound || self.sdf.is_some() {
            return Err(SolverError::Invalid(
                "the distance-field image is made once, before the buffers are bound".into(),
            ));
        }
        let [w, h, d] = dims;
        let t = self.gl.gl().create_volume(w, h, d, values).map_err(|e| {
            SolverError::Unsupported(format!("sdf=image on {}: {e}; use sdf=storage", self.info.adapter))
        })?;
        self.sdf = Some(t);
        self.gl.gl().check("uploading the distance-field image").map_err(backend)
    }

    fn bind(&mut self, sets: [Vec<(Buf, BufferId)>; 2]) -> Result<(), SolverError> {
        for set in &sets {
            for &(_, id) in set {
                self.buf(id)?;
            }
        }
        self.sets = sets;
        self.bound = true;
        Ok(())
    }

    fn build(&mut self, k: KernelRef, immediates: u32) -> Result<(), SolverError> {
        if self.programs.contains_key(&k) {
            return Ok(());
        }
        let name = k.shader_name();
        let refuse = |reason: String| SolverError::Shader { kernel: name.clone(), reason };
        if !matches!(k.def.source, kernels::Source::Builtin) && !self.gl.gl().robust() {
            return Err(refuse(format!(
                "{} gives no robust buffer access: kernels from outside are refused on it",
                self.info.adapter
            )));
        }
        if !self.bound {
            return Err(SolverError::Invalid("kernels are built after the buffers are bound".into()));
        }
        let glsl = k.glsl()?;
        let mut storage: [Vec<(u32, usize)>; 2] = Default::default();
        let mut uniform: [Vec<(u32, usize)>; 2] = Default::default();
        let mut texture = Vec::new();
        for &(binding, point) in &glsl.points {
            let point = u32::from(point);
            let buf = Buf::from_binding(binding).ok_or_else(|| refuse(format!("binding {binding} is no buffer")))?;
            if buf.kind() == BindKind::Image {
                let (t, _) = self.table.ok_or_else(|| refuse("built without the table image".into()))?;
                texture.push((point, t));
                continue;
            }
            if buf.kind() == BindKind::Volume {
                let t = self.sdf.ok_or_else(|| refuse("built without the distance-field image".into()))?;
                texture.push((point, t));
                continue;
            }
            for parity in 0..2 {
                let id = self.sets[parity].iter().find(|(b, _)| *b == buf).map(|&(_, id)| id).ok_or_else(|| {
                    refuse(format!("it reads binding {binding} ({buf:?}), which the solver did not bind"))
                })?;
                let raw = self.buf(id)?.index;
                let list = if buf.kind() == BindKind::Uniform { &mut uniform } else { &mut storage };
                list[parity].push((point, raw));
            }
        }
        let storage_blocks = storage[0].len();
        let most = self.gl.gl().limits().storage_blocks as usize;
        if storage_blocks > most {
            return Err(refuse(format!(
                "{storage_blocks} shader storage blocks, more than the {most} {} allows a compute shader",
                self.info.adapter
            )));
        }
        let covered: u32 = glsl.uniforms.iter().map(|u| u.1 + 4 * u.3 as u32).max().unwrap_or(0);
        if immediates > covered {
            return Err(refuse(format!("{immediates} bytes of immediates, but its GLSL sets only {covered}")));
        }
        let names: Vec<&str> = glsl.uniforms.iter().map(|u| u.0.as_str()).collect();
        let text = self.patch(&glsl.text);
        let index = self.gl.gl().program(&text, &names).map_err(|log| refuse(format!("the GL driver: {log}")))?;
        let uniforms = glsl.uniforms.iter().map(|u| (u.1, u.2, u.3)).collect();
        self.programs.insert(k, Program { index, storage, uniform, texture, uniforms });
        self.gl.gl().check("building a kernel").map_err(backend)
    }

    fn kernels(&self) -> Vec<KernelRef> {
        self.programs.keys().copied().collect()
    }

    fn write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError> {
        let b = self.buf(id)?;
        self.settle().map_err(backend)?;
        self.gl.gl().write(b.index, 0, bytes).map_err(backend)
    }

    fn read(&mut self, id: BufferId) -> Result<Vec<u8>, SolverError> {
        let b = self.buf(id)?;
        self.settle().map_err(backend)?;
        self.gl.gl().read(b.index, 0, b.size).map_err(backend)
    }

    fn begin(&mut self, _index: usize, _queries: u32) -> Result<(), SolverError> {
        Ok(())
    }

    /// glBufferSubData: GL orders it after what was issued before.
    fn record_write(&mut self, id: BufferId, bytes: &[u8]) -> Result<(), SolverError> {
        self.write(id, bytes)
    }

    fn clear(&mut self, id: BufferId) {
        let r = self.buf(id).map_err(|_| GlError::Invalid("clearing no buffer")).and_then(|b| {
            self.settle()?;
            self.gl.gl().clear(b.index)
        });
        self.note(r);
    }

    fn copy(&mut self, src: BufferId, dst: BufferId, size: u64) {
        let r = match (self.buf(src), self.buf(dst)) {
            (Ok(a), Ok(b)) => {
                self.settle().and_then(|_| self.gl.gl().copy(a.index, 0, b.index, 0, size.min(a.size).min(b.size)))
            }
            _ => Err(GlError::Invalid("copying no buffer")),
        };
        self.note(r);
    }

    /// glMemoryBarrier for storage-block reads after storage-block writes; GL orders its
    /// own commands after the draws before them, so `after_all` needs nothing more.
    fn barrier(&mut self, _after_all: bool) {
        let r = self.gl.gl().memory_barrier(DISPATCH_BARRIER);
        self.note(r);
    }

    fn dispatch(&mut self, d: &Dispatch<'_>) {
        let Some(p) = self.programs.get(&d.kernel) else {
            self.note(Err(GlError::Invalid("a dispatch of a kernel never built")));
            return;
        };
        // The immediates as uniform values (only the statistics kernels have any).
        let word = |at: usize| d.immediates.get(at..at + 4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        let values: Vec<(usize, Value)> = p
            .uniforms
            .iter()
            .enumerate()
            .filter_map(|(i, &(offset, kind, n))| {
                let mut u = [0u32; 4];
                for (c, x) in u.iter_mut().enumerate().take(n as usize) {
                    *x = word(offset as usize + 4 * c)?;
                }
                Some((
                    i,
                    match kind {
                        'u' => Value::U(n, u),
                        'i' => Value::I(n, u.map(|x| x as i32)),
                        _ => Value::F(n, u.map(f32::from_bits)),
                    },
                ))
            })
            .collect();
        let parity = d.parity & 1;
        let desc = DispatchDesc {
            program: p.index,
            storage: &p.storage[parity],
            uniform: &p.uniform[parity],
            textures: &p.texture,
            values: &values,
            groups: d.groups,
        };
        let r = (|| {
            if let Some(q) = d.timestamps {
                self.gl.gl().timestamp(q)?;
            }
            self.gl.gl().dispatch(&desc)?;
            if let Some(q) = d.timestamps {
                self.gl.gl().timestamp(q + 1)?;
            }
            Ok(())
        })();
        self.dirty = true;
        self.note(r);
    }

    /// A copy into the staging buffer now, read at the wait (the GPU need not stop here).
    fn readback(&mut self, id: BufferId, size: u64) -> Result<(), SolverError> {
        let b = self.buf(id)?;
        let size = size.min(b.size);
        let at = self.cursor.next_multiple_of(256);
        let need = at + size;
        if self.staging.is_none_or(|s| s.size < need) {
            if !self.readbacks.is_empty() {
                return Err(SolverError::Driver("a frame's readbacks outgrew the staging buffer".into()));
            }
            let index = self.gl.gl().create_buffer(&vec![0u8; need.max(64 * 1024) as usize]).map_err(backend)?;
            let size = self.gl.gl().buffer_size(index).map_err(backend)?;
            self.staging = Some(GlBuffer { index, size, context: self.gl.gl().id() });
        }
        let s = self.staging.expect("made above");
        self.settle().map_err(backend)?;
        self.gl.gl().copy(b.index, 0, s.index, at, size).map_err(backend)?;
        self.cursor = need;
        self.readbacks.push((at, size));
        Ok(())
    }

    /// glFlush: the commands issued so far start.
    fn submit(&mut self, _last: bool) -> Result<(), SolverError> {
        self.take_error()?;
        self.gl.gl().flush().map_err(backend)
    }

    fn wait(&mut self, queries: u32) -> Result<Finished, SolverError> {
        self.take_error()?;
        let mut done = Finished::default();
        if queries > 0 {
            done.ticks = self.gl.gl().timestamps(queries).map_err(backend)?;
        }
        if !self.readbacks.is_empty() {
            let s = self.staging.expect("readbacks copy into staging");
            for (at, size) in std::mem::take(&mut self.readbacks) {
                done.readbacks.push(self.gl.gl().read(s.index, at, size).map_err(backend)?);
            }
        }
        self.cursor = 0;
        Ok(done)
    }

    fn finish(&mut self) -> Result<(), SolverError> {
        self.gl.gl().finish().map_err(backend)
    }

    fn check(&mut self, what: &'static str) -> Result<(), SolverError> {
        self.take_error()?;
        self.gl.gl().check(what).map_err(backend)
    }
}

impl Drop for GlEngine {
    /// In a context others use (a window's), the engine's objects are deleted with it;
    /// a context of its own frees them all when it goes.
    fn drop(&mut self) {
        if !self.gl.shared() {
            return;
        }
        let gl = self.gl.gl();
        let buffers = self.buffers.iter().chain(self.staging.as_ref()).map(|b| gl.delete_buffer(b.index));
        let programs = self.programs.values().map(|p| gl.delete_program(p.index));
        let table = self.table.map(|(t, _)| gl.delete_texture(t));
        let errors: Vec<GlError> = buffers.chain(programs).chain(table).filter_map(Result::err).collect();
        if let Some(e) = errors.first() {
            log::warn!("deleting a GL solver's objects: {e}");
        }
    }
}

/// The OpenGL solver of `variant` on a new headless context.
pub fn gl_solver(
    variant: impl Into<VariantSpec>,
    scene: clothlab_core::Scene,
    params: clothlab_core::SimParams,
    options: SolverOptions,
) -> Result<GlSolver, SolverError> {
    GpuSolver::new(GlEngine::new()?, variant, scene, params, options)
}
