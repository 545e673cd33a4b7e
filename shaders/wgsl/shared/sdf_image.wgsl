// The bodies' distance fields in one 3-D image (`sdf=image`, layout::Buf::SdfImage: the
// thesis's texture memory, where the texture unit interpolates). Not an include of its
// own: shaders/build.rs appends it to shared/colliders.wgsl for the `_si` twins, whose
// `body_sample` it replaces. Body k's grid lies in the image's slices z0 … z0 + nz − 1
// (z0: the slices of the bodies before it), from the image's corner in x and y
// (clothlab_engine::tables::sdf_texels lays it out).

@group(0) @binding(35) var sdf_image: texture_3d<f32>;
@group(0) @binding(36) var sdf_sampler: sampler;

// The field at t, in texels of the image (texel (i, j, k) holds grid point (i, j, k)),
// interpolated by the texture unit: its weights have a few bits (8 on llvmpipe and
// NVIDIA, at least 4 by Vulkan's rules), so the value is within 3·h·2^-(bits+1) of the
// storage path's interpolant (h: the grid's cell; neighbouring values differ by ≤ h).
fn sdf_texel(t: vec3<f32>, size: vec3<f32>) -> f32 {
    return textureSampleLevel(sdf_image, sdf_sampler, (t + vec3<f32>(0.5)) / size, 0.0).x;
}

// Texel t of the image, as stored.
fn sdf_load(t: vec3<i32>) -> f32 {
    return textureLoad(sdf_image, t, 0).x;
}

// Body k's field at x (core::cpu::collide::body_sample's contract): where the cell's
// first texel leaves φ possibly below reach, φ from one filtered sample (the texture unit
// interpolates), and the direction to push from the cell's eight texels, the gradient of
// the interpolant as the storage path takes it (`cell_gradient`: the same values, the
// same arithmetic, so the same normal); `valid` false outside its grid or where φ ≥ reach
// (nothing to push). (Central differences of six more filtered samples were tried first:
// as cheap, but their normal leaves the interpolant's by up to 0.75 of a cell in a push
// from deep inside.)
fn body_sample(k: u32, x: vec3<f32>, reach: f32) -> BodySample {
    var out = BodySample(0.0, vec3<f32>(0.0, 1.0, 0.0), false);
    let at = body_at(k, x);
    if !at.inside {
        return out;
    }
    let g = at.g;
    let top = at.top;
    let h = at.h;
    var z0 = 0u;
    for (var j = 0u; j < k; j++) {
        z0 += bitcast<u32>(shapes[j * SDF_HEAD_FLOATS + 30u]);
    }
    // The storage path's band skip (core::sdf::BAND_CELLS): one texel, not a filtered
    // sample, where the cell's first corner shows φ ≥ reach all over the cell.
    let c = min(floor(g), top - vec3<f32>(1.0));
    let t = vec3<i32>(i32(c.x), i32(c.y), i32(c.z) + i32(z0));
    let c000 = sdf_load(t);
    if c000 - 1.75 * h >= reach {
        return out;
    }
    let size = vec3<f32>(textureDimensions(sdf_image));
    out.phi = sdf_texel(g + vec3<f32>(0.0, 0.0, f32(z0)), size);
    if out.phi >= reach {
        return out;
    }
    let f = g - c;
    let c100 = sdf_load(t + vec3<i32>(1, 0, 0));
    let c010 = sdf_load(t + vec3<i32>(0, 1, 0));
    let c110 = sdf_load(t + vec3<i32>(1, 1, 0));
    let c001 = sdf_load(t + vec3<i32>(0, 0, 1));
    let c101 = sdf_load(t + vec3<i32>(1, 0, 1));
    let c011 = sdf_load(t + vec3<i32>(0, 1, 1));
    let c111 = sdf_load(t + vec3<i32>(1, 1, 1));
    out.n = body_normal(k, cell_gradient(c000, c100, c010, c110, c001, c101, c011, c111, f));
    out.valid = true;
    return out;
}
