//! The only unsafe code of clothlab-gl: an OpenGL 4.5 core context through EGL (headless or
//! on an X11 window) and the GL calls the engine (here), the renderer (`draw`) and egui
//! (`overlay`) make, behind a safe surface.
//!
//! Soundness of the safe surface (no safe function relies on its caller):
//! * [`Gl`] is neither `Send` nor `Sync`: its context is used on the thread that made it;
//! * every call first makes the context current on this thread if EGL says another one
//!   is (asked each time, so a context another library made current — wgpu's GL backend,
//!   say — is noticed too), so two contexts on one thread never get each other's calls;
//! * GL objects are named by indices into the context's own tables, never by raw GL names
//!   from outside; a bad index is an error, not a call;
//! * every transfer's range is checked against the buffer's size before the call, and
//!   every slice GL writes into is sized by us;
//! * the context is created with robust buffer access where the driver offers it (out-of-
//!   bounds shader accesses cannot touch other memory); without it, the engine refuses
//!   kernels from outside (`Gl::robust`);
//! * an object lives until it is deleted (its table entry then says so, and its index is
//!   never reused) or the context goes: all are freed when [`Gl`] drops and destroys it;
//! * a window context holds the window (an `Arc`) until its surface is destroyed.
#![allow(unsafe_code)]

use std::cell::RefCell;
use std::marker::PhantomData;
use std::sync::{Arc, Mutex};

use glow::HasContext;
use khronos_egl as egl;

use crate::GlError;

/// `EGL_PLATFORM_X11_KHR`: a display of an Xlib `Display*`.
const PLATFORM_X11_KHR: egl::Enum = 0x31D5;
/// `EGL_PLATFORM_SURFACELESS_MESA`: a display with no window system (headless).
const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;
/// `GL_SUBGROUP_SUPPORTED_FEATURES_KHR` (GL_KHR_shader_subgroup; not in glow).
const SUBGROUP_SUPPORTED_FEATURES: u32 = 0x9534;
/// `GL_SUBGROUP_SIZE_KHR`.
const SUBGROUP_SIZE: u32 = 0x9532;
/// glClearNamedBufferData (GL 4.5): `(buffer, internalformat, format, type, data)`.
type ClearNamedBufferData = unsafe extern "system" fn(u32, u32, u32, u32, *const std::ffi::c_void);

/// A window GL can draw into: what winit's windows are.
pub trait WindowHandles: raw_window_handle::HasDisplayHandle + raw_window_handle::HasWindowHandle {}
impl<T: raw_window_handle::HasDisplayHandle + raw_window_handle::HasWindowHandle> WindowHandles for T {}

/// The Xlib display, window XID and visual of `w`; another window system is refused in
/// one line (the GL window needs X11; Wayland runs it through XWayland).
fn x11_handles(
    w: &dyn WindowHandles,
) -> Result<(*mut std::ffi::c_void, std::ffi::c_ulong, std::ffi::c_ulong), GlError> {
    use raw_window_handle::{RawDisplayHandle, RawWindowHandle};
    let d = w.display_handle().map_err(|e| GlError::NoGl(format!("the window has no display handle ({e})")))?;
    let h = w.window_handle().map_err(|e| GlError::NoGl(format!("the window has no handle ({e})")))?;
    match (d.as_raw(), h.as_raw()) {
        (RawDisplayHandle::Xlib(d), RawWindowHandle::Xlib(h)) => {
            let display = d.display.ok_or_else(|| GlError::NoGl("the X11 window has no Xlib display".into()))?;
            Ok((display.as_ptr(), h.window, h.visual_id))
        }
        (d, _) => Err(GlError::NoGl(format!(
            "--api gl draws into X11 windows only, this one is {d:?}; run with WAYLAND_DISPLAY unset (XWayland) or use --api wgpu or vulkan"
        ))),
    }
}

/// `EGL_PLATFORM_DEVICE_EXT`: a display of an `EGLDeviceEXT`.
const PLATFORM_DEVICE_EXT: egl::Enum = 0x313F;
/// eglQueryDevicesEXT (EGL_EXT_device_enumeration): `(max, devices, count) -> EGLBoolean`.
type QueryDevices = unsafe extern "system" fn(i32, *mut *mut std::ffi::c_void, *mut i32) -> u32;

/// A headless display of its own: the first EGL device (EGL_EXT_platform_device) that
/// initialises and has an OpenGL pbuffer config. Not Mesa's surfaceless display: wgpu's
/// GL backend opens that one too and terminates it when its last instance drops
/// (wgpu-hal counts only its own users), which would end every context of ours on it.
/// EGL hands out one display per (platform, native display), so another platform is
/// another display.
fn device_display(instance: &egl::DynamicInstance<egl::EGL1_5>) -> Option<egl::Display> {
    let f = instance.get_proc_address("eglQueryDevicesEXT")?;
    // SAFETY: eglQueryDevicesEXT's signature in EGL_EXT_device_enumeration is
    // `EGLBoolean (EGLint max_devices, EGLDeviceEXT *devices, EGLint *num_devices)`.
    let query = unsafe { std::mem::transmute::<extern "system" fn(), QueryDevices>(f) };
    let mut devices = [std::ptr::null_mut(); 16];
    let mut count = 0i32;
    // SAFETY: `devices` has room for the 16 handles asked for at most; `count` is written.
    if unsafe { query(devices.len() as i32, devices.as_mut_ptr(), &mut count) } != egl::TRUE {
        return None;
    }
    let found = &devices[..count.clamp(0, devices.len() as i32) as usize];
    found.iter().find_map(|&device| {
        // SAFETY: `device` is an EGLDeviceEXT EGL just listed (it lives as long as the
        // library); the attribute list is empty.
        let d = unsafe { instance.get_platform_display(PLATFORM_DEVICE_EXT, device, &[egl::ATTRIB_NONE]) }.ok()?;
        instance.initialize(d).ok()?;
        instance.bind_api(egl::OPENGL_API).ok()?;
        let attribs = [egl::RENDERABLE_TYPE, egl::OPENGL_BIT, egl::SURFACE_TYPE, egl::PBUFFER_BIT, egl::NONE];
        instance.choose_first_config(d, &attribs).ok().flatten().map(|_| d)
    })
}

/// What the context offers, read once when it is made.
#[derive(Debug, Clone)]
pub struct Limits {
    /// `GL_RENDERER`.
    pub renderer: String,
    /// `GL_VERSION`.
    pub version: String,
    /// Every extension's name.
    pub extensions: Vec<String>,
    /// GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS.
    pub storage_blocks: u32,
    /// GL_MAX_SHADER_STORAGE_BLOCK_SIZE, bytes.
    pub storage_block_size: u64,
    /// GL_MAX_UNIFORM_BLOCK_SIZE, bytes.
    pub uniform_block_size: u64,
    /// GL_MAX_TEXTURE_SIZE.
    pub texture_size: u32,
    /// GL_MAX_3D_TEXTURE_SIZE.
    pub texture_3d_size: u32,
    /// GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, bytes.
    pub shared_memory: u32,
    /// GL_SUBGROUP_SUPPORTED_FEATURES_KHR (0 without GL_KHR_shader_subgroup).
    pub subgroup_features: u32,
    /// GL_SUBGROUP_SIZE_KHR (0 without it).
    pub subgroup_size: u32,
}

impl Limits {
    /// Whether the context offers extension `name`.
    pub fn has(&self, name: &str) -> bool {
        self.extensions.iter().any(|e| e == name)
    }
}

mod draw;
mod overlay;

pub use draw::{Clear, DrawDesc, Prim, TexFormat, VertexAttr, VertexLayout};
pub use overlay::EguiPainter;

#[derive(Clone, Copy)]
struct BufferObj {
    name: glow::NativeBuffer,
    size: u64,
}

#[derive(Clone, Copy)]
struct TextureObj {
    name: glow::NativeTexture,
    width: u32,
    height: u32,
    format: TexFormat,
    samples: u32,
    /// Slices of a 3-D texture ([`Gl::create_volume`]); 0 for a 2-D one.
    depth: u32,
}

/// Every object made in the context, named by its index here. Interior mutability (the
/// context is one thread's) lets a renderer and a solver share one context by reference.
#[derive(Default)]
struct Objects {
    /// Each table's entries are `None` once deleted (indices are never reused).
    buffers: Vec<Option<BufferObj>>,
    textures: Vec<Option<TextureObj>>,
    programs: Vec<Option<Program>>,
    draw: draw::DrawObjects,
}

impl Objects {
    fn buffer(&self, i: usize) -> Option<&BufferObj> {
        self.buffers.get(i).and_then(Option::as_ref)
    }

    fn program(&self, i: usize) -> Option<&Program> {
        self.programs.get(i).and_then(Option::as_ref)
    }
}

struct Program {
    program: glow::NativeProgram,
    locations: Vec<Option<glow::NativeUniformLocation>>,
}

/// A uniform value to set before a dispatch (GL's stand-in for immediates).
#[derive(Debug, Clone, Copy)]
pub enum Value {
    /// `glUniform{n}uiv`.
    U(u8, [u32; 4]),
    /// `glUniform{n}iv`.
    I(u8, [i32; 4]),
    /// `glUniform{n}fv`.
    F(u8, [f32; 4]),
}

/// One dispatch: the program, what to bind where, and the work groups.
pub struct DispatchDesc<'a> {
    /// A program index from [`Gl::program`].
    pub program: usize,
    /// `(binding point, buffer)` for shader storage blocks.
    pub storage: &'a [(u32, usize)],
    /// `(binding point, buffer)` for uniform blocks.
    pub uniform: &'a [(u32, usize)],
    /// `(texture unit, texture)`.
    pub textures: &'a [(u32, usize)],
    /// `(uniform index in the program's list, value)`.
    pub values: &'a [(usize, Value)],
    /// Work groups in x, y and z (z: the worlds of a batch).
    pub groups: (u32, u32, u32),
}

/// An OpenGL 4.5 core context (headless, through EGL) and the objects made in it.
pub struct Gl {
    egl: egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    context: egl::Context,
    surface: Option<egl::Surface>,
    gl: glow::Context,
    clear_named_buffer_data: Option<ClearNamedBufferData>,
    limits: Limits,
    robust: bool,
    messages: Arc<Mutex<Vec<String>>>,
    objs: RefCell<Objects>,
    /// Unique in the process: tells a context's buffers from another's.
    id: u64,
    clip_control: Option<draw::ClipControl>,
    provoking_vertex: Option<draw::ProvokingVertex>,
    /// The window drawn into (kept open while its surface exists; dropped after it).
    window: Option<Arc<dyn WindowHandles>>,
    queries: Vec<glow::NativeQuery>,
    _not_send: PhantomData<*const ()>,
}

fn egl_err(what: &'static str) -> impl Fn(egl::Error) -> GlError {
    move |e| GlError::Egl { what, reason: e.to_string() }
}

impl Gl {
    /// A headless OpenGL 4.5 core context: Mesa's surfaceless platform where there is
    /// one, else the default display with a 1×1 pbuffer. A debug context, its messages of
    /// medium and high severity collected for [`Gl::messages`].
    pub fn headless() -> Result<Gl, GlError> {
        Self::open(None)
    }

    /// An OpenGL 4.5 core context drawing into `window` (X11 through EGL's X11 platform),
    /// made current with the window's surface; [`Gl::swap_buffers`] shows what was drawn.
    /// The context keeps `window` alive as long as it draws into it.
    pub fn for_window(window: Arc<dyn WindowHandles>) -> Result<Gl, GlError> {
        Self::open(Some(window))
    }

    fn open(window: Option<Arc<dyn WindowHandles>>) -> Result<Gl, GlError> {
        // SAFETY: loads the system's libEGL (libEGL.so.1), whose exported functions have
        // the EGL 1.5 signatures khronos-egl declares; nothing is called before the
        // version check `load_required` does.
        let instance = unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }
            .map_err(|e| GlError::NoGl(format!("no EGL 1.5 library ({e})")))?;
        let native = match &window {
            Some(w) => Some(x11_handles(w.as_ref())?),
            None => None,
        };
        let display = match native {
            Some((xdisplay, _, _)) => {
                // SAFETY: `xdisplay` is the live Xlib display of a window that `window`
                // (kept in the returned Gl) keeps open; the attribute list is empty.
                let d = unsafe { instance.get_platform_display(PLATFORM_X11_KHR, xdisplay, &[egl::ATTRIB_NONE]) }
                    .map_err(|e| GlError::NoGl(format!("EGL has no X11 display ({e})")))?;
                instance.initialize(d).map_err(|e| GlError::NoGl(format!("eglInitialize failed: {e}")))?;
                d
            }
            None if let Some(d) = device_display(&instance) => d,
            None => {
                // SAFETY: the surfaceless platform takes EGL_DEFAULT_DISPLAY (no native
                // display pointer is dereferenced) and an empty attribute list.
                let surfaceless = unsafe {
                    instance.get_platform_display(PLATFORM_SURFACELESS_MESA, egl::DEFAULT_DISPLAY, &[egl::ATTRIB_NONE])
                }
                .ok()
                .filter(|d| instance.initialize(*d).is_ok());
                match surfaceless {
                    Some(d) => d,
                    None => {
                        // SAFETY: EGL_DEFAULT_DISPLAY is the null native display EGL defines.
                        let d = unsafe { instance.get_display(egl::DEFAULT_DISPLAY) }
                            .ok_or_else(|| GlError::NoGl("EGL has no display".into()))?;
                        instance.initialize(d).map_err(|e| GlError::NoGl(format!("eglInitialize failed: {e}")))?;
                        d
                    }
                }
            }
        };
        instance.bind_api(egl::OPENGL_API).map_err(|e| GlError::NoGl(format!("EGL offers no OpenGL ({e})")))?;
        let config = match native {
            // A window's config: 8-bit RGB, and the window's own visual where it names one
            // (EGL refuses a surface of another visual).
            Some((_, _, visual)) => {
                let mut configs = Vec::with_capacity(64);
                instance
                    .choose_config(
                        display,
                        &[
                            egl::RENDERABLE_TYPE,
                            egl::OPENGL_BIT,
                            egl::SURFACE_TYPE,
                            egl::WINDOW_BIT,
                            egl::RED_SIZE,
                            8,
                            egl::GREEN_SIZE,
                            8,
                            egl::BLUE_SIZE,
                            8,
                            egl::NONE,
                        ],
                        &mut configs,
                    )
                    .map_err(egl_err("choosing a config"))?;
                let own = configs.iter().copied().find(|&c| {
                    visual != 0
                        && instance.get_config_attrib(display, c, egl::NATIVE_VISUAL_ID).ok() == Some(visual as i32)
                });
                own.or(configs.first().copied())
                    .ok_or_else(|| GlError::NoGl("EGL has no OpenGL config for a window".into()))?
            }
            None => instance
                .choose_first_config(
                    display,
                    &[egl::RENDERABLE_TYPE, egl::OPENGL_BIT, egl::SURFACE_TYPE, egl::PBUFFER_BIT, egl::NONE],
                )
                .map_err(egl_err("choosing a config"))?
                .ok_or_else(|| GlError::NoGl("EGL has no OpenGL config".into()))?,
        };
        let attribs = |robust: bool| {
            let mut a = vec![
                egl::CONTEXT_MAJOR_VERSION,
                4,
                egl::CONTEXT_MINOR_VERSION,
                5,
                egl::CONTEXT_OPENGL_PROFILE_MASK,
                egl::CONTEXT_OPENGL_CORE_PROFILE_BIT,
                egl::CONTEXT_OPENGL_DEBUG,
                egl::TRUE as i32,
            ];
            if robust {
                a.extend([egl::CONTEXT_OPENGL_ROBUST_ACCESS, egl::TRUE as i32]);
            }
            a.push(egl::NONE);
            a
        };
        let (context, robust) = match instance.create_context(display, config, None, &attribs(true)) {
            Ok(c) => (c, true),
            Err(_) => (
                instance.create_context(display, config, None, &attribs(false)).map_err(|e| {
                    GlError::NoGl(format!("no OpenGL 4.5 core context ({e}); clothlab needs GL 4.5 with compute"))
                })?,
                false,
            ),
        };
        // The window's surface; headless: surfaceless where EGL_KHR_surfaceless_context
        // allows it, else a 1×1 pbuffer.
        let surface = if let Some((_, xwindow, _)) = native {
            // SAFETY: `xwindow` is the XID of a live window of the display above (kept
            // open by `window`, held by the returned Gl, which destroys the surface
            // first); for X11, EGLNativeWindowType is the XID itself.
            let s = unsafe { instance.create_window_surface(display, config, xwindow as egl::NativeWindowType, None) }
                .map_err(egl_err("creating the window surface"))?;
            instance.make_current(display, Some(s), Some(s), Some(context)).map_err(egl_err("making current"))?;
            // Vsync where offered (a failure only means frames are not paced).
            let _ = instance.swap_interval(display, 1);
            Some(s)
        } else {
            match instance.make_current(display, None, None, Some(context)) {
                Ok(()) => None,
                Err(_) => {
                    let s = instance
                        .create_pbuffer_surface(display, config, &[egl::WIDTH, 1, egl::HEIGHT, 1, egl::NONE])
                        .map_err(egl_err("creating a pbuffer"))?;
                    instance
                        .make_current(display, Some(s), Some(s), Some(context))
                        .map_err(egl_err("making current"))?;
                    Some(s)
                }
            }
        };
        // SAFETY: the context is current on this thread; EGL returns GL entry points for
        // it (EGL_KHR_get_all_proc_addresses), which glow loads by name.
        let mut gl = unsafe {
            glow::Context::from_loader_function(|name| {
                instance.get_proc_address(name).map_or(std::ptr::null(), |f| f as *const std::ffi::c_void)
            })
        };
        let clear_named_buffer_data = instance.get_proc_address("glClearNamedBufferData").map(|f| {
            // SAFETY: glClearNamedBufferData's signature in the GL 4.5 core specification is
            // `void (GLuint, GLenum, GLenum, GLenum, const void *)`, which this type spells.
            unsafe { std::mem::transmute::<extern "system" fn(), ClearNamedBufferData>(f) }
        });
        let clip_control = instance.get_proc_address("glClipControl").map(|f| {
            // SAFETY: glClipControl's signature in the GL 4.5 core specification is
            // `void (GLenum origin, GLenum depth)`, which this type spells.
            unsafe { std::mem::transmute::<extern "system" fn(), draw::ClipControl>(f) }
        });
        let provoking_vertex = instance.get_proc_address("glProvokingVertex").map(|f| {
            // SAFETY: glProvokingVertex's signature in the GL 3.2+ core specification is
            // `void (GLenum provokeMode)`, which this type spells.
            unsafe { std::mem::transmute::<extern "system" fn(), draw::ProvokingVertex>(f) }
        });
        let messages = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&messages);
        // SAFETY: the context is current; the callback only pushes the message into a
        // mutex-guarded list (it may be called from the driver's threads).
        let limits = unsafe {
            gl.enable(glow::DEBUG_OUTPUT);
            gl.debug_message_callback(move |_source, kind, _id, severity, msg| {
                // Failures are errors and undefined behaviour, whatever their severity.
                // Drivers also report advice at medium severity — NVIDIA's "Buffer
                // performance warning: … copied/moved from VIDEO memory to HOST memory"
                // for every read-back, "… being recompiled based on GL state" — which is
                // logged, not failed on (it failed every command on an H100, 2026-11-25).
                let failure = kind == glow::DEBUG_TYPE_ERROR || kind == glow::DEBUG_TYPE_UNDEFINED_BEHAVIOR;
                if failure {
                    if let Ok(mut m) = sink.lock()
                        && m.len() < 64
                    {
                        m.push(msg.to_string());
                    }
                } else if severity == glow::DEBUG_SEVERITY_HIGH {
                    log::warn!("GL: {msg}");
                } else {
                    log::debug!("GL: {msg}");
                }
            });
            let count = gl.get_parameter_i32(glow::NUM_EXTENSIONS).max(0) as u32;
            let extensions: Vec<String> =
                (0..count).map(|i| gl.get_parameter_indexed_string(glow::EXTENSIONS, i)).collect();
            let has_subgroups = extensions.iter().any(|e| e == "GL_KHR_shader_subgroup");
            Limits {
                renderer: gl.get_parameter_string(glow::RENDERER),
                version: gl.get_parameter_string(glow::VERSION),
                storage_blocks: gl.get_parameter_i32(glow::MAX_COMPUTE_SHADER_STORAGE_BLOCKS).max(0) as u32,
                storage_block_size: gl.get_parameter_i64(glow::MAX_SHADER_STORAGE_BLOCK_SIZE).max(0) as u64,
                uniform_block_size: gl.get_parameter_i64(glow::MAX_UNIFORM_BLOCK_SIZE).max(0) as u64,
                texture_size: gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE).max(0) as u32,
                texture_3d_size: gl.get_parameter_i32(glow::MAX_3D_TEXTURE_SIZE).max(0) as u32,
                shared_memory: gl.get_parameter_i32(glow::MAX_COMPUTE_SHARED_MEMORY_SIZE).max(0) as u32,
                subgroup_features: if has_subgroups {
                    gl.get_parameter_i32(SUBGROUP_SUPPORTED_FEATURES) as u32
                } else {
                    0
                },
                subgroup_size: if has_subgroups { gl.get_parameter_i32(SUBGROUP_SIZE).max(0) as u32 } else { 0 },
                extensions,
            }
        };
        // SAFETY: the context is current; a query object name is all glGenQueries makes.
        let queries: Vec<glow::NativeQuery> =
            unsafe { (0..clothlab_engine::solver::MAX_QUERIES).map(|_| gl.create_query()).collect::<Result<_, _>>() }
                .map_err(|e| GlError::Gl { what: "creating timestamp queries", reason: e })?;
        let me = Gl {
            egl: instance,
            display,
            context,
            surface,
            gl,
            clear_named_buffer_data,
            limits,
            robust,
            messages,
            objs: RefCell::new(Objects::default()),
            id: {
                static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
                NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            },
            clip_control,
            provoking_vertex,
            window,
            queries,
            _not_send: PhantomData,
        };
        me.check("creating the context")?;
        Ok(me)
    }

    /// What the context offers.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// This context's number, unique in the process.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Whether out-of-bounds shader accesses are contained (a robust-access context).
    pub fn robust(&self) -> bool {
        self.robust
    }

    /// The context, made current on this thread first if it is not.
    fn cur(&self) -> Result<&glow::Context, GlError> {
        if self.egl.get_current_context() != Some(self.context) {
            self.egl
                .make_current(self.display, self.surface, self.surface, Some(self.context))
                .map_err(egl_err("making the context current"))?;
        }
        Ok(&self.gl)
    }

    fn buf(&self, i: usize) -> Result<BufferObj, GlError> {
        self.objs.borrow().buffer(i).copied().ok_or(GlError::Invalid("no such GL buffer"))
    }

    fn tex(&self, i: usize) -> Result<TextureObj, GlError> {
        self.objs.borrow().textures.get(i).copied().flatten().ok_or(GlError::Invalid("no such GL texture"))
    }

    /// A buffer of `bytes.len()` bytes (at least 4) holding `bytes`, dynamic storage.
    pub fn create_buffer(&self, bytes: &[u8]) -> Result<usize, GlError> {
        let mut data = bytes.to_vec();
        data.resize(data.len().max(4).next_multiple_of(4), 0);
        let size = i32::try_from(data.len()).map_err(|_| GlError::Invalid("a GL buffer over 2 GiB"))?;
        let gl = self.cur()?;
        // SAFETY: the context is current; the buffer is bound to COPY_WRITE (no shader
        // binding point) for its storage, which is `size` bytes copied from `data`.
        let name = unsafe {
            let name = gl.create_buffer().map_err(|e| GlError::Gl { what: "creating a buffer", reason: e })?;
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, Some(name));
            gl.buffer_storage(glow::COPY_WRITE_BUFFER, size, Some(&data), glow::DYNAMIC_STORAGE_BIT);
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, None);
            name
        };
        let mut o = self.objs.borrow_mut();
        o.buffers.push(Some(BufferObj { name, size: data.len() as u64 }));
        let i = o.buffers.len() - 1;
        drop(o);
        self.check("creating a buffer")?;
        Ok(i)
    }

    /// The size of buffer `i`, bytes.
    pub fn buffer_size(&self, i: usize) -> Result<u64, GlError> {
        Ok(self.buf(i)?.size)
    }

    /// Writes `bytes` at `offset` in buffer `i` (in command order).
    pub fn write(&self, i: usize, offset: u64, bytes: &[u8]) -> Result<(), GlError> {
        let b = self.buf(i)?;
        if offset + bytes.len() as u64 > b.size {
            return Err(GlError::Invalid("a write past a GL buffer's end"));
        }
        let name = b.name;
        let gl = self.cur()?;
        // SAFETY: the context is current; the range lies inside the buffer (checked).
        unsafe {
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, Some(name));
            gl.buffer_sub_data_u8_slice(glow::COPY_WRITE_BUFFER, offset as i32, bytes);
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, None);
        }
        Ok(())
    }

    /// `len` bytes of buffer `i` from `at`, after every command before; a range past the
    /// end is refused.
    pub fn read(&self, i: usize, at: u64, len: u64) -> Result<Vec<u8>, GlError> {
        let b = self.buf(i)?;
        if at + len > b.size {
            return Err(GlError::Invalid("a read past a GL buffer's end"));
        }
        let name = b.name;
        let mut out = vec![0u8; len as usize];
        let gl = self.cur()?;
        // SAFETY: the context is current; GL writes `out.len()` bytes, all inside both
        // the buffer (checked) and `out`.
        unsafe {
            gl.bind_buffer(glow::COPY_READ_BUFFER, Some(name));
            gl.get_buffer_sub_data(glow::COPY_READ_BUFFER, at as i32, &mut out);
            gl.bind_buffer(glow::COPY_READ_BUFFER, None);
        }
        Ok(out)
    }

    /// Fills buffer `i` with zeros (glClearNamedBufferData, else a zero upload).
    pub fn clear(&self, i: usize) -> Result<(), GlError> {
        let b = self.buf(i)?;
        match self.clear_named_buffer_data {
            Some(clear) => {
                let name = b.name.0.get();
                self.cur()?;
                // SAFETY: the context is current; `name` is a buffer of this context; a
                // null data pointer fills with zeros (GL 4.5 §6.2.1), R32UI words.
                unsafe { clear(name, glow::R32UI, glow::RED_INTEGER, glow::UNSIGNED_INT, std::ptr::null()) };
                Ok(())
            }
            None => self.write(i, 0, &vec![0u8; b.size as usize]),
        }
    }

    /// Copies `size` bytes of `src` from `src_at` into `dst` at `dst_at`; a range past
    /// either buffer's end is refused.
    pub fn copy(&self, src: usize, src_at: u64, dst: usize, dst_at: u64, size: u64) -> Result<(), GlError> {
        let (a, b) = (self.buf(src)?, self.buf(dst)?);
        if src_at + size > a.size || dst_at + size > b.size {
            return Err(GlError::Invalid("a copy past a GL buffer's end"));
        }
        let (a, b) = (a.name, b.name);
        let gl = self.cur()?;
        // SAFETY: the context is current; both ranges lie inside their buffers (checked).
        unsafe {
            gl.bind_buffer(glow::COPY_READ_BUFFER, Some(a));
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, Some(b));
            gl.copy_buffer_sub_data(
                glow::COPY_READ_BUFFER,
                glow::COPY_WRITE_BUFFER,
                src_at as i32,
                dst_at as i32,
                size as i32,
            );
            gl.bind_buffer(glow::COPY_READ_BUFFER, None);
            gl.bind_buffer(glow::COPY_WRITE_BUFFER, None);
        }
        Ok(())
    }

    /// A `width`×`height` texture of `format` with one level, multisampled when
    /// `samples` > 1 (an attachment only); returns its index. Its sampling state comes
    /// from the sampler bound with it; a texture of integers (read by `texelFetch` in
    /// kernels, no sampler) gets NEAREST filters, without which it is incomplete.
    pub fn create_texture(&self, format: TexFormat, width: u32, height: u32, samples: u32) -> Result<usize, GlError> {
        if width == 0 || height == 0 || width > self.limits.texture_size || height > self.limits.texture_size {
            return Err(GlError::Invalid("a texture side of 0 or over GL_MAX_TEXTURE_SIZE"));
        }
        if !(1..=4).contains(&samples) {
            return Err(GlError::Invalid("a texture of other than 1 to 4 samples"));
        }
        let gl = self.cur()?;
        let target = if samples > 1 { glow::TEXTURE_2D_MULTISAMPLE } else { glow::TEXTURE_2D };
        // SAFETY: the context is current; immutable storage of the checked size, format
        // and sample count.
        let t = unsafe {
            let t = gl.create_texture().map_err(|e| GlError::Gl { what: "creating a texture", reason: e })?;
            gl.bind_texture(target, Some(t));
            if samples > 1 {
                gl.tex_storage_2d_multisample(
                    target,
                    samples as i32,
                    format.internal(),
                    width as i32,
                    height as i32,
                    true,
                );
            } else {
                gl.tex_storage_2d(target, 1, format.internal(), width as i32, height as i32);
                let filter = if format.integer() { glow::NEAREST } else { glow::LINEAR };
                gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, filter as i32);
                gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, filter as i32);
            }
            gl.bind_texture(target, None);
            t
        };
        let mut o = self.objs.borrow_mut();
        o.textures.push(Some(TextureObj { name: t, width, height, format, samples, depth: 0 }));
        let i = o.textures.len() - 1;
        drop(o);
        self.check("creating a texture")?;
        Ok(i)
    }

    /// A `width × height × depth` 3-D texture of `R32F` texels filled from `values` (x
    /// fastest), filtered linearly and clamped to the edge: the bodies' distance fields
    /// (`sdf=image`), sampled by compute programs.
    pub fn create_volume(&self, width: u32, height: u32, depth: u32, values: &[f32]) -> Result<usize, GlError> {
        let most = self.limits.texture_3d_size;
        if width == 0 || height == 0 || depth == 0 || width.max(height).max(depth) > most {
            return Err(GlError::Invalid("a 3-D texture side of 0 or over GL_MAX_3D_TEXTURE_SIZE"));
        }
        if values.len() != (width * height * depth) as usize {
            return Err(GlError::Invalid("values that do not fill the 3-D texture"));
        }
        let gl = self.cur()?;
        let t3 = glow::TEXTURE_3D;
        // SAFETY: the context is current; immutable storage of the checked size, then
        // `values` (exactly width × height × depth floats, checked) written into all of
        // it with the default unpack state (alignment 4 divides a float).
        let t = unsafe {
            let t = gl.create_texture().map_err(|e| GlError::Gl { what: "creating a texture", reason: e })?;
            gl.bind_texture(t3, Some(t));
            gl.tex_storage_3d(t3, 1, glow::R32F, width as i32, height as i32, depth as i32);
            for (what, v) in [
                (glow::TEXTURE_MIN_FILTER, glow::LINEAR),
                (glow::TEXTURE_MAG_FILTER, glow::LINEAR),
                (glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE),
                (glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE),
                (glow::TEXTURE_WRAP_R, glow::CLAMP_TO_EDGE),
            ] {
                gl.tex_parameter_i32(t3, what, v as i32);
            }
            gl.tex_sub_image_3d(
                t3,
                0,
                0,
                0,
                0,
                width as i32,
                height as i32,
                depth as i32,
                glow::RED,
                glow::FLOAT,
                glow::PixelUnpackData::Slice(Some(bytemuck::cast_slice(values))),
            );
            gl.bind_texture(t3, None);
            t
        };
        let mut o = self.objs.borrow_mut();
        o.textures.push(Some(TextureObj { name: t, width, height, format: TexFormat::R32f, samples: 1, depth }));
        let i = o.textures.len() - 1;
        drop(o);
        self.check("creating a 3-D texture")?;
        Ok(i)
    }

    /// Deletes texture `i` (its index is not reused; a later use is refused).
    pub fn delete_texture(&self, i: usize) -> Result<(), GlError> {
        let t = self.tex(i)?;
        let gl = self.cur()?;
        // SAFETY: the context is current; the name is this context's and is forgotten here.
        unsafe { gl.delete_texture(t.name) };
        self.objs.borrow_mut().textures[i] = None;
        Ok(())
    }

    /// Deletes buffer `i` (its index is not reused; a later use is refused).
    pub fn delete_buffer(&self, i: usize) -> Result<(), GlError> {
        let b = self.buf(i)?;
        let gl = self.cur()?;
        // SAFETY: the context is current; the name is this context's and forgotten here.
        unsafe { gl.delete_buffer(b.name) };
        self.objs.borrow_mut().buffers[i] = None;
        Ok(())
    }

    /// Deletes program `i` (its index is not reused; a later use is refused).
    pub fn delete_program(&self, i: usize) -> Result<(), GlError> {
        let p = self.objs.borrow_mut().programs.get_mut(i).and_then(Option::take);
        let p = p.ok_or(GlError::Invalid("no such GL program"))?;
        let gl = self.cur()?;
        // SAFETY: the context is current; the name is this context's, forgotten above.
        unsafe { gl.delete_program(p.program) };
        Ok(())
    }

    /// Writes the whole of single-sampled texture `i` from `bytes`, rows from the first
    /// (RGBA32UI: 16 bytes a texel; sRGB RGBA8: 4).
    pub fn write_texture(&self, i: usize, bytes: &[u8]) -> Result<(), GlError> {
        let t = self.tex(i)?;
        let (format, kind, size) = match t.format {
            TexFormat::Rgba32ui => (glow::RGBA_INTEGER, glow::UNSIGNED_INT, 16),
            TexFormat::Srgba8 => (glow::RGBA, glow::UNSIGNED_BYTE, 4),
            _ => return Err(GlError::Invalid("writing a depth or R32UI texture")),
        };
        if t.samples != 1 || bytes.len() != (t.width * t.height) as usize * size {
            return Err(GlError::Invalid("texels that do not fill the texture"));
        }
        let gl = self.cur()?;
        // SAFETY: the context is current; `bytes` holds exactly width×height texels of
        // the texture's format, read with the default unpack state (alignment 4 divides
        // both texel sizes).
        unsafe {
            gl.bind_texture(glow::TEXTURE_2D, Some(t.name));
            gl.tex_sub_image_2d(
                glow::TEXTURE_2D,
                0,
                0,
                0,
                t.width as i32,
                t.height as i32,
                format,
                kind,
                glow::PixelUnpackData::Slice(Some(bytes)),
            );
            gl.bind_texture(glow::TEXTURE_2D, None);
        }
        Ok(())
    }

    /// Compiles and links a compute program from `glsl`; `uniforms` are the names whose
    /// locations [`DispatchDesc::values`] refers to by index. The error is the driver's log.
    pub fn program(&self, glsl: &str, uniforms: &[&str]) -> Result<usize, String> {
        self.link(&[(glow::COMPUTE_SHADER, glsl)], uniforms)
    }

    /// Compiles `stages` (`(shader type, text)`), links them into a program and lists the
    /// locations of `uniforms`; the error is the driver's log.
    fn link(&self, stages: &[(u32, &str)], uniforms: &[&str]) -> Result<usize, String> {
        let gl = self.cur().map_err(|e| e.to_string())?;
        // SAFETY: the context is current; the shaders and program are made, used and
        // (the shaders) deleted here; strings are passed as slices glow sizes itself.
        let (program, locations) = unsafe {
            let program = gl.create_program()?;
            let mut made = Vec::new();
            for &(kind, text) in stages {
                let shader = gl.create_shader(kind)?;
                made.push(shader);
                gl.shader_source(shader, text);
                gl.compile_shader(shader);
                if !gl.get_shader_compile_status(shader) {
                    let log = gl.get_shader_info_log(shader);
                    made.into_iter().for_each(|s| gl.delete_shader(s));
                    gl.delete_program(program);
                    return Err(log.trim().to_string());
                }
                gl.attach_shader(program, shader);
            }
            gl.link_program(program);
            for shader in made {
                gl.detach_shader(program, shader);
                gl.delete_shader(shader);
            }
            if !gl.get_program_link_status(program) {
                let log = gl.get_program_info_log(program);
                gl.delete_program(program);
                return Err(log.trim().to_string());
            }
            let locations = uniforms.iter().map(|n| gl.get_uniform_location(program, n)).collect();
            (program, locations)
        };
        let mut o = self.objs.borrow_mut();
        o.programs.push(Some(Program { program, locations }));
        Ok(o.programs.len() - 1)
    }

    /// Binds what `d` names and dispatches it. Bad indices are refused before any call.
    pub fn dispatch(&self, d: &DispatchDesc<'_>) -> Result<(), GlError> {
        let o = self.objs.borrow();
        let p = o.program(d.program).ok_or(GlError::Invalid("no such GL program"))?;
        // Every index checked first (no allocation: this runs for every dispatch).
        // (Each binding's buffer is looked up again below, with no allocation: this runs
        // for every dispatch.)
        if d.storage.iter().chain(d.uniform).any(|&(_, i)| o.buffer(i).is_none()) {
            return Err(GlError::Invalid("no such GL buffer"));
        }
        if d.textures.iter().any(|&(_, i)| o.textures.get(i).is_none_or(|t| t.is_none_or(|t| t.samples != 1))) {
            return Err(GlError::Invalid("no such GL texture"));
        }
        let gl = self.cur()?;
        // SAFETY: the context is current; every name is an object of this context; a
        // uniform location is the program's own (or None, which GL ignores).
        unsafe {
            gl.use_program(Some(p.program));
            for &(pt, i) in d.storage {
                gl.bind_buffer_base(glow::SHADER_STORAGE_BUFFER, pt, o.buffer(i).map(|b| b.name));
            }
            for &(pt, i) in d.uniform {
                gl.bind_buffer_base(glow::UNIFORM_BUFFER, pt, o.buffer(i).map(|b| b.name));
            }
            for &(unit, i) in d.textures {
                gl.active_texture(glow::TEXTURE0 + unit);
                let t = o.textures[i];
                let target = if t.is_some_and(|t| t.depth > 0) { glow::TEXTURE_3D } else { glow::TEXTURE_2D };
                gl.bind_texture(target, t.map(|t| t.name));
                // A sampler object the renderer left on this unit would override the
                // texture's NEAREST filters (and make an integer texture incomplete).
                gl.bind_sampler(unit, None);
            }
            for &(i, v) in d.values {
                let loc = p.locations.get(i).and_then(|l| l.as_ref());
                match v {
                    Value::U(n, x) => gl.uniform_n_u32(n, loc, x),
                    Value::I(n, x) => gl.uniform_n_i32(n, loc, x),
                    Value::F(n, x) => gl.uniform_n_f32(n, loc, x),
                }
            }
            gl.dispatch_compute(d.groups.0, d.groups.1, d.groups.2);
        }
        Ok(())
    }

    /// glMemoryBarrier(`bits`).
    pub fn memory_barrier(&self, bits: u32) -> Result<(), GlError> {
        let gl = self.cur()?;
        // SAFETY: the context is current.
        unsafe { gl.memory_barrier(bits) };
        Ok(())
    }

    /// Records a timestamp into query `q` (glQueryCounter; ignored past the last query).
    pub fn timestamp(&self, q: u32) -> Result<(), GlError> {
        let Some(&query) = self.queries.get(q as usize) else { return Ok(()) };
        let gl = self.cur()?;
        // SAFETY: the context is current; the query is this context's.
        unsafe { gl.query_counter(query, glow::TIMESTAMP) };
        Ok(())
    }

    /// The timestamps of queries `0..n`, ns (waits for them).
    pub fn timestamps(&self, n: u32) -> Result<Vec<u64>, GlError> {
        let gl = self.cur()?;
        // SAFETY: the context is current; each query was written by glQueryCounter
        // before (an unwritten one is a GL error, reported by `check`, not UB).
        Ok(self
            .queries
            .iter()
            .take(n as usize)
            .map(|&q| unsafe { gl.get_query_parameter_u64(q, glow::QUERY_RESULT) })
            .collect())
    }

    /// glFlush: what is recorded starts.
    pub fn flush(&self) -> Result<(), GlError> {
        let gl = self.cur()?;
        // SAFETY: the context is current.
        unsafe { gl.flush() };
        Ok(())
    }

    /// glFinish: everything issued is done.
    pub fn finish(&self) -> Result<(), GlError> {
        let gl = self.cur()?;
        // SAFETY: the context is current.
        unsafe { gl.finish() };
        Ok(())
    }

    /// Shows what was drawn into the window's default framebuffer (eglSwapBuffers); a
    /// headless context has nothing to show.
    pub fn swap_buffers(&self) -> Result<(), GlError> {
        let Some(surface) = self.surface.filter(|_| self.window.is_some()) else {
            return Err(GlError::Invalid("swapping buffers of a context with no window"));
        };
        self.cur()?;
        self.egl.swap_buffers(self.display, surface).map_err(egl_err("swapping buffers"))
    }

    /// Whether the context draws into a window.
    pub fn has_window(&self) -> bool {
        self.window.is_some()
    }

    /// Fails with the GL errors and the debug messages since the last call.
    pub fn check(&self, what: &'static str) -> Result<(), GlError> {
        let gl = self.cur()?;
        let mut found = Vec::new();
        for _ in 0..16 {
            // SAFETY: the context is current.
            let e = unsafe { gl.get_error() };
            if e == glow::NO_ERROR {
                break;
            }
            found.push(format!("GL error 0x{e:04X}"));
        }
        if let Ok(mut m) = self.messages.lock() {
            found.append(&mut m);
        }
        if found.is_empty() { Ok(()) } else { Err(GlError::Gl { what, reason: found.join("; ") }) }
    }
}

/// glUniform{1,2,3,4}{ui,i,f} by component count.
trait UniformN {
    /// # Safety
    /// The context must be current and the location its current program's.
    unsafe fn uniform_n_u32(&self, n: u8, loc: Option<&glow::NativeUniformLocation>, x: [u32; 4]);
    /// # Safety
    /// As [`UniformN::uniform_n_u32`].
    unsafe fn uniform_n_i32(&self, n: u8, loc: Option<&glow::NativeUniformLocation>, x: [i32; 4]);
    /// # Safety
    /// As [`UniformN::uniform_n_u32`].
    unsafe fn uniform_n_f32(&self, n: u8, loc: Option<&glow::NativeUniformLocation>, x: [f32; 4]);
}

impl UniformN for glow::Context {
    unsafe fn uniform_n_u32(&self, n: u8, loc: Option<&glow::NativeUniformLocation>, x: [u32; 4]) {
        // SAFETY: as the caller promised (the context current, the location valid).
        unsafe {
            match n {
                1 => self.uniform_1_u32(loc, x[0]),
                2 => self.uniform_2_u32(loc, x[0], x[1]),
                3 => self.uniform_3_u32(loc, x[0], x[1], x[2]),
                _ => self.uniform_4_u32(loc, x[0], x[1], x[2], x[3]),
            }
        }
    }
    unsafe fn uniform_n_i32(&self, n: u8, loc: Option<&glow::NativeUniformLocation>, x: [i32; 4]) {
        // SAFETY: as the caller promised.
        unsafe {
            match n {
                1 => self.uniform_1_i32(loc, x[0]),
                2 => self.uniform_2_i32(loc, x[0], x[1]),
                3 => self.uniform_3_i32(loc, x[0], x[1], x[2]),
                _ => self.uniform_4_i32(loc, x[0], x[1], x[2], x[3]),
            }
        }
    }
    unsafe fn uniform_n_f32(&self, n: u8, loc: Option<&glow::NativeUniformLocation>, x: [f32; 4]) {
        // SAFETY: as the caller promised.
        unsafe {
            match n {
                1 => self.uniform_1_f32(loc, x[0]),
                2 => self.uniform_2_f32(loc, x[0], x[1]),
                3 => self.uniform_3_f32(loc, x[0], x[1], x[2]),
                _ => self.uniform_4_f32(loc, x[0], x[1], x[2], x[3]),
            }
        }
    }
}

impl Drop for Gl {
    fn drop(&mut self) {
        if self.egl.get_current_context() == Some(self.context) {
            let _ = self.egl.make_current(self.display, None, None, None);
        }
        // Destroying the context frees every object made in it (buffers, textures,
        // programs, queries); the display stays initialised for the process (other
        // contexts may use it; eglTerminate would end them too).
        let _ = self.egl.destroy_context(self.display, self.context);
        if let Some(s) = self.surface {
            let _ = self.egl.destroy_surface(self.display, s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headless() -> Option<Gl> {
        match Gl::headless() {
            Ok(g) => Some(g),
            Err(e) if std::env::var("CLOTHLAB_REQUIRE_GPU").as_deref() != Ok("1") => {
                eprintln!("skipped: {e}");
                None
            }
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn two_contexts_on_one_thread_keep_their_own_buffers_and_bad_ranges_are_refused() {
        let (Some(a), Some(b)) = (headless(), headless()) else { return };
        // Buffer 0 of each context: same index, different objects and contents.
        let ba = a.create_buffer(&[1u8; 16]).unwrap();
        let bb = b.create_buffer(&[2u8; 32]).unwrap();
        assert_eq!((ba, bb), (0, 0));
        // Interleaved use: each call must go to its own context (made current as needed).
        a.write(ba, 4, &[7u8; 4]).unwrap();
        b.write(bb, 0, &[9u8; 8]).unwrap();
        assert_eq!(a.read(ba, 0, 16).unwrap(), [1, 1, 1, 1, 7, 7, 7, 7, 1, 1, 1, 1, 1, 1, 1, 1]);
        assert_eq!(b.read(bb, 0, 8).unwrap(), [9u8; 8]);
        assert_eq!(b.buffer_size(bb).unwrap(), 32);
        // Ranges past an end and unknown objects are refused before any GL call.
        assert!(a.write(ba, 12, &[0u8; 8]).is_err());
        assert!(a.read(ba, 8, 16).is_err());
        assert!(a.copy(ba, 0, 5, 0, 4).is_err());
        assert!(a.write_texture(0, &[0; 16]).is_err());
        a.clear(ba).unwrap();
        assert_eq!(a.read(ba, 0, 16).unwrap(), [0u8; 16]);
        a.check("the test").unwrap();
        b.check("the test").unwrap();
        // Dropping one leaves the other working.
        drop(a);
        assert_eq!(b.read(bb, 0, 8).unwrap(), [9u8; 8]);
    }

    #[test]
    fn a_shader_the_driver_refuses_comes_back_with_its_log() {
        let Some(gl) = headless() else { return };
        let e =
            gl.program("#version 450 core\nlayout(local_size_x = 1) in;\nvoid main() { undefined_thing = 1; }\n", &[]);
        let log = e.unwrap_err();
        assert!(log.contains("undefined_thing"), "{log}");
    }
}
