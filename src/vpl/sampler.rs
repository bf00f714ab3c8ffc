//! Stage 6: samplers pick the frame's N VPLs (one per slot) and their weights. All draw from
//! the same light-path distribution p and share the importance I.
//!
//! - `uniform`: Keller's instant radiosity: fresh light paths until the slots are full, each
//!   VPL weighted 1 / (paths used).
//! - `cdf`: M fresh candidates a frame (the VPLs of P paths), N drawn by stratified inverse
//!   transform of the CDF of I, weight `b / (N I(v)) * (M / P)` with `b` the mean of I over
//!   the candidates. (M / P turns "one candidate" into "one path's share": the candidates of P
//!   paths sum, divided by P, to the uniform estimator.)
//! - `mh`: N independent Metropolis-Hastings chains, one per slot, one step a frame: re-trace
//!   the slot's path in the new frame, re-evaluate its I under the new camera, propose a
//!   uniformly chosen candidate of the frame (an independence proposal from p), accept with
//!   `min(1, I'/I)`; weight `b / (N I) * (M / P)`. Chains start from a CDF draw. Escape
//!   (`mh_escape` > 0): a chain whose VPL no camera point sees (I at the floor) makes up to
//!   that many more proposals in the frame and takes the first one some camera point sees.
//!   Without it, when the view changes abruptly (through a door), many chains land on hidden
//!   VPLs at once, where the proposals (mostly hidden too) keep them for frames, each with the
//!   floor's large weight, and ISM light leaks times that weight shows as bright flashes.
//!
//! I always includes the defensive floor `eps * mean(I over the candidates)`.

use super::importance::{camera_points, importance, importance_all, CameraPoint};
use super::{trace_path, ShadedVpl, Vpl};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use rand::Rng;
use serde::Serialize;
use std::time::Instant;

/// Which sampler picks the frame's VPLs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    /// Keller's instant radiosity: fresh light paths every frame
    Uniform,
    /// Importance by inverse transform of the CDF over fresh candidates
    Cdf,
    /// One Metropolis-Hastings chain per slot: VPLs stay until a better one is proposed
    Mh,
}

/// The sampler's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct SamplerParams {
    pub kind: SamplerKind,
    /// N: VPL slots.
    pub slots: usize,
    /// M: candidate VPLs a frame (cdf, mh).
    pub candidates: usize,
    /// K: camera points for importance.
    pub camera_points: usize,
    /// The defensive floor's factor.
    pub eps: f32,
    /// MH: probability that a chain proposes in a frame (1: one step a frame).
    pub mh_rate: f32,
    /// MH: extra proposals a frame for a chain whose VPL no camera point sees.
    pub mh_escape: u32,
    pub dmin: f32,
    pub seed: u64,
    /// The image the camera points stratify.
    pub width: u32,
    pub height: u32,
}

/// The frame's VPLs and what the run record says about them.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    pub vpls: Vec<Vpl>,
    pub shaded: Vec<ShadedVpl>,
    /// Light paths traced for this frame's fresh VPLs (candidates).
    pub paths: u64,
    /// Fraction of slots whose VPL changed since the last frame.
    pub replaced: f32,
    /// MH: fraction of this frame's proposals accepted.
    pub acceptance: Option<f32>,
    /// Mean floored importance over the candidates.
    pub b: Option<f32>,
    /// Seconds spent on camera points, importance (and, for mh, re-tracing the chains'
    /// paths) and the sampler's draws, without tracing the candidates' paths.
    pub importance_s: f64,
}

/// Path ids of frame f start at f * PATHS_PER_FRAME, so frames draw independent paths.
pub const PATHS_PER_FRAME: u64 = 1 << 32;

/// Identity of a VPL: (path id, depth). The path can be re-traced in any frame.
type Key = (u64, u32);

fn key(v: &Vpl) -> Key {
    (v.path, v.depth)
}

/// The VPLs of paths `frame * 2^32 + k`, k = 0, 1, ... Paths are added whole while `full`
/// says the set is not complete; returns the VPLs and the number of paths.
fn fresh_paths(
    frame: &Frame,
    tracer: &Tracer,
    seed: u64,
    frame_index: u64,
    target: usize,
    whole: bool,
) -> (Vec<Vpl>, u64) {
    let mut vpls = Vec::with_capacity(target + 16);
    let mut paths = 0u64;
    // Batches of paths in parallel, kept in path order.
    while vpls.len() < target && paths < 64 * target as u64 + 1024 {
        let batch = ((target - vpls.len()) / 2).clamp(1, 4096) as u64;
        let first = frame_index * PATHS_PER_FRAME + paths;
        let traced: Vec<Vec<Vpl>> = {
            use rayon::prelude::*;
            (first..first + batch)
                .into_par_iter()
                .map(|p| trace_path(frame, tracer, seed, p))
                .collect()
        };
        for p in traced {
            if vpls.len() >= target || (whole && vpls.len() + p.len() > target) {
                return (vpls, paths);
            }
            // A path that left no VPL (its light escaped) still counts as a path.
            vpls.extend(p);
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

/// A sampler with its state across frames.
pub struct Sampler {
    pub params: SamplerParams,
    /// The keys of the VPLs in the slots last frame.
    slots: Vec<Key>,
}

/// Candidates of a frame with their floored importance.
struct Candidates {
    vpls: Vec<Vpl>,
    importance: Vec<f32>,
    paths: u64,
    /// Seconds spent tracing the candidates' paths.
    paths_s: f64,
    /// eps * mean(I), added to every I.
    floor: f32,
    /// Mean floored importance.
    b: f32,
}

impl Sampler {
    pub fn new(params: SamplerParams) -> Self {
        Sampler {
            params,
            slots: Vec::new(),
        }
    }

    fn candidates(
        &self,
        frame: &Frame,
        tracer: &Tracer,
        f: u64,
        points: &[CameraPoint],
    ) -> Candidates {
        let p = &self.params;
        let t = Instant::now();
        let (vpls, paths) = fresh_paths(frame, tracer, p.seed, f, p.candidates, false);
        let paths_s = t.elapsed().as_secs_f64();
        let raw = importance_all(&vpls, points, tracer, p.dmin);
        let mean = raw.iter().map(|&x| x as f64).sum::<f64>() / raw.len().max(1) as f64;
        let floor = (p.eps as f64 * mean) as f32;
        Candidates {
            importance: raw.iter().map(|&x| x + floor).collect(),
            vpls,
            paths,
            paths_s,
            floor,
            b: (mean * (1.0 + p.eps as f64)) as f32,
        }
    }

    /// Picks frame `f`'s VPLs.
    pub fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = self.params.clone();
        if p.kind == SamplerKind::Uniform {
            let (vpls, paths) = fresh_paths(frame, tracer, p.seed, f, p.slots, true);
            let w = 1.0 / paths.max(1) as f32;
            let keys: Vec<Key> = vpls.iter().map(key).collect();
            let replaced = self.replaced(&keys);
            self.slots = keys;
            return Selection {
                shaded: vpls.iter().map(|v| ShadedVpl::new(v, w)).collect(),
                vpls,
                paths,
                replaced,
                ..Default::default()
            };
        }
        let t = Instant::now();
        let points = camera_points(frame, tracer, p.width, p.height, p.camera_points, p.seed);
        let c = self.candidates(frame, tracer, f, &points);
        if c.vpls.is_empty() {
            self.slots.clear();
            return Selection {
                paths: c.paths,
                replaced: 1.0,
                importance_s: t.elapsed().as_secs_f64() - c.paths_s,
                ..Default::default()
            };
        }
        let n = p.slots;
        let scale = c.b / n as f32 * (c.vpls.len() as f32 / c.paths.max(1) as f32);
        let mut r = rng(&[p.seed, f, 0x5a3b]);
        let (chosen, imp, acceptance) = if p.kind == SamplerKind::Mh && self.slots.len() == n {
            let mut chosen = Vec::with_capacity(n);
            let mut imp = Vec::with_capacity(n);
            let mut accepted = 0usize;
            // Re-trace each slot's path and re-evaluate its importance in this frame.
            let current: Vec<Option<(Vpl, f32)>> = {
                use rayon::prelude::*;
                self.slots
                    .par_iter()
                    .map(|&(path, depth)| {
                        let v = trace_path(frame, tracer, p.seed, path)
                            .into_iter()
                            .find(|v| v.depth == depth)?;
                        let i = importance(&v, &points, tracer, p.dmin) + c.floor;
                        Some((v, i))
                    })
                    .collect()
            };
            let mut proposals = 0usize;
            for cur in current {
                let j = r.random_range(0..c.vpls.len());
                let u: f32 = r.random();
                let propose = r.random::<f32>() < p.mh_rate || cur.is_none();
                proposals += propose as usize;
                let (mut v, mut i) = match cur {
                    Some((v, i)) if !propose || !mh_accept(i, c.importance[j], u) => (v, i),
                    _ => {
                        accepted += 1;
                        (c.vpls[j], c.importance[j])
                    }
                };
                // Escape: a chain on a VPL no camera point sees (I at the floor) tries up to
                // `mh_escape` more proposals this frame and takes the first that is seen.
                if i <= c.floor {
                    for _ in 0..p.mh_escape {
                        let k = r.random_range(0..c.vpls.len());
                        if c.importance[k] > c.floor {
                            (v, i) = (c.vpls[k], c.importance[k]);
                            break;
                        }
                    }
                }
                chosen.push(v);
                imp.push(i);
            }
            (chosen, imp, Some(accepted as f32 / proposals.max(1) as f32))
        } else {
            let idx = cdf_draw(&c.importance, n, &mut r);
            let chosen: Vec<Vpl> = idx.iter().map(|&i| c.vpls[i]).collect();
            let imp = idx.iter().map(|&i| c.importance[i]).collect();
            (
                chosen,
                imp,
                if p.kind == SamplerKind::Mh {
                    Some(1.0)
                } else {
                    None
                },
            )
        };
        let shaded = chosen
            .iter()
            .zip(&imp)
            .map(|(v, &i)| ShadedVpl::new(v, scale / i))
            .collect();
        let keys: Vec<Key> = chosen.iter().map(key).collect();
        let replaced = self.replaced(&keys);
        self.slots = keys;
        Selection {
            vpls: chosen,
            shaded,
            paths: c.paths,
            replaced,
            acceptance,
            b: Some(c.b),
            importance_s: t.elapsed().as_secs_f64() - c.paths_s,
        }
    }

    fn replaced(&self, keys: &[Key]) -> f32 {
        if self.slots.len() != keys.len() || keys.is_empty() {
            return 1.0;
        }
        self.slots.iter().zip(keys).filter(|(a, b)| a != b).count() as f32 / keys.len() as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chi-square statistic of observed counts against expected probabilities.
    fn chi2(counts: &[u64], probs: &[f64]) -> f64 {
        let n: u64 = counts.iter().sum();
        counts
            .iter()
            .zip(probs)
            .map(|(&c, &p)| (c as f64 - n as f64 * p).powi(2) / (n as f64 * p))
            .sum()
    }

    // 99.9% quantile of chi-square with 5 degrees of freedom.
    const CHI2_5_999: f64 = 20.52;

    const P: [f64; 6] = [0.3, 0.25, 0.2, 0.1, 0.1, 0.05];
    const I: [f32; 6] = [0.5, 2.0, 1.0, 4.0, 0.25, 3.0];

    fn target() -> Vec<f64> {
        let z: f64 = P.iter().zip(I).map(|(p, i)| p * i as f64).sum();
        P.iter().zip(I).map(|(p, i)| p * i as f64 / z).collect()
    }

    fn draw_p(r: &mut impl Rng) -> usize {
        let u: f64 = r.random();
        let mut acc = 0.0;
        for (i, p) in P.iter().enumerate() {
            acc += p;
            if u < acc {
                return i;
            }
        }
        P.len() - 1
    }

    /// Final states of 20000 independent chains from state 0 after 40 steps (burn-in), each
    /// step proposing from p and moving when `accept(current, proposal, u)` says so.
    fn final_states(stream: u64, accept: impl Fn(usize, usize, f32) -> bool) -> [u64; 6] {
        let mut counts = [0u64; 6];
        for c in 0..20_000u64 {
            let mut r = rng(&[c, stream]);
            let mut s = 0usize;
            for _ in 0..40 {
                let j = draw_p(&mut r);
                if accept(s, j, r.random()) {
                    s = j;
                }
            }
            counts[s] += 1;
        }
        counts
    }

    #[test]
    fn mh_chains_visit_states_in_proportion_to_i_times_p() {
        let counts = final_states(77, |cur, prop, u| mh_accept(I[cur], I[prop], u));
        let x = chi2(&counts, &target());
        assert!(
            x < CHI2_5_999,
            "chi-square {x}: counts {counts:?} against {:?}",
            target()
        );
        // A wrong acceptance (min(1, I/I') instead of min(1, I'/I)) fails the same test.
        let wrong = final_states(78, |cur, prop, u| mh_accept(I[prop], I[cur], u));
        assert!(chi2(&wrong, &target()) > 100.0);
    }

    #[test]
    fn cdf_draws_match_i_times_p() {
        // Candidates drawn from p (M = 2000), then N = 64 stratified CDF draws, repeated.
        let mut counts = [0u64; 6];
        for rep in 0..400u64 {
            let mut r = rng(&[rep, 99]);
            let cands: Vec<usize> = (0..2000).map(|_| draw_p(&mut r)).collect();
            let w: Vec<f32> = cands.iter().map(|&c| I[c]).collect();
            for i in cdf_draw(&w, 64, &mut r) {
                counts[cands[i]] += 1;
            }
        }
        let x = chi2(&counts, &target());
        assert!(
            x < CHI2_5_999,
            "chi-square {x}: counts {counts:?} against {:?}",
            target()
        );
    }
}
