// Form-factor hemicube faces: a mesh's elements seen from one point along one face axis
// (90 degree square frustum), storing the nearest element's index + 1 (0: nothing there, or
// the back of an element).

struct Face {
    pos: vec4f,   // the eye: an element's centre, lifted a hair along its normal
    right: vec4f, // right x up = fwd on every face, so windings agree across faces
    up: vec4f,
    fwd: vec4f,
    near: f32,
    far: f32,
    ortho: f32,   // 0 here: form-factor faces are perspective (see shadow.wgsl)
    pad1: f32,
}
@group(0) @binding(0) var<uniform> H: Face;

struct HemiOut {
    @builtin(position) clip: vec4f,
    @location(0) @interpolate(flat) elem: u32,
}

@vertex
fn vs(@location(0) pos: vec3f, @location(1) elem: u32) -> HemiOut {
    let q = pos - H.pos.xyz;
    let vx = dot(q, H.right.xyz);
    let vy = dot(q, H.up.xyz);
    let vz = dot(q, H.fwd.xyz);
    var o: HemiOut;
    o.clip = vec4f(vx, vy, H.far * (vz - H.near) / (H.far - H.near), vz);
    o.elem = elem;
    return o;
}

// Elements are wound counter-clockwise around their normals. Seen from the eye through a
// face whose right x up points away from it, an element facing the eye is clockwise on the
// screen: not `front_facing` under the pipeline's counter-clockwise convention. Backs still
// write depth (they hide what is behind) but store nothing.
@fragment
fn fs(i: HemiOut, @builtin(front_facing) front: bool) -> @location(0) vec4u {
    if front {
        return vec4u(0u, 0u, 0u, 0u);
    }
    return vec4u(i.elem + 1u, 0u, 0u, 0u);
}
