// Shadow hemicube faces: the scene's triangles seen from one emitter sample along one face
// axis (90 degree square frustum), storing the distance to the sample.

struct Face {
    pos: vec4f,   // the light sample
    right: vec4f,
    up: vec4f,
    fwd: vec4f,
    near: f32,
    far: f32,
    pad0: f32,
    pad1: f32,
}
@group(0) @binding(0) var<uniform> F: Face;

struct VsOut {
    @builtin(position) clip: vec4f,
    @location(0) q: vec3f,
}

@vertex
fn vs(@location(0) pos: vec3f, @location(1) tri: u32) -> VsOut {
    let q = pos - F.pos.xyz;
    let vx = dot(q, F.right.xyz);
    let vy = dot(q, F.up.xyz);
    let vz = dot(q, F.fwd.xyz);
    var o: VsOut;
    o.clip = vec4f(vx, vy, F.far * (vz - F.near) / (F.far - F.near), vz);
    o.q = q;
    return o;
}

// Integer target (renderable everywhere): the distance's bits; 0 means nothing there.
@fragment
fn fs(i: VsOut) -> @location(0) vec4u {
    return vec4u(bitcast<u32>(length(i.q)), 0u, 0u, 0u);
}
