// Gather: every pixel sums the clamped contribution of every VPL, with ISM visibility
// (a depth bias scaled by the tile's texel footprint). Interleaved (P.interleave = n > 1):
// the pixel at block position k = ((y + shift_y) mod n) * n + (x + shift_x) mod n sums only
// the VPLs i with i mod n^2 = k, scaled by n^2, and writes that irradiance-like sum without
// the albedo: the `interleave` pass filters it and applies the albedo.
// Supersampled (P.aa = S > 1), the S^2 sub-samples of a pixel (one per tile of the grid) split
// the VPLs further: the sub-sample of tile t sums the VPLs i with i mod (n^2 S^2) = k S^2 + t,
// scaled by n^2 S^2, so that a pixel's resolve (the mean of its sub-samples) holds every VPL
// once while each sub-sample gathers 1/S^2 of what it would alone: the gather costs what it
// costs without supersampling.

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var<storage, read> ism: array<f32>;
@group(0) @binding(4) var gbuf: texture_2d<u32>;
@group(0) @binding(5) var<storage, read_write> indirect: array<vec4f>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= P.width || gid.y >= P.height {
        return;
    }
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    let pix = gid.y * P.width + gid.x;
    if g.w == 0u {
        indirect[pix] = vec4f(0.0);
        return;
    }
    let tri = tris[g.w - 1u];
    let x = gbuffer_x(g);
    let n = facing(tri.n.xyz, x, P.cam_pos.xyz);
    let texel_angle = 4.0 / f32(P.ism_size);
    let side = max(P.interleave, 1u);
    let s = max(P.aa, 1u);
    let step = side * side * s * s;
    let first = (((gid.y + P.shift_y) % side) * side + (gid.x + P.shift_x) % side) * s * s
        + subsample_tile(gid.xy, vec2u(P.width, P.height), P.aa);
    var sum = vec3f(0.0);
    for (var i = first; i < P.num_vpls; i += step) {
        let v = vpls[i];
        let d = v.pos.xyz - x;
        let d2 = dot(d, d);
        let dist = sqrt(d2);
        let w = d / dist;
        let cos_x = dot(n, w);
        let cos_y = -dot(v.normal.xyz, w);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            continue;
        }
        let stored = ism[i * P.ism_size * P.ism_size + paraboloid_texel(-w, v.normal.xyz, P.ism_size)];
        if stored >= 0.0 {
            // The footprint of the level the depth came from (filled holes: a coarser one).
            let footprint = dist * texel_angle * exp2(ism_level(stored));
            let tan_x = slope(cos_x);
            let bias = P.ism_bias * footprint * (1.0 + tan_x) / P.far;
            if dist / P.far > ism_depth(stored) + bias {
                continue;
            }
        }
        sum += v.flux.xyz * (cos_x * cos_y / (PI * PI * max(d2, P.dmin * P.dmin)));
    }
    if side > 1u {
        indirect[pix] = vec4f(sum * f32(step), 1.0);
    } else {
        indirect[pix] = vec4f(sum * f32(step) * tri.albedo.xyz, 1.0);
    }
}
