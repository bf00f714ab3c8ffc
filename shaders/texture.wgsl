// Textures, shared by the passes that read them (`surface`, and `gbuffer` and `shadow`
// for alpha MASK cut-outs); each of them declares `tris`, `attrs`, `materials`, `textures`
// and `texels`. Sampling as scene::texture documents: sRGB texels decoded, then blended
// (LINEAR) or the nearest (NEAREST), the wrap mode applied to each texel index.

// Whether any material has an alpha MASK.
struct Cutouts {
    on: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct TriAttr {
    uv0: vec4f, // corner 0: set 0 in xy, set 1 in zw
    uv1: vec4f,
    uv2: vec4f,
    c0: vec4f, // COLOR_0 of the corners
    c1: vec4f,
    c2: vec4f,
    mat: vec4u, // x: material index
}

struct SurfaceMaterial {
    base_tex: vec4u, // x: texture + 1 (0: none), y: UV set, z: alpha factor (bits)
    base_r0: vec4f, // UV transform rows
    base_r1: vec4f,
    emis_tex: vec4u,
    emis_r0: vec4f,
    emis_r1: vec4f,
}

struct TexInfo {
    offset: u32,
    width: u32,
    height: u32,
    flags: u32, // wrap s (bits 0-1), wrap t (2-3): 0 repeat, 1 clamp, 2 mirror; bit 4 nearest
}

fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn wrap_index(i: i32, n: i32, mode: u32) -> i32 {
    if mode == 1u {
        return clamp(i, 0, n - 1);
    }
    if mode == 2u {
        let k = ((i % (2 * n)) + 2 * n) % (2 * n);
        return select(2 * n - 1 - k, k, k < n);
    }
    return ((i % n) + n) % n;
}

fn reduce(u: f32, mode: u32) -> f32 {
    if mode == 1u {
        return clamp(u, -1.0, 2.0);
    }
    return u - 2.0 * floor(u * 0.5);
}

fn texel(t: TexInfo, i: i32, j: i32) -> vec4f {
    let ii = wrap_index(i, i32(t.width), t.flags & 3u);
    let jj = wrap_index(j, i32(t.height), (t.flags >> 2u) & 3u);
    let p = texels[t.offset + u32(jj) * t.width + u32(ii)];
    let c = vec4f(f32(p & 255u), f32((p >> 8u) & 255u), f32((p >> 16u) & 255u), f32(p >> 24u)) / 255.0;
    return vec4f(srgb_decode(c.x), srgb_decode(c.y), srgb_decode(c.z), c.w);
}

fn tex_sample(t: TexInfo, uv_in: vec2f) -> vec4f {
    let uv = vec2f(reduce(uv_in.x, t.flags & 3u), reduce(uv_in.y, (t.flags >> 2u) & 3u));
    let x = uv.x * f32(t.width) - 0.5;
    let y = uv.y * f32(t.height) - 0.5;
    if (t.flags & 16u) != 0u {
        return texel(t, i32(floor(x + 0.5)), i32(floor(y + 0.5)));
    }
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i = i32(x0);
    let j = i32(y0);
    let top = mix(texel(t, i, j), texel(t, i + 1, j), fx);
    let bottom = mix(texel(t, i, j + 1), texel(t, i + 1, j + 1), fx);
    return mix(top, bottom, fy);
}

// A material's texture (index + 1 in tex.x, UV set in tex.y) at the corners' UVs.
fn lookup(tex: vec4u, r0: vec4f, r1: vec4f, a: TriAttr, b: vec3f) -> vec4f {
    if tex.x == 0u {
        return vec4f(1.0);
    }
    var uv = a.uv0.xy * b.x + a.uv1.xy * b.y + a.uv2.xy * b.z;
    if tex.y == 1u {
        uv = a.uv0.zw * b.x + a.uv1.zw * b.y + a.uv2.zw * b.z;
    }
    let q = vec2f(dot(r0.xyz, vec3f(uv, 1.0)), dot(r1.xyz, vec3f(uv, 1.0)));
    return tex_sample(textures[tex.x - 1u], q);
}

// Albedo and alpha (factor x base colour texture x COLOR_0) of triangle k at point x.
fn base_color(k: u32, x: vec3f) -> vec4f {
    let tri = tris[k];
    let b = barycentrics(tri, x);
    let a = attrs[k];
    let m = materials[a.mat.x];
    let color = a.c0 * b.x + a.c1 * b.y + a.c2 * b.z;
    return vec4f(tri.albedo.xyz, bitcast<f32>(m.base_tex.z)) * lookup(m.base_tex, m.base_r0, m.base_r1, a, b) * color;
}

// Barycentrics (1 - b1 - b2, b1, b2) of x in tri (as the CPU tracer computes them).
fn barycentrics(tri: Tri, x: vec3f) -> vec3f {
    let e1 = tri.v1.xyz - tri.v0.xyz;
    let e2 = tri.v2.xyz - tri.v0.xyz;
    let n = cross(e1, e2);
    let inv = 1.0 / dot(n, n);
    let b1 = clamp(dot(cross(e2, x - tri.v0.xyz), -n) * inv, 0.0, 1.0);
    let b2 = clamp(dot(cross(e1, x - tri.v0.xyz), n) * inv, 0.0, 1.0);
    return vec3f(1.0 - b1 - b2, b1, b2);
}

// Whether an alpha MASK cuts triangle k away at x (cutoff in base_tex.w, negative: none).
fn cut_away(k: u32, x: vec3f) -> bool {
    let cutoff = bitcast<f32>(materials[attrs[k].mat.x].base_tex.w);
    return cutoff > 0.0 && base_color(k, x).w < cutoff;
}
