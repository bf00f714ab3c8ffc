// Resolve (supersampling, `--aa S` > 1): the passes before it ran on S x S tiles of the
// output size (P.width and P.height are the tiles' together), tile (i, j) holding every
// pixel's sub-sample at offset (i, j) inside it (an n-rooks lattice: see gbuffer.rs). Each
// output pixel is the unweighted mean of its S^2 sub-samples: a box filter over the pixel's
// area, whose expectation the reference's uniformly jittered samples estimate too. The HDR
// frame and its components (direct, indirect) are resolved alike (the box filter is linear,
// so the resolved parts still sum to the resolved frame), then the 8-bit preview is taken
// from the resolved HDR.

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> hdr_in: array<vec4f>;
@group(0) @binding(2) var<storage, read> direct_in: array<vec4f>;
@group(0) @binding(3) var<storage, read> indirect_in: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> hdr: array<vec4f>;
@group(0) @binding(5) var<storage, read_write> ldr: array<u32>;
@group(0) @binding(6) var<storage, read_write> direct: array<vec4f>;
@group(0) @binding(7) var<storage, read_write> indirect: array<vec4f>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    // One read of the parameters into registers (a storage buffer is not hoisted).
    let p = P;
    let s = max(p.aa, 1u);
    let w = p.width / s;
    let h = p.height / s;
    if gid.x >= w || gid.y >= h {
        return;
    }
    var c = vec3f(0.0);
    var d = vec3f(0.0);
    var i = vec3f(0.0);
    for (var ty = 0u; ty < s; ty++) {
        for (var tx = 0u; tx < s; tx++) {
            let q = (ty * h + gid.y) * p.width + tx * w + gid.x;
            c += hdr_in[q].xyz;
            d += direct_in[q].xyz;
            i += indirect_in[q].xyz;
        }
    }
    let k = 1.0 / f32(s * s);
    let pix = gid.y * w + gid.x;
    c *= k;
    hdr[pix] = vec4f(c, 1.0);
    direct[pix] = vec4f(d * k, 1.0);
    indirect[pix] = vec4f(i * k, 1.0);
    let t = clamp(c * p.exposure, vec3f(0.0), vec3f(1.0));
    let q = vec3u(vec3f(srgb_oetf(t.x), srgb_oetf(t.y), srgb_oetf(t.z)) * 255.0 + 0.5);
    ldr[pix] = q.x | (q.y << 8u) | (q.z << 16u) | (255u << 24u);
}
