// Compose: emission seen from the camera (front faces only) + direct + indirect, then exposure
// and the sRGB transfer for the 8-bit preview.

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var gbuf: texture_2d<u32>;
@group(0) @binding(3) var<storage, read> direct: array<vec4f>;
@group(0) @binding(4) var<storage, read> indirect: array<vec4f>;
@group(0) @binding(5) var<storage, read_write> hdr: array<vec4f>;
@group(0) @binding(6) var<storage, read_write> ldr: array<u32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= P.width || gid.y >= P.height {
        return;
    }
    let pix = gid.y * P.width + gid.x;
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    var c = vec3f(0.0);
    if g.w != 0u {
        let tri = tris[g.w - 1u];
        if dot(tri.n.xyz, P.cam_pos.xyz - gbuffer_x(g)) > 0.0 {
            c = tri.emission.xyz;
        }
        c += direct[pix].xyz + indirect[pix].xyz;
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
