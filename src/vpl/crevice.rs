//! Light paths in crevices (docs/math.md, "Light that cannot get out"): a vertex between two
//! surfaces closer than the renderer can resolve (a lamp's top under the ceiling) sees almost
//! nothing but the other surface, and a path there bounces hundreds of times before it leaves,
//! leaving a VPL at every bounce. Those VPLs filled the frame's slots (1000 of 1024 VPLs from 28
//! paths with a 1 mm gap) while lighting almost nothing the camera sees, and what they lit
//! through their ISMs was mostly leaks.
//!
//! So a light path keeps the VPL of a vertex with a probability `p` (and divides its power by
//! `p`), where `p` grows with how much of the vertex's cosine lobe reaches beyond its
//! neighbourhood: [`RAYS`] stratified cosine-distributed rays, of which `open` reach farther
//! than [`REACH`] of the scene's size, give `p = min(1, 4 open / RAYS)`. A vertex of which
//! a quarter of the rays or more get out is always kept (almost every vertex of an open room).
//! One of which no ray gets out lights little but the crevice itself, whose inside it is: it is
//! kept with probability [`NEAR_KEEP`], as a VPL that the GPU's gather does not see
//! ([`crate::vpl::Vpl::near`]) and that the compensation reads with exact visibility, at any
//! distance along its paths and within the reach at the point a pixel sees. Before, such a
//! vertex was dropped, and between two plates a quarter of the reach apart (a 1 cm gap in a 2 m
//! room) a third of the gap's light went with it: the compensation, which lights the gap's
//! inside from the VPLs, had 40% too little of it halfway in (docs/math.md, "Inside the 1 cm
//! gap"). The path goes on either way, so the light that leaves the crevice arrives as the
//! VPLs of its later vertices. Unbiased for every vertex (the coin's probability is divided
//! out), but for the light of a crevice's VPL that reaches a pixel's point beyond the reach.
//!
//! The rays and the coin draw from a stream of their own, seeded by (seed, path, depth): the
//! path's own random numbers, so its later vertices, are those it had without this, and a
//! path re-traced in another frame of a still scene keeps the same VPLs.

use crate::math::{cosine_hemisphere, rng};
use crate::trace::Tracer;
use glam::{Vec2, Vec3};
use rand::Rng;

/// Rays a vertex casts to find how much of its lobe gets out of its neighbourhood.
pub const RAYS: u32 = 16;

/// The probability that a vertex none of whose rays gets out is kept, as a VPL that only the
/// compensation reads ([`crate::vpl::Vpl::near`]).
pub const NEAR_KEEP: f32 = 1.0 / 16.0;

/// The neighbourhood's radius, as a fraction of the scene's size (its bounding box's largest
/// side): the default distance clamp's order (2% of the diagonal), within which the gather
/// cannot tell one distance from another.
pub const REACH: f32 = 0.02;

/// The probability that the VPL at `x` (normal `n`, facing the side the light arrived from) of
/// light path `path`, bounce `depth`, is kept, and the coin: Some((p, near)) if kept, `near`
/// when none of its rays got out (kept with probability [`NEAR_KEEP`] for the compensation
/// alone, which reads VPLs with exact visibility: the GPU's gather does not see it).
pub fn keep(
    tracer: &Tracer,
    x: Vec3,
    n: Vec3,
    (seed, path, depth): (u64, u64, u32),
) -> Option<(f32, bool)> {
    let mut r = rng(&[seed, path, depth as u64, 0xc7e5]);
    let reach = REACH * tracer.size();
    let side = (RAYS as f32).sqrt() as u32;
    let mut open = 0u32;
    for i in 0..RAYS {
        let u = Vec2::new(
            ((i % side) as f32 + r.random::<f32>()) / side as f32,
            ((i / side) as f32 + r.random::<f32>()) / side as f32,
        );
        let d = cosine_hemisphere(n, u);
        if tracer
            .intersect_light(tracer.offset(x, n, d), d, reach)
            .is_none()
        {
            open += 1;
            if 4 * open >= RAYS {
                return Some((1.0, false));
            }
        }
    }
    if open == 0 {
        // None got out: kept, rarely, for the compensation alone.
        return (r.random::<f32>() < NEAR_KEEP).then_some((NEAR_KEEP, true));
    }
    let p = (4 * open) as f32 / RAYS as f32;
    (r.random::<f32>() < p).then_some((p, false))
}
