//! The points each VPL's imperfect shadow map is splatted from, made on the CPU: the scene's
//! point set (by area, kept as triangle and barycentrics so it follows moving geometry), each
//! slot's subset of it, each VPL's ray-cast near-field points, and the fraction of the scene a
//! VPL sees, which sizes the subsets. The GPU passes that splat them are `gpu::ism`.

use crate::math::{rng, triangle_barycentrics};
use crate::scene::Frame;
use glam::{Vec2, Vec3};
use rand::Rng;

/// A point of the set: its triangle and barycentrics (b1, b2); `pad` is unused (0). The
/// layout of the WGSL `Point` (`shaders/ism_splat.wgsl`), checked by `gpu::ism`'s test.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Point {
    pub tri: u32,
    pub b1: f32,
    pub b2: f32,
    pub pad: u32,
}

/// `count` points on `frame`'s surfaces in proportion to area, in random order; points an
/// alpha MASK cuts away are drawn again (up to 64 times, so a scene cut away everywhere
/// still ends).
pub fn point_set(frame: &Frame, count: usize, seed: u64) -> Vec<Point> {
    let mut cdf = Vec::with_capacity(frame.areas.len());
    let mut acc = 0.0f64;
    for &a in &frame.areas {
        acc += a as f64;
        cdf.push(acc);
    }
    let mut r = rng(&[seed, 0x15a]);
    let cutouts = frame.has_cutouts();
    (0..count)
        .map(|_| {
            let mut draw = || {
                let u = r.random::<f64>() * acc;
                let tri = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
                (
                    tri,
                    triangle_barycentrics(Vec2::new(r.random(), r.random())),
                )
            };
            let (mut tri, mut b) = draw();
            for _ in 0..64 {
                if !cutouts || !frame.cut_at(tri, b.x, b.y) {
                    break;
                }
                (tri, b) = draw();
            }
            Point {
                tri: tri as u32,
                b1: b.x,
                b2: b.y,
                pad: 0,
            }
        })
        .collect()
}

/// The fraction of `frame`'s surface area a VPL sees: 64 points of its surfaces (by area,
/// standing in for VPLs, which light paths leave on surfaces) each look at 64 others (by
/// area) and count those in front of them, on the side of their surface that sees more, with
/// nothing between; the mean over the 64. What a VPL's points of the set land in its tile as
/// (the others fall behind its hemisphere or behind nearer surfaces).
pub fn seen_fraction(frame: &Frame, tracer: &crate::trace::Tracer, seed: u64) -> f32 {
    const LOOKERS: usize = 64;
    const TARGETS: usize = 64;
    let points = point_set(frame, LOOKERS * (TARGETS + 1), seed ^ 0x5ee);
    let at = |p: &Point| {
        let tri = p.tri as usize;
        (frame.point(tri, p.b1, p.b2), frame.normals[tri])
    };
    let seen: usize = points
        .chunks(TARGETS + 1)
        .map(|c| {
            let (a, na) = at(&c[0]);
            let (mut front, mut back) = (0, 0);
            for q in &c[1..] {
                let (b, nb) = at(q);
                let side = na.dot(b - a);
                if side != 0.0 && !tracer.occluded(a, na, b, nb) {
                    *(if side > 0.0 { &mut front } else { &mut back }) += 1;
                }
            }
            front.max(back)
        })
        .sum();
    seen as f32 / (LOOKERS * TARGETS) as f32
}

/// The pull-push levels a tile of side `size` runs for `--pull-levels` `levels`: at most
/// log2(size) - 1, so that the coarsest level is 2 x 2 (the shaders' `min(P.pull_levels,
/// sh - 1)`).
pub fn pull_levels_run(size: u32, levels: u32) -> u32 {
    levels.min(size.trailing_zeros().saturating_sub(1))
}

/// Side of the grid of near-field rays for a tile of `ism_size` texels whose holes pull-push
/// fills up to `2^pull_levels` texels: the rays land about 0.7 of that apart, so the nearest
/// surfaces a VPL sees leave no hole pull-push cannot close (13 for 64 texels, 3 levels).
pub fn near_grid(ism_size: u32, pull_levels: u32) -> u32 {
    let hole = 1u32 << pull_levels_run(ism_size, pull_levels);
    // At most a cell of two texels a side, so that every cell holds its ray's texel.
    (ism_size * 3 / (2 * hole) + 1)
        .clamp(4, 32)
        .min(ism_size / 2)
}

/// The near-field ray directions of a grid of side `n`, in a VPL's frame (z along its normal):
/// the centres of an n x n grid over the paraboloid map's square that fall inside its disk,
/// mapped back to directions, so they cover the tile evenly.
pub fn near_directions(n: u32) -> Vec<Vec3> {
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let u = (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
            let v = (j as f32 + 0.5) / n as f32 * 2.0 - 1.0;
            let r2 = u * u + v * v;
            if r2 < 1.0 {
                out.push(Vec3::new(2.0 * u, 2.0 * v, 1.0 - r2) / (1.0 + r2));
            }
        }
    }
    out
}

/// Each VPL's near-field points: the first surface hit by each of `dirs` (see
/// [`near_directions`]) cast from it, as (triangle, barycentrics), `u32::MAX` for a miss;
/// `dirs.len()` points per VPL, in slot order.
///
/// Why: the point set is spread over the scene by area, so a surface close to a VPL gets few
/// points while it covers most of the VPL's tile; the tile is then mostly holes and the VPL
/// shines through it. A VPL in a thin gap (between a lamp's top and the ceiling) sees the
/// room through its whole tile instead of a sliver. The ray-cast points are spread by solid
/// angle, so whatever a VPL sees first closes its tile: the splat keeps the plane of the
/// triangle each ray hit for its cell of the tile (the n x n grid whose centres the rays go
/// through), and every texel of the cell takes the depth at which its own direction meets
/// that plane where its own splat is farther or empty (`gpu::ism::plane_depth`).
pub fn near_points(
    tracer: &crate::trace::Tracer,
    vpls: &[super::ShadedVpl],
    dirs: &[Vec3],
) -> Vec<Point> {
    use rayon::prelude::*;
    vpls.par_iter()
        .flat_map_iter(|v| {
            let (t, b) = v.normal.any_orthonormal_pair();
            dirs.iter().map(move |d| {
                let w = t * d.x + b * d.y + v.normal * d.z;
                let o = tracer.offset(v.position, v.normal, w);
                match tracer.intersect_occluder(o, w, f32::INFINITY) {
                    Some(h) => Point {
                        tri: h.tri,
                        b1: h.b1,
                        b2: h.b2,
                        pad: 0,
                    },
                    None => Point {
                        tri: u32::MAX,
                        b1: 0.0,
                        b2: 0.0,
                        pad: 0,
                    },
                }
            })
        })
        .collect()
}

/// The offset into the point set of slot `slot`'s subset (depends on the seed and slot only).
pub fn slot_offset(seed: u64, slot: u32, num_points: u32) -> u32 {
    (crate::math::stream_seed(&[seed, slot as u64, 0x5107]) % num_points as u64) as u32
}
