//! The scene renderer on raw OpenGL: the same passes, shaders (render.wgsl, as naga's
//! GLSL per entry point) and look as the wgpu and Vulkan renderers — a shadow pass from
//! the light, a lit main pass with 4× MSAA into an sRGB target, the cloth as triangles,
//! lines or points, and a picking pass — drawing the cloth straight from the GL solver's
//! position and normal buffers (the thesis's shared buffers: a shader storage block for
//! the kernels is a vertex buffer for the draw, no copy).

use clothlab_core::grid::{ClothState, ClothTopology};
use clothlab_core::render::{Frame, SAMPLES, SHADOW_SIZE, SKY, StaticVertex, cloth_lines, fabric_texture, static_mesh};
use clothlab_core::scene::Scene;
use clothlab_core::solver::{RenderError, RenderMode, View};

use crate::raw::{Clear, DrawDesc, Gl, Prim, TexFormat, VertexAttr, VertexLayout};
use crate::{GlBuffer, GlContext, GlError};

/// Where the cloth's positions and normals come from.
#[derive(Clone, Copy)]
pub enum GlCloth<'a> {
    /// The GL solver's own buffers (`[f32; 4]` per particle each), in the renderer's
    /// context: drawn with no copy.
    Gpu {
        /// Positions.
        pos: GlBuffer,
        /// Normals.
        normal: GlBuffer,
    },
    /// A CPU solver's state: uploaded once per frame.
    Cpu(&'a ClothState),
}

fn rerr(e: GlError) -> RenderError {
    RenderError::Backend(e.to_string())
}

/// The frame's render targets: MSAA colour and depth, the resolved colour, the picking
/// ids and their depth (shared by the resolve framebuffer, which needs a depth of its
/// size and never tests it).
struct Targets {
    textures: Vec<usize>,
    main: usize,
    resolve: usize,
    pick: usize,
}

impl Targets {
    fn new(gl: &Gl, width: u32, height: u32) -> Result<Self, GlError> {
        let mut textures = Vec::new();
        let mut tex = |format, samples| {
            let t = gl.create_texture(format, width, height, samples)?;
            textures.push(t);
            Ok::<_, GlError>(t)
        };
        let msaa = tex(TexFormat::Srgba8, SAMPLES)?;
        let msaa_depth = tex(TexFormat::Depth32f, SAMPLES)?;
        let color = tex(TexFormat::Srgba8, 1)?;
        let ids = tex(TexFormat::R32ui, 1)?;
        let depth = tex(TexFormat::Depth32f, 1)?;
        Ok(Self {
            main: gl.create_framebuffer(Some(msaa), msaa_depth)?,
            resolve: gl.create_framebuffer(Some(color), depth)?,
            pick: gl.create_framebuffer(Some(ids), depth)?,
            textures,
        })
    }

    fn delete(&self, gl: &Gl) -> Result<(), GlError> {
        for f in [self.main, self.resolve, self.pick] {
            gl.delete_framebuffer(f)?;
        }
        self.textures.iter().try_for_each(|&t| gl.delete_texture(t))
    }
}

struct Programs {
    lit_static: usize,
    lit_cloth: usize,
    flat_cloth: usize,
    shadow_static: usize,
    shadow_cloth: usize,
    pick_static: usize,
    pick_cloth: usize,
}

fn programs(gl: &Gl) -> Result<Programs, RenderError> {
    let entry = |name: &str| {
        clothlab_shaders::RENDER_GLSL
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, text)| *text)
            .ok_or_else(|| RenderError::Backend(format!("render.wgsl has no entry point {name}")))
    };
    let link = |vs: &str, fs: Option<&str>| -> Result<usize, RenderError> {
        let fs = fs.map(entry).transpose()?;
        gl.graphics_program(entry(vs)?, fs)
            .map_err(|log| RenderError::Backend(format!("the GL driver refused the render shader {vs}: {log}")))
    };
    Ok(Programs {
        lit_static: link("vs_static", Some("fs_lit"))?,
        lit_cloth: link("vs_cloth", Some("fs_lit"))?,
        flat_cloth: link("vs_cloth", Some("fs_flat"))?,
        shadow_static: link("vs_shadow_static", None)?,
        shadow_cloth: link("vs_shadow_cloth", None)?,
        pick_static: link("vs_pick_static", Some("fs_pick"))?,
        pick_cloth: link("vs_pick_cloth", Some("fs_pick"))?,
    })
}

/// The vertex arrays: static geometry (all of it, or positions), cloth (positions,
/// normals, uv from three buffers, or positions).
struct Layouts {
    static_all: usize,
    static_pos: usize,
    cloth_all: usize,
    cloth_pos: usize,
}

fn layouts(gl: &Gl) -> Result<Layouts, GlError> {
    let f = |location, components, offset| VertexAttr { location, components, integer: false, offset };
    let stride = std::mem::size_of::<StaticVertex>() as u32;
    let stat =
        [f(0, 3, 0), f(1, 3, 12), f(2, 2, 24), VertexAttr { location: 3, components: 1, integer: true, offset: 32 }];
    let (pos, normal, uv) = ([f(0, 4, 0)], [f(1, 4, 0)], [f(2, 2, 0)]);
    Ok(Layouts {
        static_all: gl.create_vertex_array(&[VertexLayout { stride, attrs: &stat }])?,
        static_pos: gl.create_vertex_array(&[VertexLayout { stride, attrs: &stat[..1] }])?,
        cloth_all: gl.create_vertex_array(&[
            VertexLayout { stride: 16, attrs: &pos },
            VertexLayout { stride: 16, attrs: &normal },
            VertexLayout { stride: 8, attrs: &uv },
        ])?,
        cloth_pos: gl.create_vertex_array(&[VertexLayout { stride: 16, attrs: &pos }])?,
    })
}

/// Offscreen renderer of one scene and its cloth on raw OpenGL, in a [`GlContext`] (the
/// solver's, so that its buffers are drawn as they are); its objects are deleted with it.
pub struct GlRenderer {
    width: u32,
    height: u32,
    targets: Targets,
    programs: Programs,
    layouts: Layouts,
    shadow: usize,
    shadow_fb: usize,
    fabric: usize,
    shadow_sampler: usize,
    fabric_sampler: usize,
    frame: usize,
    static_vb: usize,
    /// Vertices in `static_vb`.
    static_vertices: usize,
    static_ib: usize,
    uv: usize,
    tri_ib: usize,
    line_ib: usize,
    cpu_pos: usize,
    cpu_normal: usize,
    num_particles: u32,
    ctx: GlContext,
}

fn check_size(gl: &Gl, width: u32, height: u32) -> Result<(), RenderError> {
    let max = gl.limits().texture_size;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::InvalidSize { width, height, reason: format!("each side must be in 1 ..= {max}") });
    }
    Ok(())
}

impl GlRenderer {
    /// A renderer of `scene` with its cloth `topo` in `ctx`, drawing `width × height`.
    pub fn new(
        ctx: &GlContext,
        scene: &Scene,
        topo: &ClothTopology,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        let gl = ctx.gl();
        check_size(gl, width, height)?;
        let programs = programs(gl)?;
        Self::build(ctx, programs, scene, topo, width, height).map_err(rerr)
    }

    fn build(
        ctx: &GlContext,
        programs: Programs,
        scene: &Scene,
        topo: &ClothTopology,
        width: u32,
        height: u32,
    ) -> Result<Self, GlError> {
        let gl = ctx.gl();
        let shadow = gl.create_texture(TexFormat::Depth32f, SHADOW_SIZE, SHADOW_SIZE, 1)?;
        let fabric = gl.create_texture(TexFormat::Srgba8, 64, 64, 1)?;
        gl.write_texture(fabric, &fabric_texture())?;
        let (sv, si) = static_mesh(scene);
        let tri: Vec<u32> = topo.triangles.iter().flatten().copied().collect();
        let np = topo.num_particles() as u32;
        let zeros = vec![0u8; np as usize * 16];
        let r = Self {
            width,
            height,
            targets: Targets::new(gl, width, height)?,
            programs,
            layouts: layouts(gl)?,
            shadow,
            shadow_fb: gl.create_framebuffer(None, shadow)?,
            fabric,
            shadow_sampler: gl.create_sampler(true)?,
            fabric_sampler: gl.create_sampler(false)?,
            frame: gl.create_buffer(&[0u8; std::mem::size_of::<Frame>()])?,
            static_vb: gl.create_buffer(bytemuck::cast_slice(&sv))?,
            static_vertices: sv.len(),
            static_ib: gl.create_index_buffer(&si)?,
            uv: gl.create_buffer(bytemuck::cast_slice(&topo.render_uvs()))?,
            tri_ib: gl.create_index_buffer(&tri)?,
            line_ib: gl.create_index_buffer(&cloth_lines(topo))?,
            cpu_pos: gl.create_buffer(&zeros)?,
            cpu_normal: gl.create_buffer(&zeros)?,
            num_particles: np,
            ctx: ctx.clone(),
        };
        gl.check("making the GL renderer")?;
        Ok(r)
    }

    /// Target size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Draws the colliders of `scene` from now on (moving colliders: `Scene::moved_to`);
    /// the same shapes as the renderer was made with, else refused.
    pub fn set_colliders(&mut self, ctx: &GlContext, scene: &Scene) -> Result<(), RenderError> {
        let gl = self.gl(ctx)?;
        let (sv, _) = static_mesh(scene);
        if sv.len() != self.static_vertices {
            return Err(RenderError::Backend("set_colliders: the scene's colliders are not the renderer's".into()));
        }
        gl.write(self.static_vb, 0, bytemuck::cast_slice(&sv)).map_err(rerr)
    }

    /// Changes the target size; a zero or too large side is refused and nothing changes.
    pub fn resize(&mut self, ctx: &GlContext, width: u32, height: u32) -> Result<(), RenderError> {
        let gl = self.gl(ctx)?;
        check_size(gl, width, height)?;
        let targets = Targets::new(gl, width, height).map_err(rerr)?;
        self.targets.delete(gl).map_err(rerr)?;
        self.targets = targets;
        self.width = width;
        self.height = height;
        Ok(())
    }

    /// `ctx`, if it is the context this renderer was made in.
    fn gl<'a>(&self, ctx: &'a GlContext) -> Result<&'a Gl, RenderError> {
        if !ctx.same(&self.ctx) {
            return Err(RenderError::Backend("a GL renderer used with another context than its own".into()));
        }
        Ok(ctx.gl())
    }

    /// Writes the frame's constants and a CPU state; the buffers the cloth is drawn from.
    fn prepare(&self, gl: &Gl, view: &View, cloth: &GlCloth<'_>) -> Result<(usize, usize), RenderError> {
        let f = Frame::new(view, self.width, self.height);
        gl.write(self.frame, 0, bytemuck::bytes_of(&f)).map_err(rerr)?;
        let need = self.num_particles as u64 * 16;
        match cloth {
            GlCloth::Gpu { pos, normal } => {
                if pos.context != gl.id() || normal.context != gl.id() {
                    return Err(RenderError::Backend("cloth buffers of another GL context".into()));
                }
                if pos.size < need || normal.size < need {
                    return Err(RenderError::Backend("cloth buffers of another grid size".into()));
                }
                // The solver's kernels wrote them as storage blocks: make that visible
                // to vertex fetching (GL orders its own commands, not shader writes).
                gl.memory_barrier(glow::VERTEX_ATTRIB_ARRAY_BARRIER_BIT).map_err(rerr)?;
                Ok((pos.index, normal.index))
            }
            GlCloth::Cpu(state) => {
                if state.pos.len() != self.num_particles as usize || state.normal.len() != state.pos.len() {
                    return Err(RenderError::Backend("state of another grid size".into()));
                }
                gl.write(self.cpu_pos, 0, bytemuck::cast_slice(&state.pos)).map_err(rerr)?;
                gl.write(self.cpu_normal, 0, bytemuck::cast_slice(&state.normal)).map_err(rerr)?;
                Ok((self.cpu_pos, self.cpu_normal))
            }
        }
    }

    /// The floor, colliders and cloth triangles into `fb` with `stat` and `cloth`
    /// programs (positions only): the shadow and picking passes.
    fn draw_geometry(
        &self,
        gl: &Gl,
        fb: usize,
        (stat, cloth): (usize, usize),
        pos: usize,
        depth_bias: Option<(f32, f32)>,
    ) -> Result<(), GlError> {
        let frame = [(0, self.frame)];
        let d = |program, vertex_array, vertices, indices| DrawDesc {
            framebuffer: fb,
            program,
            vertex_array,
            vertices,
            indices: Some(indices),
            count: 0,
            prim: Prim::Triangles,
            uniform: &frame,
            textures: &[],
            depth_bias,
        };
        let (stat_vb, cloth_vb) = ([self.static_vb], [pos]);
        gl.draw(&d(stat, self.layouts.static_pos, &stat_vb, self.static_ib))?;
        gl.draw(&d(cloth, self.layouts.cloth_pos, &cloth_vb, self.tri_ib))
    }

    /// Draws one frame of the scene with the cloth from `cloth` (read back by
    /// [`GlRenderer::read_image`]).
    pub fn render(&mut self, ctx: &GlContext, view: &View, cloth: GlCloth<'_>) -> Result<(), RenderError> {
        let gl = self.gl(ctx)?;
        let (pos, normal) = self.prepare(gl, view, &cloth)?;
        self.draw(gl, view, pos, normal).map_err(rerr)?;
        gl.check("drawing a frame").map_err(rerr)
    }

    fn draw(&self, gl: &Gl, view: &View, pos: usize, normal: usize) -> Result<(), GlError> {
        // Shadow pass: depth from the light (the bias of the other renderers).
        gl.clear_target(self.shadow_fb, Clear::Color([0.0; 4]))?;
        let p = &self.programs;
        self.draw_geometry(gl, self.shadow_fb, (p.shadow_static, p.shadow_cloth), pos, Some((2.0, 2.0)))?;
        // Main pass: 4× MSAA colour, resolved into the sRGB target.
        let main = self.targets.main;
        gl.clear_target(main, Clear::Color(SKY))?;
        let frame = [(0, self.frame)];
        let textures = [(0, self.shadow, self.shadow_sampler), (1, self.fabric, self.fabric_sampler)];
        let lit = |program, vertex_array, vertices, indices, count, prim| DrawDesc {
            framebuffer: main,
            program,
            vertex_array,
            vertices,
            indices,
            count,
            prim,
            uniform: &frame,
            textures: &textures,
            depth_bias: None,
        };
        let l = &self.layouts;
        let (stat_vb, cloth) = ([self.static_vb], [pos, normal, self.uv]);
        gl.draw(&lit(p.lit_static, l.static_all, &stat_vb, Some(self.static_ib), 0, Prim::Triangles))?;
        gl.draw(&match view.mode {
            RenderMode::Triangles => lit(p.lit_cloth, l.cloth_all, &cloth, Some(self.tri_ib), 0, Prim::Triangles),
            RenderMode::Lines => lit(p.flat_cloth, l.cloth_all, &cloth, Some(self.line_ib), 0, Prim::Lines),
            RenderMode::Points => lit(p.flat_cloth, l.cloth_all, &cloth, None, self.num_particles, Prim::Points),
        })?;
        gl.resolve(main, self.targets.resolve)
    }

    /// The particle drawn at pixel `(x, y)` (origin top left) for this view and cloth, or
    /// `None` where no cloth is: the provoking vertex of the cloth triangle under the
    /// pixel (the particle or a direct neighbour), as on wgpu and Vulkan.
    pub fn pick(
        &mut self,
        ctx: &GlContext,
        view: &View,
        cloth: GlCloth<'_>,
        x: u32,
        y: u32,
    ) -> Result<Option<u32>, RenderError> {
        if x >= self.width || y >= self.height {
            return Ok(None);
        }
        let gl = self.gl(ctx)?;
        let (pos, _) = self.prepare(gl, view, &cloth)?;
        let pick = self.targets.pick;
        let p = &self.programs;
        let raw = (|| {
            gl.clear_target(pick, Clear::Uint([0; 4]))?;
            self.draw_geometry(gl, pick, (p.pick_static, p.pick_cloth), pos, None)?;
            gl.read_pixels(pick, x, y, 1, 1)
        })()
        .map_err(rerr)?;
        gl.check("picking").map_err(rerr)?;
        Ok(u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]).checked_sub(1))
    }

    /// The last frame as tightly packed sRGB RGBA8 rows, the first at the top.
    pub fn read_image(&self, ctx: &GlContext) -> Result<Vec<u8>, RenderError> {
        let gl = self.gl(ctx)?;
        gl.read_pixels(self.targets.resolve, 0, 0, self.width, self.height).map_err(rerr)
    }
}

impl GlRenderer {
    /// Copies the last frame into `ctx`'s window (scaled to `width × height`, its drawable
    /// size), under whatever is drawn next (the panels).
    pub fn present(&self, ctx: &GlContext, width: u32, height: u32) -> Result<(), RenderError> {
        let gl = self.gl(ctx)?;
        gl.blit_to_window(self.targets.resolve, width, height).map_err(rerr)
    }
}

impl Drop for GlRenderer {
    fn drop(&mut self) {
        let gl = self.ctx.gl();
        let p = &self.programs;
        let l = &self.layouts;
        let results = [
            self.targets.delete(gl),
            gl.delete_framebuffer(self.shadow_fb),
            gl.delete_texture(self.shadow),
            gl.delete_texture(self.fabric),
            gl.delete_draw_objects(
                &[self.static_ib, self.tri_ib, self.line_ib],
                &[self.shadow_sampler, self.fabric_sampler],
                &[l.static_all, l.static_pos, l.cloth_all, l.cloth_pos],
            ),
        ]
        .into_iter()
        .chain([self.frame, self.static_vb, self.uv, self.cpu_pos, self.cpu_normal].map(|b| gl.delete_buffer(b)))
        .chain(
            [p.lit_static, p.lit_cloth, p.flat_cloth, p.shadow_static, p.shadow_cloth, p.pick_static, p.pick_cloth]
                .map(|x| gl.delete_program(x)),
        );
        let errors: Vec<GlError> = results.filter_map(Result::err).collect();
        if let Some(e) = errors.first() {
            log::warn!("deleting the GL renderer's objects: {e}");
        }
    }
}

impl clothlab_core::Renderer for GlRenderer {
    type Context = GlContext;
    type Cloth<'a> = GlCloth<'a>;

    fn resize(&mut self, ctx: &GlContext, width: u32, height: u32) -> Result<(), RenderError> {
        GlRenderer::resize(self, ctx, width, height)
    }

    fn render(&mut self, ctx: &GlContext, view: &View, cloth: GlCloth<'_>) -> Result<(), RenderError> {
        GlRenderer::render(self, ctx, view, cloth)
    }

    fn pick(
        &mut self,
        ctx: &GlContext,
        view: &View,
        cloth: GlCloth<'_>,
        x: u32,
        y: u32,
    ) -> Result<Option<u32>, RenderError> {
        GlRenderer::pick(self, ctx, view, cloth, x, y)
    }

    fn read_image(&self, ctx: &GlContext) -> Result<Vec<u8>, RenderError> {
        GlRenderer::read_image(self, ctx)
    }
}
