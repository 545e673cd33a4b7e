//! egui's panels on GL: egui_glow's painter, called only with its context current. Part
//! of the raw layer: egui_glow's safe methods issue GL calls on the context they were
//! given and expect it to be current; this wrapper makes it so before every call, and
//! refuses a painter from another context.

use std::sync::Arc;

use super::{Gl, GlError};

/// egui_glow's painter, bound to the context it was made in.
pub struct EguiPainter {
    painter: egui_glow::Painter,
    context: u64,
}

impl Gl {
    /// An egui painter in this context.
    pub fn egui_painter(&self) -> Result<EguiPainter, GlError> {
        self.cur()?;
        // SAFETY: the context is current on this thread; EGL returns GL entry points for
        // it, which glow loads by name (a second table of the same functions, for egui).
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                self.egl.get_proc_address(name).map_or(std::ptr::null(), |f| f as *const std::ffi::c_void)
            })
        };
        let painter = egui_glow::Painter::new(Arc::new(gl), "", None, false)
            .map_err(|e| GlError::Gl { what: "making egui's painter", reason: e.to_string() })?;
        Ok(EguiPainter { painter, context: self.id })
    }

    fn check_painter(&self, p: &EguiPainter) -> Result<(), GlError> {
        if p.context != self.id {
            return Err(GlError::Invalid("an egui painter of another context"));
        }
        self.cur().map(|_| ())
    }

    /// Paints egui's shapes over the window's default framebuffer of `size` pixels, after
    /// applying the texture changes.
    pub fn paint_egui(
        &self,
        p: &mut EguiPainter,
        size: [u32; 2],
        pixels_per_point: f32,
        primitives: &[egui::ClippedPrimitive],
        textures: &egui::TexturesDelta,
    ) -> Result<(), GlError> {
        self.check_painter(p)?;
        let mut textures = textures.clone();
        use glow::HasContext;
        // SAFETY: the context is current; egui draws into the bound draw framebuffer,
        // which must be the window's (0).
        unsafe { self.gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
        // egui_glow's calls run on the current context (made so above).
        p.painter.paint_and_update_textures(size, pixels_per_point, primitives, &mut textures);
        Ok(())
    }

    /// Deletes the painter's GL objects (before it drops).
    pub fn destroy_egui(&self, p: &mut EguiPainter) -> Result<(), GlError> {
        self.check_painter(p)?;
        p.painter.destroy();
        Ok(())
    }
}
