//! What the samplers share: fresh light paths, the frame's candidates with their floored
//! importance, stratified CDF draws, the MH acceptance test, and the weighted selection.

use super::Selection;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::importance::{importance_all_sampled, CameraPoint};
use crate::vpl::{trace_path, ShadedVpl, Vpl};
use rand::Rng;
use std::collections::{HashMap, HashSet};
use std::time::Instant;

/// Path ids of frame f start at f * PATHS_PER_FRAME, so frames draw independent paths.
pub const PATHS_PER_FRAME: u64 = 1 << 32;

/// Identity of a VPL: (path id, depth). The path can be re-traced in any frame.
pub type Key = (u64, u32);

pub fn key(v: &Vpl) -> Key {
    (v.path, v.depth)
}

/// The VPLs of paths `stream * 2^32 + k`, k = 0, 1, ... (`stream` is the frame index for
/// fresh paths, a fixed number for paths that are the same every frame). Paths are added
/// until there are `target` VPLs the GPU gathers (`whole`: only whole paths that fit; a
/// crevice's `near` VPLs come along uncounted); returns the VPLs and the number of paths.
pub fn fresh_paths(
    frame: &Frame,
    tracer: &Tracer,
    seed: u64,
    stream: u64,
    target: usize,
    whole: bool,
) -> (Vec<Vpl>, u64) {
    paths_by(
        frame,
        tracer,
        seed,
        |k| stream * PATHS_PER_FRAME + k,
        target,
        whole,
    )
}

/// How many VPLs, the compensation's included, a frame's paths may leave for each slot
/// ([`paths_by`]): the sweep's 1 mm gap left about 8 (9300 for 1024 slots) when paths bounced
/// up to 1024 times in the gap with `vpl::crevice`'s coin at each bounce (now up to 16384, with
/// the coin at every 16th bounce past 256, `vpl::paths::DEEP`).
pub const NEAR_SLOTS: usize = 16;

/// [`fresh_paths`] with the k-th path's id given by `id(k)`.
pub fn paths_by(
    frame: &Frame,
    tracer: &Tracer,
    seed: u64,
    id: impl Fn(u64) -> u64 + Sync,
    target: usize,
    whole: bool,
) -> (Vec<Vpl>, u64) {
    let mut vpls = Vec::with_capacity(target + 16);
    // The slots count the VPLs the GPU gathers: a crevice's `near` VPLs, which the
    // compensation alone reads (vpl::crevice), take none.
    let gathered = |p: &[Vpl]| p.iter().filter(|v| v.near.is_none()).count();
    let mut filled = 0usize;
    let mut paths = 0u64;
    // Batches of paths in parallel, kept in path order; in a scene that is all crevice (its
    // paths leave the compensation's VPLs alone, each path up to paths::MAX_DEPTH bounces of
    // them), only until NEAR_SLOTS times the slots of those.
    let most = NEAR_SLOTS * target.max(1);
    while filled < target && paths < 64 * target as u64 + 1024 && vpls.len() < most {
        let batch = ((target - filled) / 2).clamp(1, 4096) as u64;
        let traced: Vec<Vec<Vpl>> = {
            use rayon::prelude::*;
            (paths..paths + batch)
                .into_par_iter()
                .map(|k| trace_path(frame, tracer, seed, id(k)))
                .collect()
        };
        for p in traced {
            let n = gathered(&p);
            if whole && filled == 0 && n > target {
                // One path longer than every slot (an albedo-1 room can bounce for hundreds
                // of vertices): its first `target` VPLs, rather than no light at all.
                let mut left = target;
                vpls.extend(p.into_iter().take_while(|v| {
                    let take = left > 0;
                    left -= usize::from(take && v.near.is_none());
                    take
                }));
                return (vpls, 1);
            }
            if filled >= target || vpls.len() >= most || (whole && filled + n > target) {
                return (vpls, paths);
            }
            // A path that left no VPL (its light escaped) still counts as a path.
            vpls.extend(p);
            filled += n;
            paths += 1;
        }
    }
    (vpls, paths)
}

/// Stratified inverse-transform draws of `n` indices from weights `w`.
pub fn cdf_draw(w: &[f32], n: usize, r: &mut impl Rng) -> Vec<usize> {
    let mut cdf = Vec::with_capacity(w.len());
    let mut acc = 0.0f64;
    for &x in w {
        acc += x as f64;
        cdf.push(acc);
    }
    (0..n)
        .map(|j| {
            let u = (j as f64 + r.random::<f64>()) / n as f64 * acc;
            cdf.partition_point(|&c| c <= u).min(w.len() - 1)
        })
        .collect()
}

/// One Metropolis-Hastings decision: accept a proposal of importance `proposed` from a state
/// of importance `current` (a state of importance 0 always moves).
pub fn mh_accept(current: f32, proposed: f32, u: f32) -> bool {
    current <= 0.0 || u * current < proposed
}

/// Candidates of a frame with their floored importance.
pub struct Candidates {
    pub vpls: Vec<Vpl>,
    /// Floored importance.
    pub importance: Vec<f32>,
    /// Importance without the floor.
    pub raw: Vec<f32>,
    pub paths: u64,
    /// Seconds spent tracing the candidates' paths.
    pub paths_s: f64,
    /// eps * mean(I), added to every I.
    pub floor: f32,
    /// Mean floored importance.
    pub b: f32,
}

impl Candidates {
    /// The VPLs of fresh paths of `stream` until there are at least `m`, and their importance
    /// plus the floor `eps * mean(I)`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        frame: &Frame,
        tracer: &Tracer,
        points: &[CameraPoint],
        seed: u64,
        stream: u64,
        m: usize,
        eps: f32,
        clamp: f32,
    ) -> Self {
        let t = Instant::now();
        let (vpls, paths) = fresh_paths(frame, tracer, seed, stream, m, false);
        Self::of(
            vpls,
            paths,
            t.elapsed().as_secs_f64(),
            tracer,
            points,
            eps,
            clamp,
        )
    }

    /// Candidates `vpls` (of `paths` paths, traced in `paths_s` seconds) with their floored
    /// importance.
    pub fn of(
        vpls: Vec<Vpl>,
        paths: u64,
        paths_s: f64,
        tracer: &Tracer,
        points: &[CameraPoint],
        eps: f32,
        clamp: f32,
    ) -> Self {
        Self::sampled(vpls, (paths, paths_s), tracer, (points, 1), eps, clamp)
    }

    /// [`Candidates::of`] with each importance estimated from the camera points of every
    /// `stride`-th stratum ([`crate::vpl::importance::importance_sampled`]).
    pub fn sampled(
        vpls: Vec<Vpl>,
        (paths, paths_s): (u64, f64),
        tracer: &Tracer,
        (points, stride): (&[CameraPoint], usize),
        eps: f32,
        clamp: f32,
    ) -> Self {
        let raw = importance_all_sampled(&vpls, points, tracer, clamp, stride);
        let mean = raw.iter().map(|&x| x as f64).sum::<f64>() / raw.len().max(1) as f64;
        let floor = (eps as f64 * mean) as f32;
        Candidates {
            importance: raw.iter().map(|&x| x + floor).collect(),
            raw,
            vpls,
            paths,
            paths_s,
            floor,
            b: (mean * (1.0 + eps as f64)) as f32,
        }
    }

    /// `b / N * (M / P)`: a chosen VPL's weight is this over its floored importance.
    pub fn scale(&self, n: usize) -> f32 {
        self.b / n as f32 * (self.vpls.len() as f32 / self.paths.max(1) as f32)
    }
}

/// The selection of `chosen` VPLs with weights `scale / I`.
pub fn weighted(
    chosen: Vec<Vpl>,
    importance: &[f32],
    scale: f32,
    paths: u64,
    b: f32,
    acceptance: Option<f32>,
) -> Selection {
    let shaded = chosen
        .iter()
        .zip(importance)
        .map(|(v, &i)| ShadedVpl::new(v, scale / i))
        .collect();
    Selection {
        vpls: chosen,
        shaded,
        paths,
        acceptance,
        b: Some(b),
        ..Default::default()
    }
}

/// Total-variation distance between a set of paths' normalized importance last frame (`last`,
/// by key) and now (`vpls` with importance `raw`), over the paths present both frames; VPLs of
/// last frame that are gone (their paths got shorter) count with their whole mass. 0 when
/// `last` is empty (the first frame), exactly 0 when nothing changed.
pub fn tv_change(last: &HashMap<Key, f32>, vpls: &[Vpl], raw: &[f32]) -> f32 {
    if last.is_empty() {
        return 0.0;
    }
    let now_paths: HashSet<u64> = vpls.iter().map(|v| v.path).collect();
    let before_paths: HashSet<u64> = last.keys().map(|k| k.0).collect();
    let now: Vec<(Key, f64)> = vpls
        .iter()
        .zip(raw)
        .filter(|(v, _)| before_paths.contains(&v.path))
        .map(|(v, &i)| (key(v), i as f64))
        .collect();
    let before: HashMap<Key, f64> = last
        .iter()
        .filter(|(k, _)| now_paths.contains(&k.0))
        .map(|(&k, &i)| (k, i as f64))
        .collect();
    let (sn, sb) = (
        now.iter().map(|x| x.1).sum::<f64>(),
        before.values().sum::<f64>(),
    );
    if sn <= 0.0 || sb <= 0.0 {
        return if sn == sb { 0.0 } else { 1.0 };
    }
    let mut matched = 0.0f64;
    let mut d = 0.0f64;
    for (k, i) in &now {
        let b = before.get(k).copied().unwrap_or(0.0);
        matched += b;
        d += (i / sn - b / sb).abs();
    }
    // VPLs of last frame that are gone (their paths got shorter).
    d += (sb - matched).max(0.0) / sb;
    (0.5 * d).min(1.0) as f32
}

/// Fraction of slots whose key differs between two frames (1 when the counts differ).
pub fn replaced(before: &[Key], after: &[Key]) -> f32 {
    if before.len() != after.len() || after.is_empty() {
        return 1.0;
    }
    before.iter().zip(after).filter(|(a, b)| a != b).count() as f32 / after.len() as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// Whole paths only: a first path longer than the slots is cut to them instead of
    /// leaving no VPL at all (with one slot, every path of two or more bounces used to give
    /// an empty set, so the frame had no indirect light).
    #[test]
    fn a_path_longer_than_the_slots_still_fills_them() {
        let scene = builtin::load_any("cornell").unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        let mut long = 0;
        for stream in 0..20 {
            let (all, _) = fresh_paths(&f, &tr, 1, stream, 1000, true);
            let (one, _) = fresh_paths(&f, &tr, 1, stream, 1, true);
            assert_eq!(one.len(), 1, "stream {stream}");
            long += (all.iter().take_while(|v| v.path == all[0].path).count() > 1) as usize;
        }
        // The case the fix is for happened: some first paths had several VPLs.
        assert!(long > 0);
    }
}
