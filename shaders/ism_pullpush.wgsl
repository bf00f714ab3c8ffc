// Pull-push hole filling within each ISM tile. The pyramid holds `depth + 4 * level` (depth
// normalized to [0,1], level the pyramid level whose footprint the value stands for), -1 for a
// hole. `decode` turns the splat atlas into level 0; `pull` averages the valid children into
// the next coarser level; `push` fills holes of a level from its (already filled) parent, so a
// filled texel says which coarser footprint its depth came from (see `ism_depth` in common).
// Only the tiles of `slots[k].x`, k < P.num_changed, are redone; the others keep theirs.

@group(0) @binding(0) var<storage, read> P: Params;
@group(0) @binding(1) var<storage, read> atlas: array<u32>;
@group(0) @binding(2) var<storage, read_write> pyramid: array<f32>;
@group(0) @binding(3) var<storage, read> slots: array<vec2u>;

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
    let t = slots[i / per_tile].x * per_tile + i % per_tile;
    let e = atlas[t];
    pyramid[t] = select(f32(16777216u - e) / 16777215.0, -1.0, e == 0u);
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
    var sum = 0.0;
    var count = 0.0;
    for (var dy = 0u; dy < 2u; dy++) {
        for (var dx = 0u; dx < 2u; dx++) {
            let v = pyramid[base + (y + dy) * L.size + x + dx];
            if v >= 0.0 {
                sum += ism_depth(v);
                count += 1.0;
            }
        }
    }
    pyramid[L.parent_offset + tile * per_tile + k] = select(-1.0, sum / max(count, 1.0) + 4.0 * f32(L.level + 1u), count > 0.0);
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
