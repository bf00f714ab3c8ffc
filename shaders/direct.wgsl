// Direct light: every pixel sums the stratified emitter samples, each with the visibility its
// shadow hemicube gives.
// Supersampled (P.aa = S > 1), the S^2 sub-samples of a pixel split the emitter samples:
// the sub-sample of tile t sums the samples j with j mod S^2 = t, scaled by S^2, so that the
// pixel's resolve holds every sample once at the cost of one sample point per pixel.

@group(0) @binding(0) var<storage, read> P: Params;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var<storage, read> lights: array<LightSample>;
@group(0) @binding(3) var shadows: texture_2d_array<u32>;
@group(0) @binding(4) var gbuf: texture_2d<u32>;
@group(0) @binding(5) var<storage, read_write> direct: array<vec4f>;

// Face index (0: +n, 1: +t, 2: -t, 3: +b, 4: -b) and its (right, up, fwd) local coordinates
// of a direction with local coordinates l = (t, b, n) components.
fn face_coords(l: vec3f) -> vec4f {
    let ax = abs(l.x);
    let ay = abs(l.y);
    if l.z >= ax && l.z >= ay {
        return vec4f(0.0, l.x / l.z, l.y / l.z, 0.0);
    }
    if ax >= ay {
        let f = select(2.0, 1.0, l.x > 0.0);
        return vec4f(f, l.y / ax, l.z / ax, 0.0);
    }
    let f = select(4.0, 3.0, l.y > 0.0);
    return vec4f(f, l.x / ay, l.z / ay, 0.0);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    // One read of the parameters into registers (a storage buffer is not hoisted).
    let p = P;
    if gid.x >= p.width || gid.y >= p.height {
        return;
    }
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    let pix = gid.y * p.width + gid.x;
    if g.w == 0u {
        direct[pix] = vec4f(0.0);
        return;
    }
    let tri = tris[g.w - 1u];
    let x = gbuffer_x(g);
    let n = facing(tri.n.xyz, x, p.cam_pos.xyz);
    let size = f32(p.shadow_size);
    var sum = vec3f(0.0);
    let s = max(p.aa, 1u);
    for (var j = subsample_tile(gid.xy, vec2u(p.width, p.height), s); j < p.num_light_samples; j += s * s) {
        let ls = lights[j];
        let d = x - ls.pos.xyz;
        let d2 = dot(d, d);
        let dist = sqrt(d2);
        let w = d / dist;
        let cos_l = dot(ls.normal.xyz, w);
        let cos_x = -dot(n, w);
        if cos_l <= 0.0 || cos_x <= 0.0 {
            continue;
        }
        let ln = ls.normal.xyz;
        let l = vec3f(dot(w, basis_t(ln)), dot(w, basis_b(ln)), cos_l);
        let fc = face_coords(l);
        let texel = clamp(vec2i(floor(vec2f(fc.y * 0.5 + 0.5, 0.5 - 0.5 * fc.z) * size)), vec2i(0), vec2i(i32(p.shadow_size) - 1));
        let stored = bitcast<f32>(textureLoad(shadows, texel, i32(j * 5u + u32(fc.x)), 0).x);
        let tan_x = slope(cos_x);
        let bias = p.shadow_bias * dist * (2.0 / size) * (1.0 + tan_x) + p.near;
        if stored > 0.0 && stored < dist - bias {
            continue;
        }
        sum += ls.radiance.xyz * (cos_l * cos_x / d2);
    }
    direct[pix] = vec4f(sum * f32(s * s) * tri.albedo.xyz / PI, 1.0);
}
