//! Several cloths in one scene (`[[cloth]]`, issue 44): one particle array with a range per
//! cloth, each cloth's pins, velocity, mass and tethers its own; bad input refused in one
//! line naming the cloth.

use clothlab_core::{SceneFile, SimParams, build};

/// The scene file `text` as if it lay in scenes/ (so `meshes/…` names the scenes' meshes).
fn parse(text: &str) -> Result<SceneFile, String> {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/test.toml");
    SceneFile::parse(text, file).map_err(|e| e.to_string())
}

const THREE: &str = r#"
[[cloth]]
n = 6
size = 0.5
top_center = [0.0, 1.0, 0.0]
velocity = [0.5, 0.0, 0.0]

[[cloth]]
n = 4
size = 0.3
top_center = [1.0, 1.0, 0.0]
down = [0.0, -1.0, 0.0]
pinning = "top-edge"
mass = 0.2

[[cloth]]
mesh = "meshes/fan.obj"
translate = [0.0, 2.0, 0.0]
pinning = { vertices = [0] }
velocity = [0.0, -1.0, 0.0]
mass = 1.5
"#;

#[test]
fn several_cloths_are_one_array_with_a_range_pins_velocity_and_mass_each() {
    let file = parse(THREE).unwrap();
    let placed = file.scene.cloth.mesh_data.as_ref().expect("several cloths run as one mesh");
    let parts = &placed.parts;
    assert_eq!(parts.len(), 3);
    // Ranges one after another: 36, 16 and the fan's 513 particles.
    assert_eq!(parts.iter().map(|p| (p.first, p.count)).collect::<Vec<_>>(), [(0, 36), (36, 16), (52, 513)]);
    assert_eq!(parts.iter().map(|p| p.triangles).collect::<Vec<_>>(), [50, 18, 960]);
    assert_eq!(file.scene.num_particles(), 565);

    let params = SimParams { cloth_mass: 0.5, ..file.params.clone() };
    let (state, topo) = build(&file.scene, &params).unwrap();
    assert_eq!(topo.parts().len(), 3);
    // Pins: the first grid's top corners, the second's top edge, the fan's centre.
    let pinned: Vec<usize> = (0..565).filter(|&k| state.pos[k][3] == 0.0).collect();
    assert_eq!(pinned, [0, 5, 36, 37, 38, 39, 52]);
    // Velocities: each cloth's own, pinned particles still.
    assert_eq!(state.vel[1][..3], [0.5, 0.0, 0.0]);
    assert_eq!(state.vel[40][..3], [0.0, 0.0, 0.0]);
    assert_eq!(state.vel[53][..3], [0.0, -1.0, 0.0]);
    // Masses: a cloth without one weighs cloth_mass; pos.w is the mean mass over the
    // particle's, so each cloth's masses add up to its own (within f32 sums, 1e-5).
    let mesh = topo.mesh.as_ref().unwrap();
    let total = |r: std::ops::Range<usize>| r.map(|k| mesh.mass[k] as f64).sum::<f64>();
    for (part, want) in parts.iter().zip([0.5, 0.2, 1.5]) {
        let m = total(part.range());
        assert!((m - want).abs() < 1e-5 * want, "{}: {m} kg, want {want}", part.label);
    }
    let mean = params.cloth_mass / 565.0;
    for k in [1usize, 40, 300] {
        let w = state.pos[k][3];
        assert!((mean / w - mesh.mass[k]).abs() <= 1e-6 * mesh.mass[k], "particle {k}: w {w}");
    }
    // Tethers hold a particle to pins of its own cloth only.
    for (c, part) in parts.iter().enumerate() {
        for k in part.range() {
            for t in topo.tethers[k].iter().filter(|t| t.pin >= 0) {
                assert!(part.range().contains(&(t.pin as usize)), "cloth {c}: particle {k} tethered to {}", t.pin);
            }
        }
    }
    // No spring joins two cloths.
    for s in &topo.springs {
        let of = |v: u32| parts.iter().position(|p| p.range().contains(&(v as usize)));
        assert_eq!(of(s.a), of(s.b), "spring {s:?}");
    }
    // The renderers tell the cloths apart by their texture coordinates' u, moved by 64
    // a cloth (the fabric repeats).
    let uv = topo.render_uvs();
    assert_eq!(uv[1][0] - topo.uv[1][0], 0.0);
    assert_eq!(uv[40][0] - topo.uv[40][0], 64.0);
    assert_eq!(uv[300][0] - topo.uv[300][0], 128.0);
}

#[test]
fn bad_cloths_are_refused_in_one_line_naming_the_cloth() {
    let second_grid = |extra: &str| format!("[[cloth]]\nn = 6\n\n[[cloth]]\n{extra}\n");
    for (text, want) in [
        (second_grid("n = 1"), "test.toml:5:5: `cloth[1].n` = 1: grid side must be in"),
        (second_grid("n = 6\nmass = -1.0"), "test.toml:6:8: `cloth[1].mass` = -1"),
        (
            second_grid("n = 6\npinning = [[9, 0]]"),
            "`cloth[1].pinning[0]` = [9, 0]: a grid point [i, j] needs i, j < n = 6",
        ),
        (second_grid("mesh = \"meshes/fan.obj\"\nsize = 2.0"), "test.toml:6:8: `cloth[1].size` is the grid's"),
        (second_grid("mesh = \"meshes/nothing.obj\""), "test.toml:5:8: `cloth[1].mesh`:"),
        (second_grid("mesh = \"meshes/fan.obj\"\npinning = { vertices = [9999] }"), "cloth[1].pinning"),
        (second_grid("nn = 6"), "test.toml:5:1: unknown field `nn`"),
        (
            "[cloth]\nn = 6\nmass = 0.3\n".into(),
            "test.toml:3:8: `cloth.mass`: a scene's one cloth weighs `[params] cloth_mass`",
        ),
        ("cloth = []\n".into(), "`cloth`: no cloth in the list"),
    ] {
        let e = parse(&text).expect_err(&text);
        assert!(e.contains(want), "{text:?}:\n{e}");
        assert!(!e.contains('\n'), "{e}");
    }
}

#[test]
fn the_two_cloth_scene_loads_a_grid_each() {
    let file = SceneFile::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/two-cloths.toml")))
        .unwrap();
    let parts = &file.scene.cloth.mesh_data.as_ref().unwrap().parts;
    assert_eq!(parts.iter().map(|p| (p.count, p.grid)).collect::<Vec<_>>(), [(84 * 84, true), (67 * 67, true)]);
    // Self-collision's thickness sits between 0.71 and 1 spacing of both (see the file).
    let spacing = [2.0 / 83.0, 1.6 / 66.0];
    for h in spacing {
        assert!(file.params.self_thickness > 0.71 * h && file.params.self_thickness < h, "{h}");
    }
}
