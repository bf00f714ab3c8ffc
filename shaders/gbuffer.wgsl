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

fn project(pos: vec3f, tri: u32) -> VsOut {
    var o: VsOut;
    o.clip = cam.view_proj * vec4f(pos, 1.0);
    o.world = pos;
    o.tri = tri;
    return o;
}

@vertex
fn vs(@location(0) pos: vec3f, @location(1) tri: u32) -> VsOut {
    return project(pos, tri);
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

// The pass for scenes without cut-outs (`GBuffer::new`'s `plain`): the vertex stage leaves out
// a single-sided triangle seen from behind (all its corners moved to one point outside the
// clip volume, so that nothing of it is drawn) and the fragment stage tests nothing. The
// test is `fs`'s, on the triangle's plane through its first corner instead of the fragment,
// which lies on the same plane. A fragment shader that may discard cost llvmpipe 9-12 ms of
// `cornell-orbit`'s 256x256 frame at `--aa 2`, where this pair costs 1.3-1.5 ms.
@vertex
fn vs_sided(@location(0) pos: vec3f, @location(1) tri: u32) -> VsOut {
    var o = project(pos, tri);
    let n = tris[tri].n;
    if n.w > 0.5 && dot(n.xyz, tris[tri].v0.xyz - cam.eye.xyz) > 0.0 {
        o.clip = vec4f(2.0, 2.0, 2.0, 1.0);
    }
    return o;
}

@fragment
fn fs_plain(i: VsOut) -> @location(0) vec4u {
    return vec4u(bitcast<vec3u>(i.world), i.tri + 1u);
}
