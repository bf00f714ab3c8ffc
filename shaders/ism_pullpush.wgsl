// Pull-push hole filling within each ISM tile. The pyramid holds `depth + 4 * level` (depth
// normalized to [0,1], level the pyramid level whose footprint the value stands for), -1 for a
// hole. `decode` turns the splat atlas into level 0 (each texel the nearer of its own depth
// and where its direction meets its near-field cell's plane, see `texel_depth`); `pull`
// averages the valid children into the next coarser level; `push` fills holes of a level
// from its (already filled) parent, so a filled texel says which coarser footprint its depth
// came from (see `ism_depth` in common).
// Push stops at level 1: the gather reads level 0 and, at a hole, its parent in level 1
// (`ism_lookup` in gather.wgsl), the value push would have written there.
// Tiles of at most 64 texels a side take `fused` instead: all of it in one dispatch, the
// coarser levels in workgroup memory (the same values; `src/gpu/ism.rs` has the CPU twin).
// Only the tiles of `slots[k].x`, k < P.num_changed, are redone; the others keep theirs.

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read_write> atlas: array<u32>;
@group(0) @binding(2) var<storage, read_write> pyramid: array<f32>;
@group(0) @binding(3) var<storage, read> slots: array<vec2u>;
@group(0) @binding(4) var<storage, read_write> near: array<vec4f>;

struct Level {
    level: u32,
    offset: u32,        // start of this level in the pyramid
    parent_offset: u32, // start of the coarser level (pull writes it, push reads it)
    size: u32,          // tile side at this level
}
@group(1) @binding(0) var<storage, read> L: Level;

@compute @workgroup_size(64)
fn decode(@builtin(global_invocation_id) gid: vec3u) {
    let per_tile = P.ism_size * P.ism_size;
    let i = gid.x + gid.y * 65535u * 64u;
    if i >= P.num_changed * per_tile {
        return;
    }
    let slot = slots[i / per_tile].x;
    let k = i % per_tile;
    pyramid[slot * per_tile + k] = texel_depth(slot, k % P.ism_size, k / P.ism_size);
}

// One invocation per texel of the coarser level `L.size / 2`.
@compute @workgroup_size(64)
fn pull(@builtin(global_invocation_id) gid: vec3u) {
    let half = L.size / 2u;
    let per_tile = half * half;
    let i = gid.x + gid.y * 65535u * 64u;
    if i >= P.num_changed * per_tile {
        return;
    }
    let tile = slots[i / per_tile].x;
    let k = i % per_tile;
    let x = (k % half) * 2u;
    let y = (k / half) * 2u;
    let base = L.offset + tile * L.size * L.size;
    let at = base + y * L.size + x;
    pyramid[L.parent_offset + tile * per_tile + k] = pulled(pyramid[at], pyramid[at + 1u], pyramid[at + L.size], pyramid[at + L.size + 1u], L.level + 1u);
}

// One invocation per texel of level `L.size`.
@compute @workgroup_size(64)
fn push(@builtin(global_invocation_id) gid: vec3u) {
    let per_tile = L.size * L.size;
    let i = gid.x + gid.y * 65535u * 64u;
    if i >= P.num_changed * per_tile {
        return;
    }
    let tile = slots[i / per_tile].x;
    let k = i % per_tile;
    let at = L.offset + tile * per_tile + k;
    if pyramid[at] >= 0.0 {
        return;
    }
    let half = L.size / 2u;
    let parent = L.parent_offset + tile * half * half + ((k / L.size) / 2u) * half + (k % L.size) / 2u;
    pyramid[at] = pyramid[parent];
}

// The fused pull-push for tiles of at most FUSED_MAX texels a side: one workgroup per redrawn
// tile (k = workgroup id), its coarser levels (1, 2, ...) in workgroup memory; level 0 is
// written as decoded while level 1 is pulled, and its holes filled last. The same operations
// in the same order as decode, pull and push, so the same levels 0 and 1, the levels the
// gather reads; no pass over the whole pyramid between levels, and one dispatch instead of 2 levels + 1.
// It empties the tile's atlas texels and near-field cells once read, so the next splat finds
// them empty without a clear pass (the buffers start zeroed).
const FUSED_MAX: u32 = 64u;
// Levels 1 to 5 of a 64-texel tile: 32^2 + 16^2 + 8^2 + 4^2 + 2^2 values.
var<workgroup> up: array<f32, 1364>;

fn decoded(e: u32) -> f32 {
    return select(f32(16777216u - e) / 16777215.0, -1.0, e == 0u);
}

// Level 0 at texel (x, y) of `slot`'s tile: the nearer of the splat's depth there and where
// the texel's direction meets the plane of the near-field cell it lies in (inverted depths:
// the larger). Tile sides are powers of two: shifts, not divisions (which a software
// rasterizer does a lane at a time).
fn texel_depth(slot: u32, x: u32, y: u32) -> f32 {
    let sh = countTrailingZeros(P.ism_size);
    var e = atlas[(slot << (2u * sh)) + (y << sh) + x];
    let n = P.near_grid;
    if n > 0u {
        e = max(e, plane_depth(near[slot * n * n + ((y * n) >> sh) * n + ((x * n) >> sh)], x, y));
    }
    return decoded(e);
}

// The inverted depth at which the direction of texel (x, y) (its centre mapped back from the
// paraboloid, in the VPL's frame) meets a near-field cell's plane `q` (`near_plane` in
// ism_splat.wgsl: its unit normal and its signed distance along it); 0 (none) for an empty
// cell (zero normal) or a direction parallel to the plane or leaving it behind.
fn plane_depth(q: vec4f, x: u32, y: u32) -> u32 {
    let fs = f32(P.ism_size);
    let u = (f32(x) + 0.5) / fs * 2.0 - 1.0;
    let v = (f32(y) + 0.5) / fs * 2.0 - 1.0;
    let r2 = u * u + v * v;
    let w = vec3f(2.0 * u, 2.0 * v, 1.0 - r2) / (1.0 + r2);
    let c = dot(q.xyz, w);
    let t = q.w / c;
    if !(c != 0.0 && t > 0.0) {
        return 0u;
    }
    return 16777216u - u32(min(t / P.far, 1.0) * 16777215.0);
}

// The mean depth of the valid ones of four values as a value of level `level`, or a hole.
fn pulled(a: f32, b: f32, c: f32, d: f32, level: u32) -> f32 {
    var v = array<f32, 4>(a, b, c, d);
    var sum = 0.0;
    var count = 0.0;
    for (var j = 0u; j < 4u; j++) {
        if v[j] >= 0.0 {
            sum += ism_depth(v[j]);
            count += 1.0;
        }
    }
    return select(-1.0, sum / max(count, 1.0) + 4.0 * f32(level), count > 0.0);
}

// Where level l >= 1 of the tile starts in `up`.
fn up_offset(size: u32, l: u32) -> u32 {
    var o = 0u;
    for (var k = 1u; k < l; k++) {
        o += (size >> k) * (size >> k);
    }
    return o;
}

// Invocations a workgroup: on lavapipe and llvmpipe 256 take 35% less time than 64 (without
// the zeroing of workgroup memory, which the pipeline skips: every value is written first).
const FUSED_LANES: u32 = 256u;
@compute @workgroup_size(FUSED_LANES)
fn fused(@builtin(workgroup_id) wid: vec3u, @builtin(local_invocation_index) t: u32) {
    let size = P.ism_size;
    let k = wid.x + wid.y * 65535u;
    if k >= P.num_changed || size > FUSED_MAX {
        return;
    }
    let sh = countTrailingZeros(size);
    let levels = min(P.pull_levels, sh - 1u);
    let slot = slots[k].x;
    if levels > 0u {
        // Pull level 0 (the decoded atlas) into level 1.
        let h = size / 2u;
        for (var b = t; b < h * h; b += FUSED_LANES) {
            let x = (b & (h - 1u)) * 2u;
            let y = (b >> (sh - 1u)) * 2u;
            let v00 = texel_depth(slot, x, y);
            let v10 = texel_depth(slot, x + 1u, y);
            let v01 = texel_depth(slot, x, y + 1u);
            let v11 = texel_depth(slot, x + 1u, y + 1u);
            // Level 0 as decoded; its holes are filled below. The atlas texels are read.
            let at = (slot << (2u * sh)) + (y << sh) + x;
            pyramid[at] = v00;
            pyramid[at + 1u] = v10;
            pyramid[at + size] = v01;
            pyramid[at + size + 1u] = v11;
            atlas[at] = 0u;
            atlas[at + 1u] = 0u;
            atlas[at + size] = 0u;
            atlas[at + size + 1u] = 0u;
            up[b] = pulled(v00, v10, v01, v11, 1u);
        }
    }
    // Pull level l into l + 1.
    for (var l = 1u; l < levels; l++) {
        workgroupBarrier();
        let s = size >> l;
        let h = s / 2u;
        let src = up_offset(size, l);
        let dst = up_offset(size, l + 1u);
        for (var b = t; b < h * h; b += FUSED_LANES) {
            let at = src + (b >> (sh - l - 1u)) * 2u * s + (b & (h - 1u)) * 2u;
            up[dst + b] = pulled(up[at], up[at + 1u], up[at + s], up[at + s + 1u], l + 1u);
        }
    }
    // Push: fill the holes of level l from level l + 1, coarsest first.
    for (var l = levels - 1u; l >= 1u && l < levels; l--) {
        workgroupBarrier();
        let s = size >> l;
        let h = s / 2u;
        let at = up_offset(size, l);
        let parent = up_offset(size, l + 1u);
        for (var i = t; i < s * s; i += FUSED_LANES) {
            if up[at + i] < 0.0 {
                up[at + i] = up[parent + (i >> (sh - l + 1u)) * h + ((i & (s - 1u)) >> 1u)];
            }
        }
    }
    workgroupBarrier();
    let base = slot << (2u * sh);
    if levels == 0u {
        for (var i = t; i < size * size; i += FUSED_LANES) {
            pyramid[base + i] = texel_depth(slot, i & (size - 1u), i >> sh);
            atlas[base + i] = 0u;
        }
        // Every texel has read its near-field cell.
        workgroupBarrier();
    } else {
        // Level 1, filled, after level 0 in the pyramid: the gather's fallback at level 0's holes.
        let h = size / 2u;
        for (var i = t; i < h * h; i += FUSED_LANES) {
            pyramid[P.ism_level1 + slot * h * h + i] = up[i];
        }
    }
    // The cells were read before the barrier above; order those storage reads too.
    storageBarrier();
    let n = P.near_grid;
    for (var c = t; c < n * n; c += FUSED_LANES) {
        near[slot * n * n + c] = vec4f(0.0);
    }
}
