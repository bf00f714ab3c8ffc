// Surface: each sample's albedo (factor x base colour texture x COLOR_0, alpha in w) and
// emitted radiance (factor x emissive texture), for scenes with textures or vertex colours.
// Textures are sampled by `texture.wgsl` (prepended).

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var gbuf: texture_2d<u32>;
@group(0) @binding(3) var<storage, read> attrs: array<TriAttr>;
@group(0) @binding(4) var<storage, read> materials: array<SurfaceMaterial>;
@group(0) @binding(5) var<storage, read> textures: array<TexInfo>;
@group(0) @binding(6) var<storage, read> texels: array<u32>;
@group(0) @binding(7) var<storage, read_write> surface: array<Surface>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= P.width || gid.y >= P.height {
        return;
    }
    let pix = gid.y * P.width + gid.x;
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    if g.w == 0u {
        surface[pix] = Surface(vec4f(0.0), vec4f(0.0));
        return;
    }
    let k = g.w - 1u;
    let x = gbuffer_x(g);
    let base = base_color(k, x);
    var emission = tris[k].emission.xyz;
    if max(emission.x, max(emission.y, emission.z)) > 0.0 {
        let a = attrs[k];
        let m = materials[a.mat.x];
        emission *= lookup(m.emis_tex, m.emis_r0, m.emis_r1, a, barycentrics(tris[k], x)).xyz;
    }
    surface[pix] = Surface(base, vec4f(emission, 1.0));
}
