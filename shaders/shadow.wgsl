// Shadow hemicube faces: the scene's triangles seen from one emitter sample along one face
// axis (90 degree square frustum), storing the distance to the sample; or, for a directional
// light (ortho > 0), an orthographic map of half-width `ortho` along `fwd`, storing the depth
// along `fwd` from `pos`.

struct Face {
    pos: vec4f,   // the light sample
    right: vec4f,
    up: vec4f,
    fwd: vec4f,
    near: f32,
    far: f32,
    ortho: f32,
    pad1: f32,
}
@group(0) @binding(0) var<uniform> F: Face;
@group(0) @binding(1) var<storage, read> cut: Cutouts;
@group(0) @binding(2) var<storage, read> tris: array<Tri>;
@group(0) @binding(3) var<storage, read> attrs: array<TriAttr>;
@group(0) @binding(4) var<storage, read> materials: array<SurfaceMaterial>;
@group(0) @binding(5) var<storage, read> textures: array<TexInfo>;
@group(0) @binding(6) var<storage, read> texels: array<u32>;

struct VsOut {
    @builtin(position) clip: vec4f,
    @location(0) q: vec3f,
    @location(1) @interpolate(flat) tri: u32,
}

fn project(pos: vec3f, tri: u32) -> VsOut {
    let q = pos - F.pos.xyz;
    let vx = dot(q, F.right.xyz);
    let vy = dot(q, F.up.xyz);
    let vz = dot(q, F.fwd.xyz);
    var o: VsOut;
    if F.ortho > 0.0 {
        o.clip = vec4f(vx / F.ortho, vy / F.ortho, (vz - F.near) / (F.far - F.near), 1.0);
    } else {
        o.clip = vec4f(vx, vy, F.far * (vz - F.near) / (F.far - F.near), vz);
    }
    o.q = q;
    o.tri = tri;
    return o;
}

@vertex
fn vs(@location(0) pos: vec3f, @location(1) tri: u32) -> VsOut {
    return project(pos, tri);
}

// Scenes without cut-outs: the triangles' corners shared through an index buffer (a corner
// is shaded once for all the triangles that meet there), no triangle index.
@vertex
fn vs_shared(@location(0) pos: vec3f) -> VsOut {
    return project(pos, 0u);
}

fn distance_bits(i: VsOut) -> vec4u {
    let d = select(length(i.q), dot(i.q, F.fwd.xyz), F.ortho > 0.0);
    return vec4u(bitcast<u32>(d), 0u, 0u, 0u);
}

@fragment
fn fs_shared(i: VsOut) -> @location(0) vec4u {
    return distance_bits(i);
}

// Integer target (renderable everywhere): the distance's bits; 0 means nothing there.
@fragment
fn fs(i: VsOut) -> @location(0) vec4u {
    if cut.on != 0u && cut_away(i.tri, i.q + F.pos.xyz) {
        discard;
    }
    // An open single-sided triangle facing the light shadows nothing: the receivers behind it
    // see its back, through which they see the light (docs/math.md, "Single-sided surfaces").
    let n = tris[i.tri].n;
    if n.w > 1.5 && dot(n.xyz, select(i.q, F.fwd.xyz, F.ortho > 0.0)) < 0.0 {
        discard;
    }
    return distance_bits(i);
}
