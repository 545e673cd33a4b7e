// The scene renderer (wgpu): shadow pass, lit main pass, flat lines/points.
// Entry points: vs_static / vs_cloth (main pass), vs_shadow_static / vs_shadow_cloth
// (depth from the light), fs_lit, fs_flat.

struct Frame {
    view_proj: mat4x4<f32>,
    light_view_proj: mat4x4<f32>,
    // xyz light position, w unused
    light_pos: vec4<f32>,
    // xyz eye position, w unused
    eye: vec4<f32>,
    // x shadow-map texel size, y depth bias, z cloth material, w unused
    misc: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var shadow_map: texture_depth_2d;
@group(1) @binding(1) var shadow_sampler: sampler_comparison;
@group(1) @binding(2) var fabric: texture_2d<f32>;
@group(1) @binding(3) var fabric_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) material: u32,
}

// Static geometry: floor (material 0), spheres (1), boxes (2).
@vertex
fn vs_static(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) uv: vec2<f32>, @location(3) material: u32) -> VsOut {
    var o: VsOut;
    o.clip = frame.view_proj * vec4<f32>(pos, 1.0);
    o.world = pos;
    o.normal = normal;
    o.uv = uv;
    o.material = material;
    return o;
}

// The cloth, straight from the solver's position and normal buffers (vec4 each).
@vertex
fn vs_cloth(@location(0) pos: vec4<f32>, @location(1) normal: vec4<f32>, @location(2) uv: vec2<f32>) -> VsOut {
    var o: VsOut;
    o.clip = frame.view_proj * vec4<f32>(pos.xyz, 1.0);
    o.world = pos.xyz;
    o.normal = normal.xyz;
    o.uv = uv;
    o.material = 3u;
    return o;
}

@vertex
fn vs_shadow_static(@location(0) pos: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.light_view_proj * vec4<f32>(pos, 1.0);
}

@vertex
fn vs_shadow_cloth(@location(0) pos: vec4<f32>) -> @builtin(position) vec4<f32> {
    return frame.light_view_proj * vec4<f32>(pos.xyz, 1.0);
}

// Fraction of light reaching `world` (1 lit, 0 shadowed), 5×5 PCF.
fn shadow(world: vec3<f32>, n: vec3<f32>, l: vec3<f32>) -> f32 {
    let lc = frame.light_view_proj * vec4<f32>(world, 1.0);
    let ndc = lc.xyz / lc.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) || ndc.z > 1.0 {
        return 1.0;
    }
    // Slope-scaled bias: more where the surface is grazed by the light.
    let bias = frame.misc.y * (1.0 + 2.0 * (1.0 - clamp(dot(n, l), 0.0, 1.0)));
    let texel = frame.misc.x;
    var lit = 0.0;
    for (var y = -2; y <= 2; y++) {
        for (var x = -2; x <= 2; x++) {
            lit += textureSampleCompareLevel(shadow_map, shadow_sampler, uv + vec2<f32>(f32(x), f32(y)) * texel, ndc.z - bias);
        }
    }
    return lit / 25.0;
}

fn base_color(material: u32, world: vec3<f32>, uv: vec2<f32>) -> vec3<f32> {
    switch material {
        case 0u: {
            // Floor: a soft checkerboard, 0.5 m squares.
            let c = (i32(floor(world.x * 2.0)) + i32(floor(world.z * 2.0))) & 1;
            return select(vec3<f32>(0.55, 0.55, 0.58), vec3<f32>(0.72, 0.72, 0.74), c == 0);
        }
        case 1u: {
            return vec3<f32>(0.75, 0.22, 0.16);
        }
        case 2u: {
            return vec3<f32>(0.25, 0.45, 0.7);
        }
        default: {
            let fabric = textureSample(fabric, fabric_sampler, uv * 8.0).rgb;
            // Cloth k of several: its u moved by CLOTH_UV_STEP · k (clothlab_core's
            // ClothTopology::render_uvs; the fabric repeats), tinted its own colour. One
            // cloth, or the first, keeps the fabric's.
            let k = i32(round(uv.x / CLOTH_UV_STEP));
            if k <= 0 {
                return fabric;
            }
            let tints = array<vec3<f32>, 5>(
                vec3<f32>(0.95, 0.5, 0.2),
                vec3<f32>(0.35, 0.75, 0.35),
                vec3<f32>(0.9, 0.8, 0.3),
                vec3<f32>(0.65, 0.4, 0.85),
                vec3<f32>(0.85, 0.3, 0.45),
            );
            let grey = dot(fabric, vec3<f32>(0.3, 0.59, 0.11));
            return min(grey * 2.2 * tints[(k - 1) % 5], vec3<f32>(1.0));
        }
    }
}

// clothlab_core::grid::RENDER_UV_STEP.
const CLOTH_UV_STEP: f32 = 64.0;

// Blinn-Phong with one point light, shadowed, plus ambient; the cloth is lit on both sides.
@fragment
fn fs_lit(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var n = normalize(in.normal);
    if in.material == 3u && !front {
        n = -n;
    }
    let l = normalize(frame.light_pos.xyz - in.world);
    let v = normalize(frame.eye.xyz - in.world);
    let h = normalize(l + v);
    let albedo = base_color(in.material, in.world, in.uv);
    let diffuse = max(dot(n, l), 0.0);
    var shininess = 48.0;
    var spec_strength = 0.25;
    if in.material == 3u {
        shininess = 12.0;
        spec_strength = 0.08;
    }
    let specular = spec_strength * pow(max(dot(n, h), 0.0), shininess) * select(0.0, 1.0, diffuse > 0.0);
    let s = shadow(in.world, n, l);
    let color = albedo * (0.25 + 0.75 * diffuse * s) + vec3<f32>(specular * s);
    return vec4<f32>(color, 1.0);
}

// Lines and points: one flat colour.
@fragment
fn fs_flat(in: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(0.12, 0.16, 0.3, 1.0);
}

// Picking: particle id + 1 of the provoking vertex of the cloth triangle under each pixel,
// 0 where the floor, a sphere, a box or nothing is.
struct PickOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
}

@vertex
fn vs_pick_cloth(@location(0) pos: vec4<f32>, @builtin(vertex_index) vid: u32) -> PickOut {
    var o: PickOut;
    o.clip = frame.view_proj * vec4<f32>(pos.xyz, 1.0);
    o.id = vid + 1u;
    return o;
}

@vertex
fn vs_pick_static(@location(0) pos: vec3<f32>) -> PickOut {
    var o: PickOut;
    o.clip = frame.view_proj * vec4<f32>(pos, 1.0);
    o.id = 0u;
    return o;
}

@fragment
fn fs_pick(in: PickOut) -> @location(0) u32 {
    return in.id;
}
