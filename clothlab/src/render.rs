//! Pictures of a solver's cloth: drawn offscreen by one of the renderers (wgpu, raw Vulkan,
//! raw OpenGL) and read back as RGBA8. A GPU solver is drawn from its own buffers by its
//! own API; a CPU solver's state is uploaded to whichever API is asked for.

use anyhow::{Result, bail};
use clothlab_core::{OrbitCamera, RenderMode, Scene, View};
use clothlab_gl::{GlCloth, GlContext, GlRenderer};
use clothlab_vulkan::{VkCloth, VulkanRenderer};
use clothlab_wgpu::{ClothSource, WgpuRenderer};

use crate::backend::{AnySolver, Api, vulkan_validation};

/// The default view of a scene in `mode`: the orbit camera's start and a light above and
/// in front.
pub fn default_view(mode: RenderMode) -> View {
    View { camera: OrbitCamera::default(), light: [2.0, 5.5, 3.0], mode }
}

/// Draws `solver`'s cloth in `scene` (its colliders where they are at the solver's time)
/// into a `width × height` RGBA8 image, row by row from the top, through `api` (default:
/// the solver's own API, wgpu for a CPU solver). Returns the pixels and the adapter that
/// drew them. A GPU solver is drawn by its own API only (its buffers, no copy). The
/// renderer refuses a size it cannot draw (0, or over the API's largest target).
pub fn image(
    solver: &mut AnySolver,
    scene: &Scene,
    view: &View,
    (width, height): (u32, u32),
    api: Option<Api>,
) -> Result<(Vec<u8>, String)> {
    let own = match solver {
        AnySolver::Cpu(_) => None,
        AnySolver::Wgpu(..) => Some(Api::Wgpu),
        AnySolver::Vulkan(..) => Some(Api::Vulkan),
        AnySolver::Gl(_) => Some(Api::Gl),
    };
    let api = api.or(own).unwrap_or(Api::Wgpu);
    if let Some(own) = own
        && own != api
    {
        bail!(
            "a {} solver draws through its own API: its buffers are drawn without a copy, so pick the {} renderer (or a CPU backend)",
            own.name(),
            own.name()
        );
    }
    // Moving colliders drawn where the solver's time has them.
    let scene = scene.moved_to(solver.get_ref().time());
    let adapter = solver.adapter();
    Ok(match solver {
        AnySolver::Cpu(s) => {
            let (state, topo) = (s.state_ref(), s.topology());
            match api {
                Api::Vulkan => {
                    let dev = clothlab_vulkan::Device::new(vulkan_validation())?;
                    let mut r = VulkanRenderer::new(&dev, &scene, topo, width, height)?;
                    r.render(view, VkCloth::Cpu(state))?;
                    (r.read_image()?, format!("{} (Vulkan)", dev.name()))
                }
                Api::Gl => {
                    let ctx = GlContext::headless()?;
                    let mut r = GlRenderer::new(&ctx, &scene, topo, width, height)?;
                    r.render(&ctx, view, GlCloth::Cpu(state))?;
                    (r.read_image(&ctx)?, ctx.adapter())
                }
                Api::Wgpu => {
                    let ctx = clothlab_wgpu::GpuContext::new()?;
                    let mut r = WgpuRenderer::new(&ctx, &scene, topo, width, height)?;
                    r.render(&ctx, view, ClothSource::Cpu(state))?;
                    (r.read_image(&ctx)?, ctx.describe())
                }
            }
        }
        AnySolver::Vulkan(s, _) => {
            let mut r = VulkanRenderer::new(&s.engine().device(), &scene, s.topology(), width, height)?;
            let (pos, normal) = s.vertex_buffers();
            r.render(view, VkCloth::Gpu { pos, normal })?;
            (r.read_image()?, adapter)
        }
        AnySolver::Wgpu(s, _) => {
            let ctx = s.engine().context();
            let mut r = WgpuRenderer::new(ctx, &scene, s.topology(), width, height)?;
            let (pos, normal) = s.vertex_buffers();
            r.render(ctx, view, ClothSource::Gpu { pos, normal })?;
            (r.read_image(ctx)?, adapter)
        }
        AnySolver::Gl(s) => {
            let ctx = s.engine().context();
            let mut r = GlRenderer::new(ctx, &scene, s.topology(), width, height)?;
            let (&pos, &normal) = s.vertex_buffers();
            r.render(ctx, view, GlCloth::Gpu { pos, normal })?;
            (r.read_image(ctx)?, adapter)
        }
    })
}
