// Radiosity display: the element mesh rasterized with its Gouraud colours (radiance at the
// vertices, emission included, interpolated across each element) as float bits in an
// integer target (renderable everywhere, GL included); back faces are black (elements are
// one-sided). `resolve` box-filters each pixel's S x S sub-samples (S = rad_size[2], 1
// without supersampling; the target holds S x S tiles of the image, tile (i, j) sampling
// every pixel at sub-sample (i, j)) into the per-pixel buffer the other passes use.

struct RadCamera {
    view_proj: mat4x4f,
    position: vec4f,
}
@group(0) @binding(0) var<uniform> rad_cam: RadCamera;

struct RadOut {
    @builtin(position) clip: vec4f,
    @location(0) color: vec3f,
    @location(1) world: vec3f,
    @location(2) @interpolate(flat) normal: vec3f,
}

@vertex
fn vs(@location(0) pos: vec3f, @location(1) color: vec3f, @location(2) normal: vec3f) -> RadOut {
    var o: RadOut;
    o.clip = rad_cam.view_proj * vec4f(pos, 1.0);
    o.color = color;
    o.world = pos;
    o.normal = normal;
    return o;
}

@fragment
fn fs(i: RadOut) -> @location(0) vec4u {
    // The element's front faces the camera (independent of the projection's winding).
    if dot(i.normal, rad_cam.position.xyz - i.world) <= 0.0 {
        return vec4u(0u, 0u, 0u, 1u);
    }
    return vec4u(bitcast<vec3u>(i.color), 1u);
}

// (width, height, S): read from storage, as every compute pass's parameters (see
// `Kind::Params` in src/gpu/bindings.rs: lavapipe recompiles a loop over uniform values).
@group(0) @binding(1) var<storage, read> rad_size: array<u32>;
@group(0) @binding(2) var rad_image: texture_2d<u32>;
@group(0) @binding(3) var<storage, read_write> rad_out: array<vec4f>;

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3u) {
    let sz = vec3u(rad_size[0], rad_size[1], rad_size[2]);
    if gid.x >= sz.x || gid.y >= sz.y {
        return;
    }
    // Tile (i, j) of the target holds every pixel's sub-sample (i, j).
    let s = max(sz.z, 1u);
    var sum = vec4f(0.0);
    for (var ty = 0u; ty < s; ty++) {
        for (var tx = 0u; tx < s; tx++) {
            let t = textureLoad(rad_image, vec2i(gid.xy + vec2u(tx, ty) * sz.xy), 0);
            sum += vec4f(bitcast<vec3f>(t.xyz), f32(t.w));
        }
    }
    rad_out[gid.y * sz.x + gid.x] = sum / f32(s * s);
}
