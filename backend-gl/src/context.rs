//! The OpenGL context solvers and renderers share: one per window (or headless), drawn
//! into by the renderer and computed in by the solvers made on it, so that a solver's
//! storage buffers are the renderer's vertex buffers (the thesis's shared buffers).

use std::rc::Rc;
use std::sync::Arc;

use crate::GlError;
use crate::raw::{Gl, WindowHandles};

/// An OpenGL 4.5 core context; clones share it. Not `Send`: a GL context is used on the
/// thread that made it.
#[derive(Clone)]
pub struct GlContext(pub(crate) Rc<Gl>);

impl GlContext {
    /// A headless context (EGL surfaceless, else a pbuffer).
    pub fn headless() -> Result<Self, GlError> {
        Ok(Self(Rc::new(Gl::headless()?)))
    }

    /// A context drawing into `window` (X11), kept alive as long as the context is.
    pub fn for_window(window: Arc<dyn WindowHandles>) -> Result<Self, GlError> {
        Ok(Self(Rc::new(Gl::for_window(window)?)))
    }

    /// The renderer and version, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (OpenGL 4.5)`.
    pub fn adapter(&self) -> String {
        let l = self.0.limits();
        format!("{} (OpenGL {})", l.renderer, l.version.split(' ').next().unwrap_or("?"))
    }

    /// Whether `other` is this same context.
    pub fn same(&self, other: &GlContext) -> bool {
        Rc::ptr_eq(&self.0, &other.0)
    }

    /// Shows the window's frame (eglSwapBuffers); refused for a headless context.
    pub fn swap_buffers(&self) -> Result<(), GlError> {
        self.0.swap_buffers()
    }

    pub(crate) fn gl(&self) -> &Gl {
        &self.0
    }

    /// Whether solvers or renderers other than the holder of this handle use the context.
    pub(crate) fn shared(&self) -> bool {
        Rc::strong_count(&self.0) > 1
    }
}

impl std::fmt::Debug for GlContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GlContext({})", self.adapter())
    }
}

/// egui's panels painted into a GL window (egui_glow), over the scene.
pub struct GlOverlay {
    ctx: GlContext,
    painter: crate::raw::EguiPainter,
}

impl GlOverlay {
    /// A painter of egui's shapes into `ctx`'s window.
    pub fn new(ctx: &GlContext) -> Result<Self, GlError> {
        Ok(Self { painter: ctx.gl().egui_painter()?, ctx: ctx.clone() })
    }

    /// Paints `primitives` over the window's `size` pixels after the texture changes.
    pub fn paint(
        &mut self,
        size: [u32; 2],
        pixels_per_point: f32,
        primitives: &[egui::ClippedPrimitive],
        textures: &egui::TexturesDelta,
    ) -> Result<(), GlError> {
        self.ctx.gl().paint_egui(&mut self.painter, size, pixels_per_point, primitives, textures)
    }
}

impl Drop for GlOverlay {
    fn drop(&mut self) {
        if let Err(e) = self.ctx.gl().destroy_egui(&mut self.painter) {
            log::warn!("deleting egui's GL objects: {e}");
        }
    }
}

impl GlContext {
    /// The window's `width × height` pixels as drawn so far this frame (before the swap),
    /// sRGB RGBA8, first row at the top.
    pub fn read_window(&self, width: u32, height: u32) -> Result<Vec<u8>, GlError> {
        self.0.read_window(width, height)
    }
}
