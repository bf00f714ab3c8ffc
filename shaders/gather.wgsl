// Gather: every pixel sums the clamped contribution of every VPL, with ISM visibility
// (a depth bias scaled by the tile's texel footprint). Interleaved (P.interleave = n > 1):
// the pixel at block position k = ((y + shift_y) mod n) * n + (x + shift_x) mod n sums only
// the VPLs i with i mod n^2 = k, scaled by n^2, and writes that irradiance-like sum without
// the albedo: the `interleave` pass filters it and applies the albedo.
// Interleaved, invocations are laid out de-interleaved: the dispatch is n x n sub-images, each
// of every n-th pixel in x and y, so that a workgroup's pixels gather the same VPLs in step (the
// same VPL record and ISM tile across its lanes, not n^2 different ones); each pixel's sum is
// the same.
// Supersampled (P.aa = S > 1), the gather (and the interleave filter) run at one sample per
// pixel, on tile 0 of the sub-sample grid, and leave the albedo out: compose gives each
// sub-sample the indirect light of the pixel's sample or of a neighbour's on its own surface
// (indirect light is smooth), times its own albedo.

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var<storage, read> vpls: array<GpuVpl>;
@group(0) @binding(3) var<storage, read> ism: array<f32>;
@group(0) @binding(4) var gbuf: texture_2d<u32>;
@group(0) @binding(5) var<storage, read_write> indirect: array<vec4f>;
@group(0) @binding(6) var<storage, read> surface: array<Surface>;

// The ISM value of texel `texel` of `slot`'s tile: level 0 of the pyramid, or at a hole there
// its parent in level 1 (filled by pull-push; `ism_pullpush.wgsl`), -1 if that is a hole too.
fn ism_lookup(slot: u32, texel: u32, size: u32, level1: u32) -> f32 {
    let v = ism[slot * size * size + texel];
    if v >= 0.0 || level1 == 0u {
        return v;
    }
    let sh = countTrailingZeros(size);
    let h = size >> 1u;
    return ism[level1 + slot * h * h + ((texel >> sh) >> 1u) * h + ((texel & (size - 1u)) >> 1u)];
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    // One read of the parameters into registers (a storage buffer is not hoisted).
    let p = P;
    let side = max(p.interleave, 1u);
    var q = gid.xy;
    if side > 1u {
        // The gathered image: tile 0 of the sub-sample grid (all of it without supersampling).
        let image = vec2u(p.width, p.height) / max(p.aa, 1u);
        let sub = (image + side - 1u) / side;
        let which = gid.xy / sub;
        if any(which >= vec2u(side)) {
            return;
        }
        q = (gid.xy % sub) * side + which;
        if any(q >= image) {
            return;
        }
    }
    if q.x >= p.width || q.y >= p.height {
        return;
    }
    let g = textureLoad(gbuf, vec2i(q), 0);
    let pix = q.y * p.width + q.x;
    if g.w == 0u {
        indirect[pix] = vec4f(0.0);
        return;
    }
    let x = gbuffer_x(g);
    let n = facing(tris[g.w - 1u].n.xyz, x, p.cam_pos.xyz);
    let texel_angle = 4.0 / f32(p.ism_size);
    let step = side * side;
    let first = ((q.y + p.shift_y) % side) * side + (q.x + p.shift_x) % side;
    var sum = vec3f(0.0);
    for (var i = first; i < p.num_vpls; i += step) {
        let v = vpls[i];
        let d = v.pos.xyz - x;
        let d2 = dot(d, d);
        let dist = sqrt(d2);
        let w = d / dist;
        let cos_x = dot(n, w);
        let cos_y = vpl_lobe(v, -w);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            continue;
        }
        let stored = ism_lookup(i, paraboloid_texel(-w, v.normal.xyz, p.ism_size), p.ism_size, p.ism_level1);
        if stored >= 0.0 {
            // The footprint of the level the depth came from (filled holes: a coarser one).
            let footprint = dist * texel_angle * exp2(ism_level(stored));
            let tan_x = slope(cos_x);
            let bias = p.ism_bias * footprint * (1.0 + tan_x) / p.far;
            if dist / p.far > ism_depth(stored) + bias {
                continue;
            }
        }
        sum += v.flux.xyz * (cos_x * cos_y / (PI * PI * max(d2, p.clamp * p.clamp)));
    }
    if side > 1u {
        indirect[pix] = vec4f(sum * f32(step), 1.0);
    } else {
        // Supersampled, compose applies each sub-sample's own albedo.
        var albedo = vec3f(1.0);
        if p.aa <= 1u {
            albedo = select(tris[g.w - 1u].albedo.xyz, surface[pix].albedo.xyz, p.textured != 0u);
        }
        indirect[pix] = vec4f(sum * albedo, 1.0);
    }
}
