// Interleave filter: recombines the interleaved gather's subsets. Each pixel averages the
// n^2-scaled subset sums of the pixels of the window centred on it that lie on its own
// surface (normals within ~25 degrees, and within 1% of the camera distance of its tangent
// plane), then applies its albedo. The window is n x n for odd n; for even n it is
// (n+1) x (n+1) with half weights on its outer rows and columns (their pixels carry the same
// subsets), so that it stays centred. On a flat region it holds every subset with total
// weight one; any
// accepted neighbour's value alone is an unbiased estimate of the full gather over the
// pattern's random shift, so their mean is too.
// Supersampled (P.aa = S > 1) the grid is S x S tiles, each a whole image: the window
// keeps to the pixel's own tile.

@group(0) @binding(0) var<storage, read> P: FrameConstants;
@group(0) @binding(1) var<storage, read> tris: array<Tri>;
@group(0) @binding(2) var gbuf: texture_2d<u32>;
@group(0) @binding(3) var<storage, read> subsets: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> indirect: array<vec4f>;
@group(0) @binding(5) var<storage, read> surface: array<Surface>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    // One read of the parameters into registers (a storage buffer is not hoisted).
    let p = P;
    if gid.x >= p.width || gid.y >= p.height {
        return;
    }
    let pix = gid.y * p.width + gid.x;
    let g = textureLoad(gbuf, vec2i(gid.xy), 0);
    if g.w == 0u {
        indirect[pix] = vec4f(0.0);
        return;
    }
    let x = gbuffer_x(g);
    let n = facing(tris[g.w - 1u].n.xyz, x, p.cam_pos.xyz);
    let tol = surface_tol(x, p.cam_pos.xyz);
    let side = i32(max(p.interleave, 1u));
    let even = side % 2 == 0;
    let h = side / 2;
    // The pixel's tile of the sub-sample grid (the whole grid without supersampling).
    let s = max(p.aa, 1u);
    let tile = vec2u(p.width / s, p.height / s);
    let lo = vec2i((gid.xy / tile) * tile);
    let hi = lo + vec2i(tile);
    var sum = vec3f(0.0);
    var count = 0.0;
    for (var dy = -h; dy <= h; dy++) {
        for (var dx = -h; dx <= h; dx++) {
            let q = vec2i(gid.xy) + vec2i(dx, dy);
            if q.x < lo.x || q.y < lo.y || q.x >= hi.x || q.y >= hi.y {
                continue;
            }
            let gq = textureLoad(gbuf, q, 0);
            if gq.w == 0u {
                continue;
            }
            let xq = gbuffer_x(gq);
            let nq = facing(tris[gq.w - 1u].n.xyz, xq, p.cam_pos.xyz);
            if !same_surface(x, n, tol, xq, nq) {
                continue;
            }
            let wx = select(1.0, 0.5, even && abs(dx) == h);
            let wy = select(1.0, 0.5, even && abs(dy) == h);
            sum += wx * wy * subsets[u32(q.y) * p.width + u32(q.x)].xyz;
            count += wx * wy;
        }
    }
    // The pixel itself always passes (weight 1): count >= 1.
    // Supersampled, compose applies each sub-sample's own albedo.
    var albedo = vec3f(1.0);
    if p.aa <= 1u {
        albedo = select(tris[g.w - 1u].albedo.xyz, surface[pix].albedo.xyz, p.textured != 0u);
    }
    indirect[pix] = vec4f(sum / count * albedo, 1.0);
}
