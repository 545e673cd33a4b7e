//! clothlab-gl: the cloth solver, the scene renderer and the app's window on raw OpenGL
//! 4.5 core through glow, with contexts through EGL (headless: Mesa's surfaceless
//! platform, else a pbuffer; or an X11 window), running the same kernels as the other
//! backends — naga's GLSL of the one WGSL source, written when clothlab-shaders builds —
//! and the same recipes.
//!
//! All `unsafe` is in the crate-private `raw` module, each block with a `// SAFETY:` line;
//! the engine, renderer and overlay above it are safe code over indices into the
//! context's own objects.
//!
//! How it fits: a [`GlContext`] is shared by the solvers and renderers made in it, so that
//! the renderer draws a solver's storage buffers as vertex buffers (the thesis's shared
//! buffers). [`GlEngine`] is this API's `clothlab_engine::Engine` (buffer objects with
//! immutable storage, one compute program per kernel, shader storage and uniform blocks
//! bound per dispatch at the points the GLSL declares, `glMemoryBarrier` where the generic
//! solver places a barrier, `glQueryCounter` timestamps, the spring table as an RGBA32UI
//! texture); the solver is `GpuSolver<GlEngine>`, the generic solver wgpu and Vulkan use.
//! [`GlRenderer`] draws the scene with the passes of the other renderers; [`GlOverlay`]
//! paints egui into a window context. What GL lacks is refused in one line: push
//! constants (`constants=immediates`), and subgroup operations where
//! `GL_KHR_shader_subgroup` is missing.
#![deny(unsafe_code)]

mod context;
pub mod overhead;
mod raw;
mod render;
mod solver;

use thiserror::Error;

pub use context::{GlContext, GlOverlay};
pub use raw::WindowHandles;
pub use render::{GlCloth, GlRenderer};
pub use solver::{GlBuffer, GlEngine, GlSolver, gl_solver};

/// Why OpenGL could not be used.
#[derive(Debug, Error)]
pub enum GlError {
    /// No EGL, no display, or no GL 4.5 core context.
    #[error(
        "no GPU adapter found (OpenGL 4.5 core through EGL): {0}; on Linux, `apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri` gives a software one (llvmpipe)"
    )]
    NoGl(String),
    /// An EGL call failed.
    #[error("EGL error while {what}: {reason}")]
    Egl {
        /// What was being done.
        what: &'static str,
        /// EGL's error.
        reason: String,
    },
    /// GL reported errors (glGetError, debug output).
    #[error("OpenGL error while {what}: {reason}")]
    Gl {
        /// What was being done.
        what: &'static str,
        /// The errors and messages.
        reason: String,
    },
    /// A request outside what was made (a bad index, a range past an end).
    #[error("OpenGL: {0}")]
    Invalid(&'static str),
}
