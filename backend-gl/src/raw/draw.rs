//! Drawing, for the GL renderer: textures as attachments, framebuffers, sampler objects,
//! vertex arrays, index buffers, graphics programs, draws, the MSAA resolve and pixel
//! reads. Part of the raw layer, under its rules (see the parent module): objects are
//! indices into the context's tables, and every draw is checked before it is issued —
//! each vertex buffer holds every vertex the draw can fetch (an index buffer's largest
//! index is recorded when it is made, and its contents never change), the textures are
//! single-sampled, the framebuffer is complete.

use glow::HasContext;

use super::{Gl, GlError, TextureObj};

/// glClipControl (GL 4.5; not in glow): `(origin, depth)`.
pub(super) type ClipControl = unsafe extern "system" fn(u32, u32);
/// glProvokingVertex (GL 3.2; not in glow): `(mode)`.
pub(super) type ProvokingVertex = unsafe extern "system" fn(u32);
const FIRST_VERTEX_CONVENTION: u32 = 0x8E4D;
const LAST_VERTEX_CONVENTION: u32 = 0x8E4E;
const LOWER_LEFT: u32 = 0x8CA1;
const UPPER_LEFT: u32 = 0x8CA2;
const NEGATIVE_ONE_TO_ONE: u32 = 0x935E;
const ZERO_TO_ONE: u32 = 0x935F;

/// What a texture holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TexFormat {
    /// Four u32 (the spring table).
    Rgba32ui,
    /// sRGB-encoded RGBA8 (colour targets, the fabric).
    Srgba8,
    /// One u32 (picking ids).
    R32ui,
    /// 32-bit float depth.
    Depth32f,
    /// One 32-bit float, filtered (the bodies' distance fields, a 3-D texture).
    R32f,
}

impl TexFormat {
    pub(super) fn internal(self) -> u32 {
        match self {
            TexFormat::Rgba32ui => glow::RGBA32UI,
            TexFormat::Srgba8 => glow::SRGB8_ALPHA8,
            TexFormat::R32ui => glow::R32UI,
            TexFormat::Depth32f => glow::DEPTH_COMPONENT32F,
            TexFormat::R32f => glow::R32F,
        }
    }

    pub(super) fn integer(self) -> bool {
        matches!(self, TexFormat::Rgba32ui | TexFormat::R32ui)
    }
}

/// What a draw assembles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prim {
    /// Triangle lists.
    Triangles,
    /// Line lists.
    Lines,
    /// Points.
    Points,
}

/// A colour attachment's clear value.
#[derive(Debug, Clone, Copy)]
pub enum Clear {
    /// A linear colour (encoded to sRGB for an sRGB target).
    Color([f32; 4]),
    /// Integers.
    Uint([u32; 4]),
}

/// One vertex attribute: shader location, components (1 to 4, each 4 bytes), integer
/// (u32) or float, byte offset in the vertex.
#[derive(Debug, Clone, Copy)]
pub struct VertexAttr {
    /// `layout(location = …)`.
    pub location: u32,
    /// 1 to 4.
    pub components: u8,
    /// u32 components (else f32).
    pub integer: bool,
    /// Byte offset in the vertex.
    pub offset: u32,
}

/// The vertices of one buffer binding: their stride and attributes.
#[derive(Debug, Clone, Copy)]
pub struct VertexLayout<'a> {
    /// Bytes from one vertex to the next.
    pub stride: u32,
    /// What is read of each vertex.
    pub attrs: &'a [VertexAttr],
}

/// One draw: where, with which program and inputs.
pub struct DrawDesc<'a> {
    /// A framebuffer from [`Gl::create_framebuffer`].
    pub framebuffer: usize,
    /// A program from [`Gl::graphics_program`].
    pub program: usize,
    /// A vertex array from [`Gl::create_vertex_array`].
    pub vertex_array: usize,
    /// The buffer of each of its bindings, in order.
    pub vertices: &'a [usize],
    /// An index buffer (all of its indices are drawn), or `None`: `count` vertices.
    pub indices: Option<usize>,
    /// Vertices drawn without an index buffer.
    pub count: u32,
    /// What is assembled.
    pub prim: Prim,
    /// `(binding point, buffer)` of uniform blocks.
    pub uniform: &'a [(u32, usize)],
    /// `(texture unit, texture, sampler)`.
    pub textures: &'a [(u32, usize, usize)],
    /// Polygon offset `(slope factor, constant units)`, if any.
    pub depth_bias: Option<(f32, f32)>,
}

struct IndexObj {
    name: glow::NativeBuffer,
    count: u32,
    max: u32,
}

#[derive(Clone, Copy)]
struct FramebufferObj {
    name: glow::NativeFramebuffer,
    width: u32,
    height: u32,
    samples: u32,
    color: Option<TexFormat>,
}

struct VertexArrayObj {
    name: glow::NativeVertexArray,
    strides: Vec<u32>,
}

/// The renderer's objects of a context.
#[derive(Default)]
pub(super) struct DrawObjects {
    // Each `None` once deleted (indices are never reused).
    indices: Vec<Option<IndexObj>>,
    samplers: Vec<Option<glow::NativeSampler>>,
    framebuffers: Vec<Option<FramebufferObj>>,
    vertex_arrays: Vec<Option<VertexArrayObj>>,
}

fn gl_err(what: &'static str) -> impl Fn(String) -> GlError {
    move |reason| GlError::Gl { what, reason }
}

impl Gl {
    fn fb(&self, i: usize) -> Result<FramebufferObj, GlError> {
        self.objs.borrow().draw.framebuffers.get(i).copied().flatten().ok_or(GlError::Invalid("no such framebuffer"))
    }

    /// A buffer of `indices` for indexed draws; its contents never change, so a draw
    /// knows the largest vertex it can fetch.
    pub fn create_index_buffer(&self, indices: &[u32]) -> Result<usize, GlError> {
        let bytes: &[u8] = bytemuck::cast_slice(indices);
        let size = i32::try_from(bytes.len().max(4)).map_err(|_| GlError::Invalid("an index buffer over 2 GiB"))?;
        let mut data = bytes.to_vec();
        data.resize(size as usize, 0);
        let gl = self.cur()?;
        // SAFETY: the context is current; immutable storage (no update flag: the
        // contents cannot change) of `size` bytes copied from `data`.
        let name = unsafe {
            let name = gl.create_buffer().map_err(gl_err("creating an index buffer"))?;
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, Some(name));
            gl.buffer_storage(glow::COPY_WRITE_BUFFER, size, Some(&data), 0);
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, None);
            name
        };
        let max = indices.iter().copied().max().unwrap_or(0);
        let mut o = self.objs.borrow_mut();
        o.draw.indices.push(Some(IndexObj { name, count: indices.len() as u32, max }));
        Ok(o.draw.indices.len() - 1)
    }

    /// A sampler object: linear filtering; a depth comparison (≤) clamped to the edge
    /// when `compare`, else repeating.
    pub fn create_sampler(&self, compare: bool) -> Result<usize, GlError> {
        let gl = self.cur()?;
        // SAFETY: the context is current; parameters of a sampler made here.
        let s = unsafe {
            let s = gl.create_sampler().map_err(gl_err("creating a sampler"))?;
            let wrap = if compare { glow::CLAMP_TO_EDGE } else { glow::REPEAT } as i32;
            for p in [glow::TEXTURE_WRAP_S, glow::TEXTURE_WRAP_T] {
                gl.sampler_parameter_i32(s, p, wrap);
            }
            gl.sampler_parameter_i32(s, glow::TEXTURE_MIN_FILTER, glow::LINEAR as i32);
            gl.sampler_parameter_i32(s, glow::TEXTURE_MAG_FILTER, glow::LINEAR as i32);
            if compare {
                gl.sampler_parameter_i32(s, glow::TEXTURE_COMPARE_MODE, glow::COMPARE_REF_TO_TEXTURE as i32);
                gl.sampler_parameter_i32(s, glow::TEXTURE_COMPARE_FUNC, glow::LEQUAL as i32);
            }
            s
        };
        let mut o = self.objs.borrow_mut();
        o.draw.samplers.push(Some(s));
        Ok(o.draw.samplers.len() - 1)
    }

    /// A framebuffer drawing into texture `color` (if any) and depth texture `depth`, of
    /// one size and sample count; refused unless GL calls it complete.
    pub fn create_framebuffer(&self, color: Option<usize>, depth: usize) -> Result<usize, GlError> {
        let d = self.tex(depth)?;
        let c = color.map(|c| self.tex(c)).transpose()?;
        if d.format != TexFormat::Depth32f {
            return Err(GlError::Invalid("a depth attachment that is not a depth texture"));
        }
        if let Some(c) = c
            && (c.format == TexFormat::Depth32f || (c.width, c.height, c.samples) != (d.width, d.height, d.samples))
        {
            return Err(GlError::Invalid("attachments of different sizes or sample counts"));
        }
        let target = |t: &TextureObj| if t.samples > 1 { glow::TEXTURE_2D_MULTISAMPLE } else { glow::TEXTURE_2D };
        let gl = self.cur()?;
        // SAFETY: the context is current; the framebuffer is made here and the textures
        // are this context's (checked above).
        let (name, status) = unsafe {
            let f = gl.create_framebuffer().map_err(gl_err("creating a framebuffer"))?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(f));
            gl.framebuffer_texture_2d(glow::FRAMEBUFFER, glow::DEPTH_ATTACHMENT, target(&d), Some(d.name), 0);
            match c {
                Some(c) => {
                    gl.framebuffer_texture_2d(glow::FRAMEBUFFER, glow::COLOR_ATTACHMENT0, target(&c), Some(c.name), 0);
                    gl.draw_buffer(glow::COLOR_ATTACHMENT0);
                    gl.read_buffer(glow::COLOR_ATTACHMENT0);
                }
                None => {
                    gl.draw_buffer(glow::NONE);
                    gl.read_buffer(glow::NONE);
                }
            }
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            (f, status)
        };
        if status != glow::FRAMEBUFFER_COMPLETE {
            // SAFETY: the context is current; the framebuffer was made above.
            unsafe { gl.delete_framebuffer(name) };
            return Err(GlError::Gl { what: "making a framebuffer", reason: format!("status 0x{status:04X}") });
        }
        let fb =
            FramebufferObj { name, width: d.width, height: d.height, samples: d.samples, color: c.map(|c| c.format) };
        let mut o = self.objs.borrow_mut();
        o.draw.framebuffers.push(Some(fb));
        Ok(o.draw.framebuffers.len() - 1)
    }

    /// Deletes framebuffer `i` (its index is not reused).
    pub fn delete_framebuffer(&self, i: usize) -> Result<(), GlError> {
        let f = self.fb(i)?;
        let gl = self.cur()?;
        // SAFETY: the context is current; the name is this context's and forgotten here.
        unsafe { gl.delete_framebuffer(f.name) };
        self.objs.borrow_mut().draw.framebuffers[i] = None;
        Ok(())
    }

    /// Deletes index buffers, samplers and vertex arrays (their indices are not reused;
    /// unknown ones are skipped).
    pub fn delete_draw_objects(
        &self,
        indices: &[usize],
        samplers: &[usize],
        vertex_arrays: &[usize],
    ) -> Result<(), GlError> {
        let gl = self.cur()?;
        let mut o = self.objs.borrow_mut();
        let d = &mut o.draw;
        // SAFETY: the context is current; each name is this context's and is forgotten
        // here (taken out of its table).
        unsafe {
            for &i in indices {
                if let Some(x) = d.indices.get_mut(i).and_then(Option::take) {
                    gl.delete_buffer(x.name);
                }
            }
            for &i in samplers {
                if let Some(x) = d.samplers.get_mut(i).and_then(Option::take) {
                    gl.delete_sampler(x);
                }
            }
            for &i in vertex_arrays {
                if let Some(x) = d.vertex_arrays.get_mut(i).and_then(Option::take) {
                    gl.delete_vertex_array(x.name);
                }
            }
        }
        Ok(())
    }

    /// Copies the colour of single-sampled framebuffer `fb` into the window's default
    /// framebuffer of `width × height`, scaled to fit and turned right side up (GL's
    /// window rows go bottom up), bytes as they are (the window's framebuffer is not
    /// sRGB: the sRGB bytes are what it should show).
    pub fn blit_to_window(&self, fb: usize, width: u32, height: u32) -> Result<(), GlError> {
        let f = self.fb(fb)?;
        if !self.has_window() || f.samples != 1 || f.color.is_none() {
            return Err(GlError::Invalid("a blit to the window from no colour or with no window"));
        }
        let gl = self.cur()?;
        // SAFETY: the context is current; the framebuffer is this context's; the window's
        // default framebuffer (0) exists (the context draws into a window surface).
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(f.name));
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
            gl.disable(glow::FRAMEBUFFER_SRGB);
            gl.disable(glow::SCISSOR_TEST);
            let (w, h) = (width as i32, height as i32);
            gl.blit_framebuffer(
                0,
                0,
                f.width as i32,
                f.height as i32,
                0,
                h,
                w,
                0,
                glow::COLOR_BUFFER_BIT,
                glow::LINEAR,
            );
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
            gl.viewport(0, 0, w, h);
        }
        Ok(())
    }

    /// The window's default framebuffer's `width × height` pixels, RGBA8, first row at the
    /// top (a screenshot of what is about to be shown).
    pub fn read_window(&self, width: u32, height: u32) -> Result<Vec<u8>, GlError> {
        if !self.has_window() {
            return Err(GlError::Invalid("reading the window of a context with no window"));
        }
        let row = width as usize * 4;
        let mut out = vec![0u8; row * height as usize];
        let gl = self.cur()?;
        // SAFETY: the context is current and draws into a window; GL writes
        // width×height RGBA8 pixels in rows of width×4 bytes (alignment 4), exactly
        // `out`'s length; pixels outside the window read as undefined values, not memory.
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
            gl.read_buffer(glow::BACK);
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            gl.read_pixels(
                0,
                0,
                width as i32,
                height as i32,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut out)),
            );
        }
        // Bottom-up rows to top-down.
        let flipped = out.chunks_exact(row).rev().flatten().copied().collect();
        Ok(flipped)
    }

    /// A vertex array of `layouts` (binding `i` is `layouts[i]`); an attribute reaching
    /// past its stride is refused.
    pub fn create_vertex_array(&self, layouts: &[VertexLayout<'_>]) -> Result<usize, GlError> {
        for l in layouts {
            if l.attrs.iter().any(|a| !(1..=4).contains(&a.components) || a.offset + 4 * a.components as u32 > l.stride)
            {
                return Err(GlError::Invalid("a vertex attribute past its stride"));
            }
        }
        let gl = self.cur()?;
        // SAFETY: the context is current; the vertex array is made here and given
        // formats only (buffers are bound per draw).
        let name = unsafe {
            let v = gl.create_vertex_array().map_err(gl_err("creating a vertex array"))?;
            gl.bind_vertex_array(Some(v));
            for (b, l) in layouts.iter().enumerate() {
                for a in l.attrs {
                    gl.enable_vertex_attrib_array(a.location);
                    if a.integer {
                        gl.vertex_attrib_format_i32(a.location, a.components as i32, glow::UNSIGNED_INT, a.offset);
                    } else {
                        gl.vertex_attrib_format_f32(a.location, a.components as i32, glow::FLOAT, false, a.offset);
                    }
                    gl.vertex_attrib_binding(a.location, b as u32);
                }
            }
            gl.bind_vertex_array(None);
            v
        };
        let mut o = self.objs.borrow_mut();
        o.draw.vertex_arrays.push(Some(VertexArrayObj { name, strides: layouts.iter().map(|l| l.stride).collect() }));
        Ok(o.draw.vertex_arrays.len() - 1)
    }

    /// Compiles and links a vertex shader and, unless depth only, a fragment shader;
    /// the error is the driver's log.
    pub fn graphics_program(&self, vs: &str, fs: Option<&str>) -> Result<usize, String> {
        let mut stages = vec![(glow::VERTEX_SHADER, vs)];
        stages.extend(fs.map(|f| (glow::FRAGMENT_SHADER, f)));
        self.link(&stages, &[])
    }

    /// Clears framebuffer `fb`: its colour to `color` (if it has one) and its depth to 1.
    pub fn clear_target(&self, fb: usize, color: Clear) -> Result<(), GlError> {
        let f = self.fb(fb)?;
        let gl = self.cur()?;
        // SAFETY: the context is current; the framebuffer is this context's; the clear
        // value's kind matches the attachment's (checked).
        unsafe {
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(f.name));
            gl.enable(glow::FRAMEBUFFER_SRGB);
            gl.depth_mask(true);
            match (f.color, color) {
                (Some(TexFormat::Srgba8), Clear::Color(c)) => gl.clear_buffer_f32_slice(glow::COLOR, 0, &c),
                (Some(TexFormat::R32ui), Clear::Uint(c)) => gl.clear_buffer_u32_slice(glow::COLOR, 0, &c),
                (None, _) => {}
                _ => {
                    gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
                    return Err(GlError::Invalid("a clear value of another kind than the target"));
                }
            }
            gl.clear_buffer_f32_slice(glow::DEPTH, 0, &[1.0]);
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
        }
        Ok(())
    }

    /// Issues draw `d` as wgpu and Vulkan would: depth test `<`, no culling,
    /// counter-clockwise front faces, their clip space (y up with the first row at the
    /// top, depth 0 to 1) and their provoking vertex (the first: flat values, such as
    /// picking's particle ids, come from it). GL's defaults are set back after it.
    pub fn draw(&self, d: &DrawDesc<'_>) -> Result<(), GlError> {
        let (Some(clip), Some(provoking)) = (self.clip_control, self.provoking_vertex) else {
            return Err(GlError::NoGl("the context has no glClipControl or glProvokingVertex (GL 4.5)".into()));
        };
        let f = self.fb(d.framebuffer)?;
        let o = self.objs.borrow();
        let program = o.program(d.program).ok_or(GlError::Invalid("no such GL program"))?.program;
        let vao = o.draw.vertex_arrays.get(d.vertex_array).and_then(Option::as_ref);
        let vao = vao.ok_or(GlError::Invalid("no such vertex array"))?;
        let index = d
            .indices
            .map(|i| o.draw.indices.get(i).and_then(Option::as_ref).ok_or(GlError::Invalid("no such index buffer")))
            .transpose()?;
        // Every vertex the draw can fetch must lie in every bound buffer.
        let fetched = match index {
            Some(ix) if ix.count > 0 => ix.max as u64 + 1,
            Some(_) => 0,
            None => d.count as u64,
        };
        if d.vertices.len() != vao.strides.len() {
            return Err(GlError::Invalid("a draw with another number of vertex buffers than its vertex array"));
        }
        for (&b, &stride) in d.vertices.iter().zip(&vao.strides) {
            let buf = o.buffer(b).ok_or(GlError::Invalid("no such GL buffer"))?;
            if fetched * stride as u64 > buf.size {
                return Err(GlError::Invalid("a draw fetching vertices past a buffer's end"));
            }
        }
        if d.uniform.iter().any(|&(_, b)| o.buffer(b).is_none()) {
            return Err(GlError::Invalid("no such GL buffer"));
        }
        let mut textures = Vec::with_capacity(d.textures.len());
        for &(unit, t, s) in d.textures {
            let t = o.textures.get(t).copied().flatten().filter(|t| t.samples == 1);
            let t = t.ok_or(GlError::Invalid("no such single-sampled texture"))?;
            let s = o.draw.samplers.get(s).copied().flatten().ok_or(GlError::Invalid("no such sampler"))?;
            textures.push((unit, t.name, s));
        }
        let mode = match d.prim {
            Prim::Triangles => glow::TRIANGLES,
            Prim::Lines => glow::LINES,
            Prim::Points => glow::POINTS,
        };
        let gl = self.cur()?;
        // SAFETY: the context is current; every object is this context's (checked
        // above), every vertex fetched lies in its buffer (checked above), the index
        // count is the index buffer's own; glClipControl and glProvokingVertex have
        // their core signatures and take valid enums.
        unsafe {
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(f.name));
            gl.viewport(0, 0, f.width as i32, f.height as i32);
            clip(UPPER_LEFT, ZERO_TO_ONE);
            provoking(FIRST_VERTEX_CONVENTION);
            gl.enable(glow::FRAMEBUFFER_SRGB);
            gl.enable(glow::DEPTH_TEST);
            gl.depth_func(glow::LESS);
            gl.depth_mask(true);
            gl.disable(glow::CULL_FACE);
            gl.disable(glow::BLEND);
            gl.disable(glow::SCISSOR_TEST);
            gl.front_face(glow::CCW);
            match d.depth_bias {
                Some((slope, units)) => {
                    gl.enable(glow::POLYGON_OFFSET_FILL);
                    gl.polygon_offset(slope, units);
                }
                None => gl.disable(glow::POLYGON_OFFSET_FILL),
            }
            gl.use_program(Some(program));
            gl.bind_vertex_array(Some(vao.name));
            for (b, (&buf, &stride)) in d.vertices.iter().zip(&vao.strides).enumerate() {
                gl.bind_vertex_buffer(b as u32, o.buffer(buf).map(|x| x.name), 0, stride as i32);
            }
            for &(pt, b) in d.uniform {
                gl.bind_buffer_base(glow::UNIFORM_BUFFER, pt, o.buffer(b).map(|x| x.name));
            }
            for &(unit, t, s) in &textures {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, Some(t));
                gl.bind_sampler(unit, Some(s));
            }
            match index {
                Some(ix) => {
                    gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, Some(ix.name));
                    gl.draw_elements(mode, ix.count as i32, glow::UNSIGNED_INT, 0);
                }
                None => {
                    gl.bind_buffer(glow::ELEMENT_ARRAY_BUFFER, None);
                    gl.draw_arrays(mode, 0, d.count as i32);
                }
            }
            gl.bind_vertex_array(None);
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
            clip(LOWER_LEFT, NEGATIVE_ONE_TO_ONE);
            provoking(LAST_VERTEX_CONVENTION);
        }
        Ok(())
    }

    /// Resolves (or copies) the colour of framebuffer `src` into `dst`, of one size.
    pub fn resolve(&self, src: usize, dst: usize) -> Result<(), GlError> {
        let (a, b) = (self.fb(src)?, self.fb(dst)?);
        if (a.width, a.height) != (b.width, b.height) || a.color.is_none() || a.color != b.color || b.samples != 1 {
            return Err(GlError::Invalid("a resolve between framebuffers of different sizes or formats"));
        }
        let gl = self.cur()?;
        // SAFETY: the context is current; both framebuffers are this context's, of one
        // size and colour format (checked).
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(a.name));
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(b.name));
            gl.enable(glow::FRAMEBUFFER_SRGB);
            let (w, h) = (a.width as i32, a.height as i32);
            gl.blit_framebuffer(0, 0, w, h, 0, 0, w, h, glow::COLOR_BUFFER_BIT, glow::NEAREST);
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, None);
        }
        Ok(())
    }

    /// The `w`×`h` pixels at `(x, y)` (first row at the top, as drawn) of single-sampled
    /// framebuffer `fb`'s colour: 4 bytes a pixel (sRGB RGBA8, or a little-endian u32).
    pub fn read_pixels(&self, fb: usize, x: u32, y: u32, w: u32, h: u32) -> Result<Vec<u8>, GlError> {
        let f = self.fb(fb)?;
        let (format, kind) = match f.color {
            Some(TexFormat::Srgba8) => (glow::RGBA, glow::UNSIGNED_BYTE),
            Some(TexFormat::R32ui) => (glow::RED_INTEGER, glow::UNSIGNED_INT),
            _ => return Err(GlError::Invalid("reading pixels of a framebuffer without a colour")),
        };
        if f.samples != 1
            || x.checked_add(w).is_none_or(|e| e > f.width)
            || y.checked_add(h).is_none_or(|e| e > f.height)
        {
            return Err(GlError::Invalid("reading pixels outside the framebuffer"));
        }
        let mut out = vec![0u8; w as usize * h as usize * 4];
        let gl = self.cur()?;
        // SAFETY: the context is current; GL writes w×h pixels of 4 bytes in rows of
        // w×4 bytes (pack alignment 4 divides them), exactly `out`'s length; the
        // rectangle lies inside the framebuffer (checked).
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(f.name));
            gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            gl.read_pixels(
                x as i32,
                y as i32,
                w as i32,
                h as i32,
                format,
                kind,
                glow::PixelPackData::Slice(Some(&mut out)),
            );
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        }
        Ok(out)
    }
}
