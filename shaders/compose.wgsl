// Compose: emission seen from the camera (front faces only) + direct + indirect (where no
// geometry is seen, the environment the direct pass wrote), then exposure
// and the sRGB transfer for the 8-bit preview.
// Supersampled (P.aa = S > 1) it runs on every sub-sample of the grid of S x S tiles, while
// the indirect light (gather and interleave filter) was computed once per pixel, on tile 0,
// without the albedo: a sub-sample takes the irradiance of the pixel's tile-0 sample if that
// lies on its own surface (normals within ~25 degrees, within 1% of the camera distance of
// its tangent plane: `same_surface`), else of the nearest of the 8
// neighbouring pixels' samples that does, else the pixel's own; times its own albedo. It
// writes that per sub-sample (`indirect_ss`) for the downsample, and leaves the preview to it.

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var gbuf: texture_2d<u32>;
@group(0) @binding(3) var<storage, read> direct: array<vec4f>;
@group(0) @binding(4) var<storage, read> indirect: array<vec4f>;
@group(0) @binding(5) var<storage, read_write> hdr: array<vec4f>;
@group(0) @binding(6) var<storage, read_write> ldr: array<u32>;
@group(0) @binding(7) var<storage, read_write> indirect_ss: array<vec4f>;
@group(0) @binding(8) var<storage, read> surface: array<Surface>;

// Supersampled: the irradiance (no albedo) for sub-sample `q` at point x with normal n, from
// the tile-0 samples of its pixel and of the neighbouring pixels.
fn indirect_of(q: vec2u, x: vec3f, n: vec3f) -> vec3f {
    let s = max(P.aa, 1u);
    let size = vec2i(vec2u(P.width, P.height) / s);
    let px = vec2i(q % vec2u(size));
    let tol = surface_tol(x, P.cam_pos.xyz);
    // The pixel, its 4 edge neighbours, then its corners.
    var order = array<vec2i, 9>(
        vec2i(0, 0), vec2i(1, 0), vec2i(-1, 0), vec2i(0, 1), vec2i(0, -1),
        vec2i(1, 1), vec2i(-1, 1), vec2i(1, -1), vec2i(-1, -1));
    for (var k = 0; k < 9; k++) {
        let c = px + order[k];
        if c.x < 0 || c.y < 0 || c.x >= size.x || c.y >= size.y {
            continue;
        }
        let gc = textureLoad(gbuf, c, 0);
        if gc.w == 0u {
            continue;
        }
        let xc = gbuffer_x(gc);
        let nc = facing(tris[gc.w - 1u].n.xyz, xc, P.cam_pos.xyz);
        if same_surface(x, n, tol, xc, nc) {
            return indirect[u32(c.y) * P.width + u32(c.x)].xyz;
        }
    }
    return indirect[u32(px.y) * P.width + u32(px.x)].xyz;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= P.width || gid.y >= P.height {
        return;
    }
    let pix = gid.y * P.width + gid.x;
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    var c = vec3f(0.0);
    if g.w != 0u {
        // The triangle's fields one by one, and `surface` only when textured: a pass over
        // every sub-sample reads no more than it uses.
        let k = g.w - 1u;
        let tn = tris[k].n.xyz;
        if dot(tn, P.cam_pos.xyz - gbuffer_x(g)) > 0.0 {
            if P.textured != 0u {
                c = surface[pix].emission.xyz;
            } else {
                c = tris[k].emission.xyz;
            }
        }
        if P.aa > 1u {
            let x = gbuffer_x(g);
            let e = indirect_of(gid.xy, x, facing(tn, x, P.cam_pos.xyz));
            var albedo = tris[k].albedo.xyz;
            if P.textured != 0u {
                albedo = surface[pix].albedo.xyz;
            }
            let ind = e * albedo;
            indirect_ss[pix] = vec4f(ind, 1.0);
            c += direct[pix].xyz + ind;
        } else {
            c += direct[pix].xyz + indirect[pix].xyz;
        }
    } else {
        // No geometry: the environment, which the direct pass wrote there.
        c = direct[pix].xyz;
        if P.aa > 1u {
            indirect_ss[pix] = vec4f(0.0);
        }
    }
    hdr[pix] = vec4f(c, 1.0);
    // Supersampled, `resolve` makes the preview from the box-filtered pixels.
    if P.aa > 1u {
        return;
    }
    let t = clamp(c * P.exposure, vec3f(0.0), vec3f(1.0));
    let s = vec3u(vec3f(srgb_oetf(t.x), srgb_oetf(t.y), srgb_oetf(t.z)) * 255.0 + 0.5);
    ldr[pix] = s.x | (s.y << 8u) | (s.z << 16u) | (255u << 24u);
}
