// Direct light: every pixel sums the stratified emitter samples, each with the visibility its
// shadow hemicube gives. A sample's kind is in pos.w: 0 a point on an emitter triangle, 1 half
// a point light (intensity into the hemisphere around normal), 2 a spot light (normal.w and
// radiance.w: the cosines of its inner and outer cone), 3 a directional light (irradiance
// along normal; pos the centre of its orthographic map, normal.w its half-width, radiance.w
// the fraction of the depth bias it takes, 0 for all: an environment sample's), 4 a point light
// outside the geometry (intensity toward it, normal the axis of one shadow face zoomed to the
// half-width normal.w at unit distance).
// Supersampled (P.aa = S > 1) with at least S^2 samples, the S^2 sub-samples of a pixel split
// them: the sub-sample of tile t sums the samples j with j mod S^2 = t, scaled by S^2, so that
// the pixel's resolve holds every sample once at the cost of one sample point per pixel
// (with fewer samples, as from a few punctual lights, every sub-sample sums them all; and
// with P.direct_split = 0, the classical methods', every sub-sample sums them all too).

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var<storage, read> lights: array<GpuEmitterSample>;
@group(0) @binding(3) var shadows: texture_2d_array<u32>;
@group(0) @binding(4) var gbuf: texture_2d<u32>;
@group(0) @binding(5) var<storage, read_write> direct: array<vec4f>;
@group(0) @binding(6) var<storage, read> surface: array<Surface>;
// The environment (`gpu::direct::EnvironmentBuffer`): env[0] = (width, height, on, 0),
// env[1..5] the columns of the camera's inverse view-projection, then the map's texels.
@group(0) @binding(7) var<storage, read> env: array<vec4f>;

// The environment's radiance toward the sub-sample `q` of the grid where it sees no geometry:
// the direction through the pixel's centre (the sub-sample's tile offset left out), looked up
// in the equirectangular map as `scene::environment::direction_uv` does.
fn background(q: vec2u, p: FrameConstants) -> vec3f {
    let head = env[0];
    if head.z == 0.0 {
        return vec3f(0.0);
    }
    let s = max(p.aa, 1u);
    let size = vec2u(p.width, p.height) / s;
    let px = vec2f(q % size) + 0.5;
    let ndc = vec2f(px.x / f32(size.x) * 2.0 - 1.0, 1.0 - px.y / f32(size.y) * 2.0);
    let inv = mat4x4f(env[1], env[2], env[3], env[4]);
    let a = inv * vec4f(ndc, 0.0, 1.0);
    let b = inv * vec4f(ndc, 1.0, 1.0);
    let d = normalize(b.xyz / b.w - a.xyz / a.w);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    let u = fract(0.5 + atan2(d.x, -d.z) / (2.0 * PI));
    let w = u32(head.x);
    let h = u32(head.y);
    let i = min(u32(u * head.x), w - 1u);
    let j = min(u32(v * head.y), h - 1u);
    return env[8u + j * w + i].xyz;
}

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
        direct[pix] = vec4f(background(gid.xy, p), 1.0);
        return;
    }
    let x = gbuffer_x(g);
    let n = facing(tris[g.w - 1u].n.xyz, x, p.cam_pos.xyz);
    let size = f32(p.shadow_size);
    var sum = vec3f(0.0);
    let s = max(p.aa, 1u);
    let share = select(1u, s * s, p.num_light_samples >= s * s && p.direct_split != 0u);
    let first = select(0u, subsample_tile(gid.xy, vec2u(p.width, p.height), s), share > 1u);
    for (var j = first; j < p.num_light_samples; j += share) {
        let ls = lights[j];
        let kind = u32(ls.pos.w);
        let ln = ls.normal.xyz;
        if kind == 3u {
            // Directional: irradiance times cos_x, visibility from the orthographic map.
            let cos_x = -dot(n, ln);
            if cos_x <= 0.0 {
                continue;
            }
            let q = x - ls.pos.xyz;
            let ext = ls.normal.w;
            let uv = vec2f(dot(q, basis_t(ln)), dot(q, basis_b(ln))) / ext;
            let texel = clamp(vec2i(floor(vec2f(uv.x * 0.5 + 0.5, 0.5 - 0.5 * uv.y) * size)), vec2i(0), vec2i(i32(p.shadow_size) - 1));
            let stored = bitcast<f32>(textureLoad(shadows, texel, i32(j * 5u), 0).x);
            // An environment sample's maps take a fraction (radiance.w) of the bias.
            let scale = select(1.0, ls.radiance.w, ls.radiance.w > 0.0);
            let bias = scale * p.shadow_bias * ext * (2.0 / size) * (1.0 + slope(cos_x)) + p.near;
            if stored > 0.0 && stored < dot(q, ln) - bias {
                continue;
            }
            sum += ls.radiance.xyz * cos_x;
            continue;
        }
        let d = x - ls.pos.xyz;
        let d2 = dot(d, d);
        let dist = sqrt(d2);
        let w = d / dist;
        let cos_l = dot(ln, w);
        let cos_x = -dot(n, w);
        if cos_l <= 0.0 || cos_x <= 0.0 {
            continue;
        }
        // How the sample's light falls off with the angle from its normal.
        var f = cos_l;
        if kind == 1u || kind == 4u {
            f = 1.0;
        } else if kind == 2u {
            let a = clamp((cos_l - ls.radiance.w) / max(ls.normal.w - ls.radiance.w, 1e-3), 0.0, 1.0);
            f = a * a;
        }
        if f <= 0.0 {
            continue;
        }
        let l = vec3f(dot(w, basis_t(ln)), dot(w, basis_b(ln)), cos_l);
        var fc = face_coords(l);
        var zoom = 1.0;
        let texels = vec2f(size);
        if kind == 4u {
            zoom = 1.0 / ls.normal.w;
            fc = vec4f(0.0, l.x / l.z * zoom, l.y / l.z * zoom, 0.0);
        }
        if ls.window.z > 0.0 {
            // One face over the window that holds the geometry (`shadow::Window`), drawn
            // over the whole map: its texels are 1 / scale as wide as a hemicube face's.
            fc = vec4f(0.0, (l.x / l.z - ls.window.x) * ls.window.z, (l.y / l.z - ls.window.y) * ls.window.w, 0.0);
            zoom = min(ls.window.z, ls.window.w);
        }
        let texel = clamp(vec2i(floor(vec2f(fc.y * 0.5 + 0.5, 0.5 - 0.5 * fc.z) * texels)), vec2i(0), vec2i(texels) - 1);
        let stored = bitcast<f32>(textureLoad(shadows, texel, i32(j * 5u + u32(fc.x)), 0).x);
        let tan_x = slope(cos_x);
        let bias = p.shadow_bias * dist * (2.0 / (size * zoom)) * (1.0 + tan_x) + p.near;
        if stored > 0.0 && stored < dist - bias {
            continue;
        }
        // A point on an emitter triangle (kind 0) closer than the clamp, like a VPL, gives
        // what it gives at the clamp (`compensation` adds back the rest by rays).
        var d2c = d2;
        if kind == 0u {
            d2c = max(d2, p.direct_clamp * p.direct_clamp);
        }
        sum += ls.radiance.xyz * (f * cos_x / d2c);
    }
    var albedo = tris[g.w - 1u].albedo.xyz;
    if p.textured != 0u {
        albedo = surface[pix].albedo.xyz;
    }
    direct[pix] = vec4f(sum * f32(share) * albedo / PI, 1.0);
}
