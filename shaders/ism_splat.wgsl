// ISM splat: every VPL slot to redraw projects its own subset of the scene's points into its
// paraboloid tile, keeping the nearest with atomicMax on an inverted depth (0 means empty),
// and its ray-cast near-field points (the first surfaces its VPL sees, one along the centre of
// each cell of a P.near_grid^2 grid over the tile) into its cells in `near`: a near-field point
// stands for its whole cell, and pull-push gives each texel the nearer of its own depth and
// its cell's. `slots[k]` = (slot, its offset into the point set) for k < P.num_changed; other
// slots keep their tiles.

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
struct Point {
    tri: u32,
    b1: f32,
    b2: f32,
    pad: u32,
}
@group(0) @binding(2) var<storage, read> points: array<Point>;
@group(0) @binding(3) var<storage, read> vpls: array<GpuVpl>;
@group(0) @binding(4) var<storage, read> slots: array<vec2u>;
@group(0) @binding(5) var<storage, read_write> atlas: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> near: array<atomic<u32>>;

// Empties the tiles of the slots to redraw (one invocation per texel).
@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3u) {
    // Tile sides are powers of two: shifts, not divisions.
    let sh = 2u * countTrailingZeros(P.ism_size);
    let per_tile = 1u << sh;
    let i = gid.x + gid.y * 65535u * 64u;
    if i >= P.num_changed * per_tile {
        return;
    }
    let slot = slots[i >> sh].x;
    let k = i & (per_tile - 1u);
    atomicStore(&atlas[(slot << sh) + k], 0u);
    // The slot's near-field cells (fewer than its texels, but for tiles of 8 or 16).
    let cells = P.near_grid * P.near_grid;
    for (var c = k; c < cells; c += per_tile) {
        atomicStore(&near[slot * cells + c], 0u);
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    let j = gid.x;
    let k = gid.y;
    if j >= P.ism_points + P.near_points || k >= P.num_changed {
        return;
    }
    let s = slots[k].x;
    var pt: Point;
    if j < P.ism_points {
        pt = points[(slots[k].y + j) % P.num_points];
    } else {
        // The slot's ray-cast near-field points, after the point set; a miss is no point.
        pt = points[P.num_points + s * P.near_points + j - P.ism_points];
        if pt.tri == 0xffffffffu {
            return;
        }
    }
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
    // An open single-sided triangle facing the VPL shadows nothing (see shadow.wgsl).
    if tri.n.w > 1.5 && dot(tri.n.xyz, d) < 0.0 {
        return;
    }
    let texel = paraboloid_texel(dir, v.normal.xyz, P.ism_size);
    let depth = 16777216u - u32(clamp(dist / P.far, 0.0, 1.0) * 16777215.0);
    if j < P.ism_points {
        atomicMax(&atlas[s * P.ism_size * P.ism_size + texel], depth);
    } else {
        let n = P.near_grid;
        let sh = countTrailingZeros(P.ism_size);
        let cell = (((texel >> sh) * n) >> sh) * n + (((texel & (P.ism_size - 1u)) * n) >> sh);
        atomicMax(&near[s * n * n + cell], depth);
    }
}
