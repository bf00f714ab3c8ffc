// Temporal accumulation of the indirect light (`--accumulate N`): each pixel's indirect
// estimate (the gather's, interleave-filtered; per pixel on tile 0 of the sub-sample grid)
// is averaged with the pixel's history, the running mean of the estimates of the same
// surface point in earlier frames, found by reprojecting the point into the last frame's
// image. The mean runs over up to H.offset.z frames: out = hist + (cur - hist) / n with n the
// history's frame count plus one, so a still view averages n independent VPL sets exactly.
// The history is bilinear over the 4 samples around the reprojected point, each kept only if
// it lay on the pixel's own surface (normals within ~25 degrees, within 1% of the camera
// distance of its tangent plane: `same_surface`): a disoccluded pixel starts anew.
//
// How the history is used, the CPU says (H.offset.w): 1 as it is, when the triangles and
// emitter samples are the same bits as last frame's (the light is the same, only its estimate
// differs); 2 after the light's temporal gradient (`vpl::gradient`), when they changed: the
// relative change lambda of the light, read bilinearly from a coarse grid over the image,
// raises this frame's weight from the history's 1 / n to 1 / n + (1 - 1 / n) lambda; 0 none.

struct History {
    // The last frame's view-projection (the G-buffer's, unjittered).
    prev_view_proj: mat4x4f,
    // x, y: tile 0's sub-sample offset inside a pixel; z: the most frames averaged; w: 0 no
    // history, 1 as it is, 2 after the gradient.
    offset: vec4f,
    // x, y: the gradient grid's width and height.
    grid: vec4f,
}

// One pixel's history: the running mean (rgb) and its frame count (w), and the G-buffer
// sample it is of (position bits, triangle + 1; w = 0: none).
struct HistorySample {
    mean: vec4f,
    sample: vec4u,
}

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> H: History;
@group(0) @binding(2) var<storage, read> tris: array<Tri>;
@group(0) @binding(3) var gbuf: texture_2d<u32>;
@group(0) @binding(4) var<storage, read> current: array<vec4f>;
@group(0) @binding(5) var<storage, read> hist_in: array<HistorySample>;
@group(0) @binding(6) var<storage, read_write> output: array<vec4f>;
@group(0) @binding(7) var<storage, read_write> hist_out: array<HistorySample>;
@group(0) @binding(8) var<storage, read> gradient: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    let p = P;
    // One sample per pixel: the pixel grid is tile 0 of the sub-sample grid.
    let s = max(p.aa, 1u);
    let size = vec2u(p.width / s, p.height / s);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let pix = gid.y * p.width + gid.x;
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    let cur = current[pix].xyz;
    if g.w == 0u {
        output[pix] = vec4f(cur, 1.0);
        hist_out[pix] = HistorySample(vec4f(cur, 1.0), g);
        return;
    }
    let x = gbuffer_x(g);
    let n = facing(tris[g.w - 1u].n.xyz, x, p.cam_pos.xyz);
    let tol = surface_tol(x, p.cam_pos.xyz);
    var hist = vec3f(0.0);
    var frames = 0.0;
    var wsum = 0.0;
    let clip = H.prev_view_proj * vec4f(x, 1.0);
    if H.offset.w > 0.0 && clip.w > 0.0 {
        let ndc = clip.xy / clip.w;
        // Continuous coordinates on the last frame's grid of tile-0 samples.
        let c = vec2f((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * vec2f(size) - H.offset.xy;
        let base = vec2i(floor(c));
        let f = c - floor(c);
        for (var k = 0; k < 4; k++) {
            let o = vec2i(k & 1, k >> 1u);
            let q = base + o;
            if q.x < 0 || q.y < 0 || q.x >= i32(size.x) || q.y >= i32(size.y) {
                continue;
            }
            let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
            let qi = u32(q.y) * p.width + u32(q.x);
            let gq = hist_in[qi].sample;
            if w <= 0.0 || gq.w == 0u {
                continue;
            }
            let xq = gbuffer_x(gq);
            let nq = facing(tris[gq.w - 1u].n.xyz, xq, p.cam_pos.xyz);
            if !same_surface(x, n, tol, xq, nq) {
                continue;
            }
            let h = hist_in[qi].mean;
            hist += w * h.xyz;
            frames += w * h.w;
            wsum += w;
        }
    }
    var acc = cur;
    var count = 1.0;
    // Half the bilinear weight at least, else the history is too thin to trust.
    if wsum >= 0.5 {
        var prev = min(frames / wsum, H.offset.z - 1.0);
        if H.offset.w > 1.5 {
            // This frame's weight 1 / count, raised by the light's relative change.
            let a = 1.0 / (prev + 1.0);
            prev = 1.0 / (a + (1.0 - a) * change(gid.xy, size)) - 1.0;
        }
        count = prev + 1.0;
        acc = hist / wsum + (cur - hist / wsum) / count;
    }
    output[pix] = vec4f(acc, 1.0);
    hist_out[pix] = HistorySample(vec4f(acc, count), g);
}

// The light's relative change at sample `q` of the `size` grid of samples: the gradient grid
// read bilinearly at the sample's place in the image (clamped to the grid's cell centres).
fn change(q: vec2u, size: vec2u) -> f32 {
    let g = vec2i(H.grid.xy);
    let c = (vec2f(q) + 0.5) / vec2f(size) * H.grid.xy - 0.5;
    let c0 = clamp(vec2i(floor(c)), vec2i(0), g - 1);
    let c1 = min(c0 + 1, g - 1);
    let f = clamp(c - vec2f(c0), vec2f(0.0), vec2f(1.0));
    let l00 = gradient[c0.y * g.x + c0.x];
    let l10 = gradient[c0.y * g.x + c1.x];
    let l01 = gradient[c1.y * g.x + c0.x];
    let l11 = gradient[c1.y * g.x + c1.x];
    return clamp(mix(mix(l00, l10, f.x), mix(l01, l11, f.x), f.y), 0.0, 1.0);
}
