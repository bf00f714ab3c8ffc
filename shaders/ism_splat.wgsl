// ISM splat: every VPL slot to redraw projects its own subset of the scene's points into its
// paraboloid tile, keeping the nearest with atomicMax on an inverted depth (0 means empty),
// and its ray-cast near-field points (the first surfaces its VPL sees, one along the centre of
// each cell of a P.near_grid^2 grid over the tile) into its cells in `near`: a near-field point
// stands for its whole cell by the plane of the triangle it lies on, in the VPL's frame
// (`near_plane`), and pull-push gives each texel the nearer of its own depth and where its
// direction meets its cell's plane (none if it leaves the plane behind). `slots[k]` = (slot,
// its offset into the point set) for k < P.num_changed; other slots keep their tiles.

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
@group(0) @binding(6) var<storage, read_write> near: array<vec4f>;

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
        near[slot * cells + c] = vec4f(0.0);
    }
}

// The ray-cast near-field points first (`near_main`), then the point set (`main`): a point of
// the set that lies on its cell's plane is that plane's surface, which the plane already
// holds at every texel of the cell (`texel_depth` in ism_pullpush.wgsl), so it is left out:
// splatted, it would shut its whole texel, also the directions in it that pass beside the
// surface (those just under a ceiling, for a VPL just under it).
@compute @workgroup_size(64)
fn near_main(@builtin(global_invocation_id) gid: vec3u) {
    let j = gid.x;
    let k = gid.y;
    if j >= P.near_points || k >= P.num_changed {
        return;
    }
    let s = slots[k].x;
    // The slot's ray-cast near-field points, after the point set; a miss is no point.
    let pt = points[P.num_points + s * P.near_points + j];
    if pt.tri == 0xffffffffu {
        return;
    }
    let tri = tris[pt.tri];
    let v = vpls[s];
    let at = seen(v, tri, pt);
    if at.w < 0.0 {
        return;
    }
    // One ray a cell, so one point a cell: a plain store.
    near[near_cell(s, u32(at.w))] = near_plane(tri.n.xyz, at.xyz, v.normal.xyz);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    let j = gid.x;
    let k = gid.y;
    if j >= P.ism_points || k >= P.num_changed {
        return;
    }
    let s = slots[k].x;
    let pt = points[(slots[k].y + j) % P.num_points];
    let tri = tris[pt.tri];
    let v = vpls[s];
    let at = seen(v, tri, pt);
    if at.w < 0.0 {
        return;
    }
    let d = at.xyz;
    let dist = length(d);
    if P.near_grid > 0u {
        let q = near[near_cell(s, u32(at.w))];
        let n = v.normal.xyz;
        let m = q.x * basis_t(n) + q.y * basis_b(n) + q.z * n;
        if abs(dot(m, tri.n.xyz)) > 0.9999 && abs(dot(m, d) - q.w) <= 1e-4 * dist {
            return;
        }
    }
    let depth = 16777216u - u32(clamp(dist / P.far, 0.0, 1.0) * 16777215.0);
    atomicMax(&atlas[s * P.ism_size * P.ism_size + u32(at.w)], depth);
}

// Point `pt` of triangle `tri` as VPL `v` sees it: its offset from the VPL and its texel, or
// w = -1 where it lies behind the VPL, on it, or is an open single-sided triangle facing it
// (which shadows nothing, see shadow.wgsl).
fn seen(v: GpuVpl, tri: Tri, pt: Point) -> vec4f {
    let p = tri.v0.xyz * (1.0 - pt.b1 - pt.b2) + tri.v1.xyz * pt.b1 + tri.v2.xyz * pt.b2;
    let d = p - v.pos.xyz;
    let dist = length(d);
    if dist < 1e-6 {
        return vec4f(0.0, 0.0, 0.0, -1.0);
    }
    let dir = d / dist;
    if dot(dir, v.normal.xyz) <= 0.0 || (tri.n.w > 1.5 && dot(tri.n.xyz, d) < 0.0) {
        return vec4f(0.0, 0.0, 0.0, -1.0);
    }
    return vec4f(d, f32(paraboloid_texel(dir, v.normal.xyz, P.ism_size)));
}

// Where the near-field cell of `texel` of slot `s` lies in `near`.
fn near_cell(s: u32, texel: u32) -> u32 {
    let n = P.near_grid;
    let sh = countTrailingZeros(P.ism_size);
    return s * n * n + (((texel >> sh) * n) >> sh) * n + (((texel & (P.ism_size - 1u)) * n) >> sh);
}

// The plane through a near-field point at `d` from its VPL (normal `n`), with the unit
// normal `m` of the triangle it lies on: `m` in the VPL's frame (t, b, n, as
// `paraboloid_texel` reads directions) and the signed distance `dot(m, d)`, so that a unit
// direction `w` of that frame meets it at `dot(m, d) / dot(m, w)` (`plane_depth` in
// ism_pullpush.wgsl).
fn near_plane(m: vec3f, d: vec3f, n: vec3f) -> vec4f {
    return vec4f(dot(m, basis_t(n)), dot(m, basis_b(n)), dot(m, n), dot(m, d));
}
