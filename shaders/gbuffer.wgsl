// G-buffer: the camera's view rasterized; each pixel keeps its world position and triangle
// (see `gbuffer_x` and `gbuffer_tri` in common.wgsl).

struct Camera {
    view_proj: mat4x4f,
    eye: vec4f,
}
@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<storage, read> cut: Cutouts;
@group(0) @binding(2) var<storage, read> tris: array<Tri>;
@group(0) @binding(3) var<storage, read> attrs: array<TriAttr>;
@group(0) @binding(4) var<storage, read> materials: array<SurfaceMaterial>;
@group(0) @binding(5) var<storage, read> textures: array<TexInfo>;
@group(0) @binding(6) var<storage, read> texels: array<u32>;

struct VsOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    @location(1) @interpolate(flat) tri: u32,
}

@vertex
fn vs(@location(0) pos: vec3f, @location(1) tri: u32) -> VsOut {
    var o: VsOut;
    o.clip = cam.view_proj * vec4f(pos, 1.0);
    o.world = pos;
    o.tri = tri;
    return o;
}

// Integer target (renderable everywhere, GL included): position bits and triangle + 1.
@fragment
fn fs(i: VsOut) -> @location(0) vec4u {
    if cut.on != 0u && cut_away(i.tri, i.world) {
        discard;
    }
    // A single-sided triangle seen from behind is not there (docs/math.md).
    let n = tris[i.tri].n;
    if n.w > 0.5 && dot(n.xyz, i.world - cam.eye.xyz) > 0.0 {
        discard;
    }
    return vec4u(bitcast<vec3u>(i.world), i.tri + 1u);
}
