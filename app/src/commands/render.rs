//! `clothlab render`: simulate headless, then draw the scene into a PNG.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clothlab_core::{CpuSolver, Exec, Solver};
use clothlab_gl::{GlCloth, GlContext, GlRenderer};
use clothlab_vulkan::{VkCloth, VulkanRenderer};
use clothlab_wgpu::{ClothSource, WgpuRenderer};

use crate::cli::RenderArgs;
use crate::out::outln;
use crate::solvers::{AnySolver, Api, Backend, GpuSetup, Shared, make, vulkan_validation};

/// Runs `render`.
pub fn render(args: RenderArgs) -> Result<ExitCode> {
    let setup = args.physics.setup(args.n, 100)?;
    let (scene, params) = (setup.scene.clone(), setup.params.clone());
    if args.frames > 100_000 {
        bail!("invalid --frames {}: must be in 0 ..= 100000", args.frames);
    }
    if !matches!(args.out.extension().and_then(|e| e.to_str()), Some("png" | "PNG")) {
        bail!("--out {}: the image is written as PNG, use a .png file name", args.out.display());
    }
    crate::files::check_writable(&args.out)?;
    let mut view = args.mode.view();
    if let Some(c) = setup.camera {
        view.camera = c;
    }
    if let Some(l) = setup.light {
        view.light = l;
    }
    let setup = GpuSetup { variant: args.variant.spec(args.backend)?, ..GpuSetup::default() };
    let api = args.api.or(args.backend.api()).unwrap_or(Api::Wgpu);
    if let Some(own) = args.backend.api()
        && own != api
    {
        bail!(
            "--backend {} draws through its own API: a GPU solver's buffers are drawn without a copy, so pick --api {} (or a CPU backend)",
            args.backend.name(),
            own.name()
        );
    }
    let (pixels, adapter) = match args.backend {
        Backend::Cpu | Backend::CpuPar => {
            let exec = if args.backend == Backend::Cpu { Exec::Serial } else { Exec::Parallel };
            let mut solver = CpuSolver::new(exec, scene.clone(), params)?;
            for _ in 0..args.frames {
                solver.step_frame()?;
            }
            // Moving colliders drawn where the last frame has them.
            let scene = scene.moved_to(solver.time());
            let (topo, state) = (solver.topology(), solver.state_ref());
            match api {
                Api::Vulkan => {
                    let dev = clothlab_vulkan::Device::new(vulkan_validation())?;
                    let mut r = VulkanRenderer::new(&dev, &scene, topo, args.width, args.height)?;
                    r.render(&view, VkCloth::Cpu(state))?;
                    (r.read_image()?, format!("{} (Vulkan)", dev.name()))
                }
                Api::Gl => {
                    let ctx = GlContext::headless()?;
                    let mut r = GlRenderer::new(&ctx, &scene, topo, args.width, args.height)?;
                    r.render(&ctx, &view, GlCloth::Cpu(state))?;
                    (r.read_image(&ctx)?, ctx.adapter())
                }
                Api::Wgpu => {
                    let ctx = clothlab_wgpu::GpuContext::new()?;
                    let mut r = WgpuRenderer::new(&ctx, &scene, topo, args.width, args.height)?;
                    r.render(&ctx, &view, ClothSource::Cpu(state))?;
                    (r.read_image(&ctx)?, ctx.describe())
                }
            }
        }
        _ => {
            let mut any = make(args.backend, scene.clone(), params.clone(), &setup, &Shared::None)?;
            for _ in 0..args.frames {
                any.get().step_frame()?;
            }
            let (_, topo) = clothlab_core::build(&scene, &params)?;
            let scene = scene.moved_to(any.get_ref().time());
            let adapter = any.adapter();
            match &mut any {
                AnySolver::Vulkan(solver, _) => {
                    let mut r = VulkanRenderer::new(&solver.engine().device(), &scene, &topo, args.width, args.height)?;
                    let (pos, normal) = solver.vertex_buffers();
                    r.render(&view, VkCloth::Gpu { pos, normal })?;
                    (r.read_image()?, adapter)
                }
                AnySolver::Wgpu(solver, _) => {
                    let ctx = solver.engine().context();
                    let mut r = WgpuRenderer::new(ctx, &scene, &topo, args.width, args.height)?;
                    let (pos, normal) = solver.vertex_buffers();
                    r.render(ctx, &view, ClothSource::Gpu { pos, normal })?;
                    (r.read_image(ctx)?, adapter)
                }
                AnySolver::Gl(solver) => {
                    let ctx = solver.engine().context();
                    let mut r = GlRenderer::new(ctx, &scene, &topo, args.width, args.height)?;
                    let (&pos, &normal) = solver.vertex_buffers();
                    r.render(ctx, &view, GlCloth::Gpu { pos, normal })?;
                    (r.read_image(ctx)?, adapter)
                }
                AnySolver::Cpu(_) => bail!("a CPU solver is drawn above"),
            }
        }
    };
    crate::files::write_png(&args.out, &pixels, args.width, args.height)?;
    outln!(
        "wrote {} ({}x{}, {} frames, {:?}, adapter {adapter})",
        args.out.display(),
        args.width,
        args.height,
        args.frames,
        args.mode
    )?;
    Ok(ExitCode::SUCCESS)
}
