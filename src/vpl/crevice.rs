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
//! out), but for the light of a crevice's VPL that reaches a pixel's point beyond its reach
//! (the reach, or `FAR` reaches below).
//!
//! A vertex with a ray out but fewer than a quarter, none of whose rays ends beyond [`FAR`]
//! reaches (deep in a 1 cm gap, where only grazing rays get past the reach), lights the
//! crevice and its surroundings alone: it too is the compensation's, read at a pixel's point
//! within `FAR` reaches, and the GPU's slots go to VPLs that light the room (a frame's slots
//! count the VPLs the GPU gathers: `sampler::common::paths_by`). And a light path goes on from
//! a crevice's vertex without Russian roulette on an albedo of 1 ([`Coin::crevice`]): the
//! light there has no way but out, and ended at 0.99 a bounce it came out on the few paths
//! that lived, weighted 1/0.99 a bounce (docs/math.md, "The room's slots").
//!
//! The rays and the coin draw from a stream of their own, seeded by (seed, path, depth): the
//! path's own random numbers are those it had without this (only whether its roulette may go
//! on at 1 depends on the rays), and a path re-traced in another frame of a still scene keeps
//! the same VPLs.

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

/// How far, in reaches, a crevice vertex's rays may end for its light to count as its
/// neighbourhood's alone: a vertex of which fewer than a quarter of the rays get beyond the
/// reach, and none beyond `FAR` reaches, lights the crevice and what lies within `FAR` reaches
/// of it, and the compensation reads it there ([`crate::vpl::Vpl::near`]).
pub const FAR: f32 = 4.0;

/// What the coin found at a vertex ([`coin`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coin {
    /// `Some((p, near))` if the vertex's VPL is kept: with probability `p` (its power divided
    /// by `p`), and `near` the distance within which the compensation alone reads it (`None`:
    /// the GPU's gather reads it, as any VPL).
    pub kept: Option<(f32, Option<f32>)>,
    /// Fewer than a quarter of the vertex's rays got beyond the reach: light here has a long
    /// way out, and a light path goes on from it without Russian roulette on albedo 1
    /// (`vpl::paths`).
    pub crevice: bool,
    /// None of the vertex's rays got beyond the reach: it is sealed in its crevice.
    pub sealed: bool,
}

/// The coin at the vertex `x` (normal `n`, facing the side the light arrived from) of light
/// path `path`, bounce `depth` ([`Coin`]). A vertex a quarter of whose rays or more get out is
/// kept, for the GPU. One none of whose rays got out is kept with probability [`NEAR_KEEP`]
/// and read within the reach; one with a ray out, but fewer than a quarter, with probability
/// `p = 4 open / RAYS`, and read by the compensation alone within [`FAR`] reaches if no ray got
/// that far, else by the GPU.
pub fn coin(tracer: &Tracer, x: Vec3, n: Vec3, (seed, path, depth): (u64, u64, u32)) -> Coin {
    let mut r = rng(&[seed, path, depth as u64, 0xc7e5]);
    let reach = REACH * tracer.size();
    let far = FAR * reach;
    let side = (RAYS as f32).sqrt() as u32;
    // The rays that got out (fewer than a quarter of them, or the vertex is no crevice).
    let mut out = [Vec3::ZERO; RAYS as usize / 4];
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
            out[open as usize] = d;
            open += 1;
            if 4 * open >= RAYS {
                return Coin {
                    kept: Some((1.0, None)),
                    crevice: false,
                    sealed: false,
                };
            }
        }
    }
    let kept = if open == 0 {
        // None got out: kept, rarely, for the compensation alone.
        (r.random::<f32>() < NEAR_KEEP).then_some((NEAR_KEEP, Some(reach)))
    } else {
        let p = (4 * open) as f32 / RAYS as f32;
        // Only for a crevice's vertex: whether a ray that got out gets beyond FAR reaches too.
        let beyond = || {
            out[..open as usize].iter().any(|&d| {
                tracer
                    .intersect_light(tracer.offset(x, n, d), d, far)
                    .is_none()
            })
        };
        (r.random::<f32>() < p).then(|| (p, (!beyond()).then_some(far)))
    };
    Coin {
        kept,
        crevice: true,
        sealed: open == 0,
    }
}
