// ISM splat: every VPL slot to redraw projects its own subset of the scene's points into its
// paraboloid tile, keeping the nearest with atomicMax on an inverted depth (0 means empty).
// `slots[k]` = (slot, its offset into the point set) for k < P.num_changed; other slots keep
// their tiles.

@group(0) @binding(0) var<storage, read> P: Params;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
struct Point {
    tri: u32,
    b1: f32,
    b2: f32,
    pad: u32,
}
@group(0) @binding(2) var<storage, read> points: array<Point>;
@group(0) @binding(3) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(4) var<storage, read> slots: array<vec2u>;
@group(0) @binding(5) var<storage, read_write> atlas: array<atomic<u32>>;

// Empties the tiles of the slots to redraw (one invocation per texel).
@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3u) {
    let per_tile = P.ism_size * P.ism_size;
    let i = gid.x + gid.y * 65535u * 64u;
    if i >= P.num_changed * per_tile {
        return;
    }
    atomicStore(&atlas[slots[i / per_tile].x * per_tile + i % per_tile], 0u);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    let j = gid.x;
    let k = gid.y;
    if j >= P.points_per_vpl || k >= P.num_changed {
        return;
    }
    let s = slots[k].x;
    let pt = points[(slots[k].y + j) % P.num_points];
    let tri = tris[pt.tri];
    let p = tri.v0.xyz * (1.0 - pt.b1 - pt.b2) + tri.v1.xyz * pt.b1 + tri.v2.xyz * pt.b2;
    let v = vpls[s];
    let d = p - v.pos.xyz;
    let dist = length(d);
    if dist < 1e-6 {
        return;
    }
    let dir = d / dist;
    if dot(dir, v.normal.xyz) <= 0.0 {
        return;
    }
    let texel = paraboloid_texel(dir, v.normal.xyz, P.ism_size);
    let depth = u32(clamp(dist / P.far, 0.0, 1.0) * 16777215.0);
    atomicMax(&atlas[s * P.ism_size * P.ism_size + texel], 16777216u - depth);
}
