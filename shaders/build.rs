//! Validates every WGSL kernel with naga (a shader error fails `cargo build`), checks that
//! the shared structs have the size and field offsets of clothlab-core's `#[repr(C)]`
//! types, and emits each kernel as WGSL (for wgpu) and SPIR-V 1.3 (for Vulkan) into
//! OUT_DIR, with `kernels.rs` listing them. The WGSL constants shared with Rust are
//! generated here from `clothlab_core::layout` and the step constants' struct from
//! `clothlab_core::step_params` (both put before `shared/types.wgsl` and the rest), and every `@binding(k)` of every kernel is checked against core's binding table
//! (`layout::Buf`): a number it does not know, or a uniform where it says storage, fails
//! the build.

use std::fmt::Write as _;
use std::fs;
use std::mem::{offset_of, size_of};
use std::path::{Path, PathBuf};

use clothlab_core::grid::{GridSpringConstants, Spring, SpringSlot, Tether};
use clothlab_core::layout::{BindKind, Buf, wgsl_constants};
use clothlab_core::pins::{PinPose, PinSlot};
use clothlab_core::scene::{Aabb, RodRecord, Sphere};
use clothlab_core::step_params::{ContactParams, StepParams};

/// A struct as core lays it out: name, size, and (field, offset) pairs.
type Layout = (&'static str, usize, Vec<(&'static str, usize)>);

include!("src/glsl_out.rs");

fn expected_layouts() -> Vec<Layout> {
    macro_rules! layout {
        ($t:ty, $name:literal, [$($f:ident),*]) => {
            ($name, size_of::<$t>(), vec![$((stringify!($f), offset_of!($t, $f))),*])
        };
    }
    vec![
        // Generated from the struct itself (clothlab_core::step_params): the WGSL names
        // and order are the Rust ones, the offsets naga gives WGSL's rules are checked.
        ("StepParams", StepParams::GPU_BYTES, StepParams::FIELDS.to_vec()),
        ("ContactParams", size_of::<ContactParams>(), ContactParams::FIELDS.to_vec()),
        layout!(SpringSlot, "SpringSlot", [neighbor, rest, ks, kd]),
        layout!(Spring, "Spring", [a, b, rest, ks, kd, kind]),
        layout!(Tether, "Tether", [pin, rest]),
        layout!(GridSpringConstants, "GridSpringConstants", [slots, enabled, _pad0, _pad1, _pad2]),
        layout!(Sphere, "Sphere", [center, radius, velocity, spin]),
        layout!(Aabb, "Aabb", [min, max, velocity]),
        layout!(RodRecord, "Rod", [a, b, velocity, spin]),
        layout!(PinSlot, "PinSlot", [rest, index, group, pad]),
        layout!(PinPose, "PinPose", [cols, translation, velocity, spin]),
    ]
}

fn fail(msg: String) -> ! {
    // cargo shows a build script's panic message; one clear failure.
    panic!("\n{msg}\n");
}

fn parse_and_validate(name: &str, source: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| fail(format!("{name}: WGSL parse error\n{}", e.emit_to_string_with_path(source, name))));
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    let info = validator
        .validate(&module)
        .unwrap_or_else(|e| fail(format!("{name}: invalid shader\n{}", e.emit_to_string_with_path(source, name))));
    (module, info)
}

fn check_layouts(types_src: &str) {
    let (module, _) = parse_and_validate("prelude (constants + shared/types.wgsl)", types_src);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap_or_else(|e| fail(format!("layout: {e}")));
    for (name, size, fields) in expected_layouts() {
        let Some((handle, ty)) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)) else {
            fail(format!("shared/types.wgsl has no struct {name}, which core defines"));
        };
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            fail(format!("{name} is not a struct in WGSL"));
        };
        let wgsl_size = layouter[handle].size.max(*span);
        if wgsl_size as usize != size {
            fail(format!("struct {name}: WGSL size {wgsl_size} bytes, core's #[repr(C)] size {size}"));
        }
        if members.len() != fields.len() {
            fail(format!("struct {name}: WGSL has {} fields, core {}", members.len(), fields.len()));
        }
        for (m, (field, offset)) in members.iter().zip(&fields) {
            if m.name.as_deref() != Some(*field) || m.offset as usize != *offset {
                fail(format!(
                    "struct {name}: WGSL field {:?} at offset {}, core has `{field}` at {offset}",
                    m.name, m.offset
                ));
            }
        }
    }
}

/// How kernels declare the step constants in the uniform buffer.
const UNIFORM_PARAMS: &str = "@group(0) @binding(0) var<uniform> step_params: StepParams;";
/// How the `_sto` twins declare them (at `layout::Buf::ParamsStorage`).
fn storage_params() -> String {
    format!("@group(0) @binding({}) var<storage, read> step_params: StepParams;", Buf::ParamsStorage.binding())
}

/// The single run's world offsets (`shared/types.wgsl`), which a `_w` twin makes private.
const WORLD_CONSTS: &str = "const world_base: u32 = 0u;\nconst face_base: u32 = 0u;\nconst world_index: u32 = 0u;";

/// A kernel's `_w` twin (`//! worlds` among its header lines): every world of a batch in
/// one dispatch, the world in the dispatch's z. The step constants come from the world's
/// element of an array in the storage buffer at `layout::Buf::ParamsStorage`, and the
/// kernel's first statement (`p = step_params;`) also sets where the world's particles and
/// faces start (`world_base`, `face_base`), which every access to a per-world buffer adds.
fn world_twin(name: &str, source: &str) -> String {
    const FIRST: &str = "    p = step_params;\n";
    if source.matches(FIRST).count() != 1 || !source.contains(UNIFORM_PARAMS) || !source.contains(WORLD_CONSTS) {
        fail(format!(
            "{name}: a `//! worlds` kernel reads the step constants from the uniform block once, as its first statement"
        ));
    }
    // A kernel's per-world setup beyond the offsets (shared/tri.wgsl's), after them.
    let begin = if source.contains("fn world_begin()") { "    world_begin();\n" } else { "" };
    source
        .replace(
            UNIFORM_PARAMS,
            &format!(
                "@group(0) @binding({}) var<storage, read> world_params: array<StepParams>;",
                Buf::ParamsStorage.binding()
            ),
        )
        .replace(WORLD_CONSTS, "var<private> world_base: u32;\nvar<private> face_base: u32;\nvar<private> world_index: u32;")
        .replace(
            FIRST,
            &format!(
                "    p = world_params[id.z];\n    world_index = id.z;\n    world_base = id.z * p.num_particles;\n    face_base = 2u * world_base;\n{begin}"
            ),
        )
}

/// The group-0 bindings the kernel's entry point reads and writes (atomics count as
/// both), each checked against core's [`Buf`] table: a number it does not know, or a
/// uniform where it says storage, fails the build. (The renderer's and the overhead
/// benchmark's bindings are not the step's and are not checked.)
fn bindings(name: &str, module: &naga::Module, info: &naga::valid::ModuleInfo) -> (Vec<u32>, Vec<u32>) {
    let (mut reads, mut writes) = (Vec::new(), Vec::new());
    if name == "render" || name == "chain" || module.entry_points.is_empty() {
        return (reads, writes);
    }
    let uses = info.get_entry_point(0);
    for (handle, g) in module.global_variables.iter() {
        let Some(rb) = &g.binding else { continue };
        let var = g.name.as_deref().unwrap_or("?");
        let Some(buf) = Buf::from_binding(rb.binding).filter(|_| rb.group == 0) else {
            fail(format!(
                "{name}: `{var}` at @group({}) @binding({}), which clothlab_core::layout::Buf does not have",
                rb.group, rb.binding
            ));
        };
        let kind = match g.space {
            naga::AddressSpace::Uniform => BindKind::Uniform,
            naga::AddressSpace::Storage { .. } => BindKind::Storage,
            naga::AddressSpace::Handle => match module.types[g.ty].inner {
                naga::TypeInner::Image { dim: naga::ImageDimension::D3, .. } => BindKind::Volume,
                naga::TypeInner::Sampler { .. } => BindKind::Sampler,
                _ => BindKind::Image,
            },
            other => fail(format!("{name}: `{var}` in address space {other:?} at a binding")),
        };
        if kind != buf.kind() {
            fail(format!(
                "{name}: `{var}` at @binding({}) is a {kind:?} binding, layout::Buf::{buf:?} is {:?}",
                rb.binding,
                buf.kind()
            ));
        }
        let used = uses[handle];
        let atomic = used.contains(naga::valid::GlobalUse::ATOMIC);
        // (arrayLength is a query of the binding's size, not of its data: no hazard.)
        if atomic || used.contains(naga::valid::GlobalUse::READ) {
            reads.push(rb.binding);
        }
        if atomic || used.contains(naga::valid::GlobalUse::WRITE) {
            writes.push(rb.binding);
        }
    }
    reads.sort();
    writes.sort();
    (reads, writes)
}

/// shared/colliders.wgsl with the spheres and boxes in uniform blocks of MAX_COLLIDERS
/// entries at `layout::Buf::SpheresUniform` and `BoxesUniform` (the thesis's constant
/// memory): `colliders=uniform`.
fn colliders_uniform(storage: &str) -> String {
    let swaps = [
        (
            format!("@group(0) @binding({}) var<storage, read> spheres: array<Sphere>;", Buf::Spheres.binding()),
            format!(
                "@group(0) @binding({}) var<uniform> spheres: array<Sphere, MAX_COLLIDERS>;",
                Buf::SpheresUniform.binding()
            ),
        ),
        (
            format!("@group(0) @binding({}) var<storage, read> boxes: array<Aabb>;", Buf::Boxes.binding()),
            format!(
                "@group(0) @binding({}) var<uniform> boxes: array<Aabb, MAX_COLLIDERS>;",
                Buf::BoxesUniform.binding()
            ),
        ),
    ];
    let mut s = storage.to_owned();
    for (from, to) in swaps {
        if !s.contains(&from) {
            fail(format!("shared/colliders.wgsl: expected the declaration `{from}`"));
        }
        s = s.replace(&from, &to);
    }
    s
}

/// shared/colliders.wgsl (or its uniform-block twin) with the bodies' fields sampled from
/// the 3-D image: its `body_sample` renamed `body_sample_storage` (kept, unused) and
/// shared/sdf_image.wgsl's bindings and `body_sample` after it: `sdf=image`.
fn sdf_image(colliders: &str, image: &str) -> String {
    const DEF: &str = "fn body_sample(";
    if !colliders.contains(DEF) {
        fail("shared/colliders.wgsl: expected `fn body_sample(`".into());
    }
    format!("{}\n// ---- shared/sdf_image.wgsl\n{image}", colliders.replace(DEF, "fn body_sample_storage("))
}

/// Validates `source`, writes it and its SPIR-V to `out`, and lists it in `list`.
fn emit(out: &Path, list: &mut String, name: &str, source: &str) {
    let (module, info) = parse_and_validate(&format!("{name}.wgsl"), source);
    let (reads, writes) = bindings(name, &module, &info);
    let uses = used_bindings(&module, &info).unwrap_or_else(|e| fail(format!("{name}: {e}")));
    // The render shader gets what wgpu does to WGSL for Vulkan: y flipped into Vulkan's
    // clip space, and a point size of 1 written (Vulkan leaves it undefined otherwise).
    let flags = if name == "render" {
        naga::back::spv::WriterFlags::ADJUST_COORDINATE_SPACE | naga::back::spv::WriterFlags::FORCE_POINT_SIZE
    } else {
        naga::back::spv::WriterFlags::empty()
    };
    let mut options = naga::back::spv::Options { lang_version: (1, 3), flags, ..Default::default() };
    if !zero_workgroup_memory(name) {
        options.zero_initialize_workgroup_memory = naga::back::spv::ZeroInitializeWorkgroupMemoryMode::None;
    }
    let words = naga::back::spv::write_vec(&module, &info, &options, None)
        .unwrap_or_else(|e| fail(format!("{name}: SPIR-V output failed: {e}")));
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    fs::write(out.join(format!("{name}.wgsl")), source).expect("write WGSL");
    fs::write(out.join(format!("{name}.spv")), bytes).expect("write SPIR-V");
    // Compute kernels also as GLSL 4.50 for OpenGL (issue 33), checked here like the
    // SPIR-V: a flavor naga cannot write fails the build.
    let compute = module.entry_points.iter().any(|e| e.stage == naga::ShaderStage::Compute && e.name == "main");
    let (glsl, points, uniforms) = if compute {
        glsl_450(&module, &info, zero_workgroup_memory(name)).unwrap_or_else(|e| fail(format!("{name}: {e}")))
    } else {
        (String::new(), Vec::new(), Vec::new())
    };
    fs::write(out.join(format!("{name}.glsl")), glsl).expect("write GLSL");
    // The render shader's entry points as GLSL too, for the OpenGL renderer: one text per
    // entry point (GL links a vertex and a fragment shader into a program).
    if name == "render" {
        let mut stages = String::from(
            "/// The render shader's entry points as GLSL 4.50 core for the OpenGL renderer: `(entry point, text)`.\npub const RENDER_GLSL: &[(&str, &str)] = &[\n",
        );
        for e in &module.entry_points {
            let text =
                glsl_450_stage(&module, &info, e.stage, &e.name).unwrap_or_else(|e| fail(format!("render: {e}")));
            let file = format!("render_{}.glsl", e.name);
            fs::write(out.join(&file), text).expect("write GLSL");
            writeln!(stages, "    ({:?}, include_str!(concat!(env!(\"OUT_DIR\"), \"/{file}\"))),", e.name)
                .expect("write to string");
        }
        stages.push_str("];\n");
        fs::write(out.join("render_glsl.rs"), stages).expect("write render_glsl.rs");
    }
    writeln!(
        list,
        "    Kernel {{ name: {name:?}, wgsl: include_str!(concat!(env!(\"OUT_DIR\"), \"/{name}.wgsl\")), \
         spirv: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{name}.spv\")), \
         glsl: include_str!(concat!(env!(\"OUT_DIR\"), \"/{name}.glsl\")), gl_points: &{points:?}, gl_uniforms: &{uniforms:?}, \
         reads: &{reads:?}, writes: &{writes:?}, uses: &{uses:?} }},"
    )
    .expect("write to string");
}

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    println!("cargo:rerun-if-changed={}", dir.display());
    let read_shared = |name: &str| {
        let p = dir.join("shared").join(format!("{name}.wgsl"));
        println!("cargo:rerun-if-changed={}", p.display());
        fs::read_to_string(&p).unwrap_or_else(|e| fail(format!("{}: {e}", p.display())))
    };
    // `colliders_uni`, the `_cu` twins' include, is shared/colliders.wgsl with the two
    // declarations swapped for uniform blocks (the same code after them).
    // `colliders_si` and `colliders_uni_si`, the `_si` twins' includes: the same with the
    // bodies' fields sampled from the 3-D image (shared/sdf_image.wgsl's body_sample).
    let shared = |name: &str| {
        let (base, image) = match name.strip_suffix("_si") {
            Some(b) => (b, true),
            None => (name, false),
        };
        let text =
            if base == "colliders_uni" { colliders_uniform(&read_shared("colliders")) } else { read_shared(base) };
        if image { sdf_image(&text, &read_shared("sdf_image")) } else { text }
    };
    let types = shared("types");
    // The constants shared with Rust, then the structs: every kernel starts with these.
    let prelude = format!("{}\n{}\n{}\n{types}", wgsl_constants(), StepParams::WGSL, ContactParams::WGSL);
    check_layouts(&prelude);
    let mut shared_list = String::from(
        "/// The shared files, by name (for kernels composed at run time).\npub const SHARED: &[(&str, &str)] = &[\n",
    );
    let mut shared_files: Vec<PathBuf> = fs::read_dir(dir.join("shared"))
        .unwrap_or_else(|e| fail(format!("shared/: {e}")))
        .flatten()
        .map(|e| e.path())
        .collect();
    shared_files.sort();
    for path in shared_files {
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else { continue };
        if stem == "types" || path.extension().is_none_or(|x| x != "wgsl") {
            continue;
        }
        writeln!(shared_list, "    ({stem:?}, include_str!({:?})),", path.display().to_string())
            .expect("write to string");
    }
    for generated in ["colliders_uni", "colliders_si", "colliders_uni_si"] {
        fs::write(out.join(format!("{generated}.wgsl")), shared(generated)).expect("write a generated include");
        writeln!(shared_list, "    ({generated:?}, include_str!(concat!(env!(\"OUT_DIR\"), \"/{generated}.wgsl\"))),")
            .expect("write to string");
    }
    shared_list.push_str("];\n");
    fs::write(out.join("prelude.wgsl"), &prelude).expect("write prelude");

    let mut kernels: Vec<PathBuf> = fs::read_dir(&dir)
        .unwrap_or_else(|e| fail(format!("{}: {e}", dir.display())))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
        .collect();
    kernels.sort();
    let mut list = String::from("/// Every kernel, by name.\npub const KERNELS: &[Kernel] = &[\n");
    for path in kernels {
        println!("cargo:rerun-if-changed={}", path.display());
        let name = path.file_stem().and_then(|s| s.to_str()).expect("utf-8 file name").to_owned();
        let body = fs::read_to_string(&path).unwrap_or_else(|e| fail(format!("{}: {e}", path.display())));
        // `//! include: a, b` on the first line pulls in shared/a.wgsl, shared/b.wgsl.
        let includes: Vec<String> = body
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("//! include:"))
            .map(|list| list.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect())
            .unwrap_or_default();
        // A kernel using compare-exchange float addition also gets a `<name>_f32` twin
        // using float atomics; one reading the spring table from storage buffers a `_tex`
        // twin reading it from a sampled image; one reading the colliders from storage a
        // `_cu` twin reading them from uniform blocks. Every combination of the substitutions a kernel's includes allow (each suffix in
        // this order, as clothlab_engine::kernels::KernelRef::shader_name writes them). A
        // kernel with shared/window.wgsl also gets `<name>_sh`, passing its window's
        // neighbours by subgroup shuffles (shared/window_sh.wgsl).
        // A kernel with the colliders also gets `_si` twins (after `_cu`: `colliders` or
        // `colliders_uni` becomes `…_si`), sampling the bodies' fields from a 3-D image.
        let subs = [
            ("atomic_cas", "atomic_f32", "_f32"),
            ("table", "table_tex", "_tex"),
            ("colliders", "colliders_uni", "_cu"),
            ("colliders", "_si", "_si"),
            ("window", "window_sh", "_sh"),
        ];
        // `//! no table image` on the second line: a kernel that includes the table only
        // for shared functions it does not call (the tiled substep reads the grid's
        // constants from the uniform block) gets no `_tex` twin.
        let no_tex = body.lines().nth(1).is_some_and(|l| l.trim() == "//! no table image");
        // `//! worlds` among the header lines: the kernel also runs a batch of worlds, as
        // `<name>…_w` twins ([`world_twin`]).
        let worlds = body.lines().take_while(|l| l.starts_with("//!")).any(|l| l.trim() == "//! worlds");
        let applicable: Vec<_> = subs
            .iter()
            .filter(|(from, ..)| includes.iter().any(|i| i == from) && !(no_tex && *from == "table"))
            .collect();
        let mut variants = Vec::new();
        for mask in 0..1u32 << applicable.len() {
            let mut vname = name.clone();
            let mut incs = includes.clone();
            for (k, (from, to, suffix)) in applicable.iter().enumerate() {
                if mask & (1 << k) != 0 {
                    vname.push_str(suffix);
                    if *suffix == "_si" {
                        incs.iter_mut().filter(|i| i.starts_with("colliders")).for_each(|i| i.push_str("_si"));
                    } else {
                        incs.iter_mut().filter(|i| *i == from).for_each(|i| *i = (*to).to_owned());
                    }
                }
            }
            // (Float atomics and the table image never meet: the registry's flavors have
            // one or the other, the image winning.)
            if !(vname.contains("_f32") && vname.contains("_tex")) {
                variants.push((vname, incs));
            }
        }
        for (vname, incs) in variants {
            let mut source = prelude.clone();
            for inc in &incs {
                source.push_str(&format!("\n// ---- shared/{inc}.wgsl\n"));
                source.push_str(&shared(inc));
            }
            source.push_str(&format!("\n// ---- {name}.wgsl\n"));
            source.push_str(&body);
            emit(&out, &mut list, &vname, &source);
            // A kernel that reads the step constants from the uniform buffer also gets a
            // `<name>_imm` twin reading them from immediates (push constants), unless it
            // uses immediates for something else already.
            // And a `<name>_sto` twin reading them from a storage buffer (`constants=storage`).
            if source.contains(UNIFORM_PARAMS) && !source.contains("var<immediate>") {
                let imm = source.replace(UNIFORM_PARAMS, "var<immediate> step_params: StepParams;");
                emit(&out, &mut list, &format!("{vname}_imm"), &imm);
                let sto = source.replace(UNIFORM_PARAMS, &storage_params());
                emit(&out, &mut list, &format!("{vname}_sto"), &sto);
            }
            if worlds {
                emit(&out, &mut list, &format!("{vname}_w"), &world_twin(&vname, &source));
            }
        }
    }
    list.push_str("];\n");
    list.push_str(&shared_list);
    fs::write(out.join("kernels.rs"), list).expect("write kernels.rs");
}
