// Shared by every pass (prepended by the Rust side).

const PI: f32 = 3.14159265358979;

// One scene triangle: vertices, unit geometric normal (in w its sides: 0 double-sided, 1
// single-sided on a closed mesh, 2 single-sided elsewhere; see `Frame::sides`), albedo and
// emitted radiance.
struct Tri {
    v0: vec4f,
    v1: vec4f,
    v2: vec4f,
    n: vec4f,
    albedo: vec4f,
    emission: vec4f,
}

// A sample's albedo (alpha in w) and emitted radiance, from the `surface` pass (textured
// scenes; otherwise the triangle's are used).
struct Surface {
    albedo: vec4f,
    emission: vec4f,
}

// A VPL: position, unit normal (facing where its light arrived from), and its weighted flux
// `power * albedo_y * weight` (RGB). A VPL on the way out of a crevice has in the w's
// (pos.w, normal.w, flux.w) its fan's plane normal (zeros for any other VPL; `vpl_lobe`).
struct GpuVpl {
    pos: vec4f,
    normal: vec4f,
    flux: vec4f,
}

// How a VPL's light falls off toward the unit direction `w` it leaves along: the cosine to its
// normal, or for a VPL on the way out of a crevice pi times its fan's density (the CPU's
// `ShadedVpl::lobe` and `vpl::fan_lobe`).
fn vpl_lobe(v: GpuVpl, w: vec3f) -> f32 {
    let nf = vec3f(v.pos.w, v.normal.w, v.flux.w);
    let d = v.normal.xyz;
    if all(nf == vec3f(0.0)) {
        return dot(d, w);
    }
    let sd = dot(d, nf);
    let sw = dot(w, nf);
    if sd <= 0.0 || sw <= 0.0 {
        return 0.0;
    }
    let ed = asin(min(sd, 1.0));
    let h = min(ed, 0.5 * PI - ed);
    if h <= 0.0 || abs(asin(min(sw, 1.0)) - ed) >= h {
        return 0.0;
    }
    let a = d - nf * sd;
    let b = w - nf * sw;
    let la = length(a);
    let lb2 = dot(b, b);
    let ab = dot(a, b);
    if ab <= 0.0 || la <= 0.0 || lb2 <= 0.0 {
        return 0.0;
    }
    return PI * ab / (la * lb2) / (4.0 * h);
}

// An emitter sample for direct light: position, unit normal, and `Le / (pdf * count)`.
struct GpuEmitterSample {
    pos: vec4f,
    normal: vec4f,
    radiance: vec4f,
    // One windowed shadow face (z > 0): the window's centre (x, y) and scale (z, w) in the
    // plane at unit distance along the normal; see `shadow::Window`.
    window: vec4f,
}

// Frame constants, the same buffer for every pass.
struct FrameConstants {
    width: u32,
    height: u32,
    num_vpls: u32,
    ism_size: u32,
    ism_points: u32,
    num_points: u32,
    num_light_samples: u32,
    shadow_size: u32,
    far: f32,
    clamp: f32,
    exposure: f32,
    ism_bias: f32,
    cam_pos: vec4f,
    shadow_bias: f32,
    near: f32,
    pull_levels: u32,
    num_changed: u32, // ISM slots redrawn this frame
    interleave: u32, // interleaved gather block side (1: off)
    shift_x: u32, // the interleave pattern's shift
    shift_y: u32,
    aa: u32, // sub-samples per pixel side (width, height: the sub-sample grid's)
    near_points: u32,
    textured: u32, // 1: `surface` holds each sample's albedo and emission
    near_grid: u32,
    ism_level1: u32, // where level 1 of the ISM pyramid starts (0: no pull-push levels)
    direct_clamp: f32, // emitter triangles' samples clamped at this distance (0: not; `compensation` adds the rest)
    direct_split: u32, // 1: a pixel's sub-samples split the emitter samples among them (direct.wgsl)
    pad1: u32,
    pad2: u32,
}

// Orthonormal basis (t, b) around unit n (Duff et al. 2017), the same as math::basis.
fn basis_t(n: vec3f) -> vec3f {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    return vec3f(1.0 + s * n.x * n.x * a, s * n.x * n.y * a, -s * n.x);
}
fn basis_b(n: vec3f) -> vec3f {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    return vec3f(n.x * n.y * a, s + n.y * n.y * a, -n.y);
}

// Paraboloid texel of unit direction `d` (already known to have dot(d, n) > 0) around `n`.
fn paraboloid_texel(d: vec3f, n: vec3f, size: u32) -> u32 {
    let lx = dot(d, basis_t(n));
    let ly = dot(d, basis_b(n));
    let lz = dot(d, n);
    let uv = vec2f(lx, ly) / (1.0 + lz);
    let fs = f32(size);
    let t = clamp(vec2i(floor((uv * 0.5 + 0.5) * fs)), vec2i(0), vec2i(i32(size) - 1));
    return u32(t.y) * size + u32(t.x);
}

// The unit normal `n` turned to face the camera at `cam` from surface point `x` (surfaces
// reflect on both sides).
fn facing(n: vec3f, x: vec3f, cam: vec3f) -> vec3f {
    return select(n, -n, dot(n, cam - x) < 0.0);
}

// tan of the angle whose cosine is `c` (> 0), capped at 4: how steeply depth changes across a
// texel on a receiver seen at that angle.
fn slope(c: f32) -> f32 {
    return min(sqrt(max(1.0 - c * c, 0.0)) / c, 4.0);
}

// An ISM pyramid value `depth + 4 * level` (>= 0): its level and normalized depth.
fn ism_level(v: f32) -> f32 {
    return floor(v * 0.25);
}
fn ism_depth(v: f32) -> f32 {
    return v - 4.0 * ism_level(v);
}

// The G-buffer texel: xyz world position bits, w = triangle index + 1 (0: nothing hit).
// The tile of the sub-sample grid of `size` samples with `aa` sub-samples per pixel side
// that sample `q` lies in, row-major (0 without supersampling): tile t = ty * aa + tx holds
// every pixel's sub-sample (tx, ty).
fn subsample_tile(q: vec2u, size: vec2u, aa: u32) -> u32 {
    let s = max(aa, 1u);
    let t = q / (size / s);
    return min(t.y, s - 1u) * s + min(t.x, s - 1u);
}

fn gbuffer_x(g: vec4u) -> vec3f {
    return bitcast<vec3f>(g.xyz);
}

// The surface test of the passes that combine neighbouring samples (interleave filter,
// compose, temporal accumulation): a sample at xq with normal nq lies on the surface of x
// with normal n if their normals are within ~25 degrees and xq within `tol` of x's tangent
// plane, `tol` = surface_tol(x, camera position): 1% of x's distance from the camera.
const SURFACE_NORMAL_COS: f32 = 0.9;
const SURFACE_PLANE_REL: f32 = 0.01;

fn surface_tol(x: vec3f, cam: vec3f) -> f32 {
    return SURFACE_PLANE_REL * distance(x, cam);
}

fn same_surface(x: vec3f, n: vec3f, tol: f32, xq: vec3f, nq: vec3f) -> bool {
    return dot(nq, n) >= SURFACE_NORMAL_COS && abs(dot(xq - x, n)) <= tol;
}

fn srgb_oetf(v: f32) -> f32 {
    if v <= 0.0031308 {
        return 12.92 * v;
    }
    return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}
