//! `mh`: one Metropolis-Hastings chain per slot, at most one step a frame (see the module
//! docs).
//!
//! What a kept chain's weight `b / (N I) * (M / P)` may change with, and what it does not:
//! - `I`, its importance over the camera points, changes only as its VPL or the view moves
//!   (the camera points' jitter is the same every frame).
//! - `b` and `M / P` come from a *normalization pool*: M candidates whose light paths are
//!   re-traced in each frame's scene and each re-drawn only every `1 / mh_rate` frames, at its
//!   own phase, so a fraction `mh_rate` of the pool is new each frame, the rate at which the
//!   chains themselves renew in a still scene. Estimated from each frame's fresh candidates, b
//!   jumped 1-7% a frame and scaled every kept VPL with it; from the pool it moves by about
//!   `sqrt(2 mh_rate)` of that, and over time every pool path is replaced, so its error
//!   averages out (a pool that never renewed would keep one draw's error for good). A pool
//!   of more than [`POOL_PAIRS`] / K candidates (K camera points; 1024 at the default 256)
//!   sums each candidate's importance over the camera points of every s-th stratum only, s
//!   odd and about M K / POOL_PAIRS, times s, from an offset of the candidate's own
//!   ([`pool_stride`], `importance_sampled`): an unbiased estimate of its I, so b stays
//!   unbiased, for a fixed number of shadow rays a frame. At 4096 VPLs (a pool of 16384)
//!   the full sums took 178 ms of a 364 ms frame on 2 cores, to estimate one scalar. Chains
//!   and proposals keep the full sum, and so does the pool of the chains' first frame,
//!   which they are drawn from (its sampled sums are kept for the next frame's change).
//! - Proposals come from the frame's fresh candidates (an independence proposal from p, as
//!   before), so over time the chains still explore every path; only the proposed candidates'
//!   importance is evaluated.
//! - The rate at which chains propose follows the scene: `min(1, mh_rate + mh_follow * d)`,
//!   with `d` the total-variation distance between this frame's and the last frame's target
//!   over the pool's paths that were in it both frames (the fraction of the target's mass that
//!   moved). A still scene gives `d = 0` and chains propose at the base rate; a moving light or
//!   view raises the rate so chains follow it. `d` depends on the pool only, never on the
//!   chains' states, so each frame's step is a lazy MH kernel that keeps that frame's target.

use super::common::{cdf_draw, key, mh_accept, tv_change, weighted, Candidates, Key};
use super::{SamplerKind, SamplerParams, Selection, VplSampler};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::importance::{importance, importance_all_sampled, CameraPoint};
use crate::vpl::sampler::common::{fresh_paths, paths_by, PATHS_PER_FRAME};
use crate::vpl::{trace_path, Vpl};
use rand::Rng;
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

/// The id of the normalization pool's k-th path in frame `f`: re-drawn every `1 / rate`
/// frames (rounded), at a phase of its own. Its stream, `2^31 + generation`, is above every
/// frame's fresh stream (frames use streams 0, 1, ...).
pub fn pool_path(seed: u64, k: u64, f: u64, rate: f32) -> u64 {
    let period = (1.0 / rate.max(1e-9) as f64).round().clamp(1.0, 1e9) as u64;
    let phase = crate::math::stream_seed(&[seed, k, 0x9001]) % period;
    ((1 << 31) + (f + phase) / period) * PATHS_PER_FRAME + k
}

/// Candidate-point pairs of the normalization pool's importance a frame: the pool of the
/// default 256 VPLs (1024 candidates) at the default 256 camera points, summed in full.
pub const POOL_PAIRS: usize = 1024 * 256;

/// The stride of the camera points a pool of `m` candidates sums its importance over, with
/// `k` camera points: 1 up to [`POOL_PAIRS`] pairs, else `ceil(m k / POOL_PAIRS)` made odd.
pub fn pool_stride(m: usize, k: usize) -> usize {
    let s = (m * k).div_ceil(POOL_PAIRS).max(1);
    if s > 1 && s.is_multiple_of(2) {
        s + 1
    } else {
        s
    }
}

pub struct Mh {
    params: SamplerParams,
    /// The VPL each chain is on, by key; empty before the first frame.
    chains: Vec<Key>,
    /// The pool's importance (without the floor, which moves as the pool renews) last frame,
    /// by key.
    last_pool: HashMap<Key, f32>,
}

/// One chain's random numbers for a frame, drawn before any importance is known so that the
/// stream does not depend on outcomes.
/// What a step of the chains gives: their VPLs and importance, the acceptance rate, the fresh
/// paths traced and the seconds they took.
struct Stepped {
    chosen: Vec<Vpl>,
    imp: Vec<f32>,
    acceptance: f32,
    fresh_paths: u64,
    paths_s: f64,
}

struct Draws {
    propose: bool,
    /// The proposal, as a fraction of the fresh candidates.
    j: f64,
    u: f32,
    /// Escape proposals, as fractions of the fresh candidates.
    escape: Vec<f64>,
}

impl Mh {
    pub fn new(params: &SamplerParams) -> Self {
        Mh {
            params: params.clone(),
            chains: Vec::new(),
            last_pool: HashMap::new(),
        }
    }

    /// Each chain's VPL re-traced in this frame with its floored importance (None: its path no
    /// longer reaches that depth).
    fn current(
        &self,
        frame: &Frame,
        tracer: &Tracer,
        points: &[CameraPoint],
        floor: f32,
    ) -> Vec<Option<(Vpl, f32)>> {
        let p = &self.params;
        self.chains
            .par_iter()
            .map(|&(path, depth)| {
                let v = trace_path(frame, tracer, p.seed, path)
                    .into_iter()
                    .find(|v| v.depth == depth)?;
                let i = importance(&v, points, tracer, p.clamp) + floor;
                Some((v, i))
            })
            .collect()
    }

    /// Total-variation distance between the pool's normalized target last frame and now, over
    /// the paths that were in the pool both frames (0 on the first frame).
    fn change(&self, pool: &Candidates) -> f32 {
        tv_change(&self.last_pool, &pool.vpls, &pool.raw)
    }

    /// One step of every chain: re-evaluated current states, proposals from fresh candidates
    /// accepted by the MH rule, and escapes of chains on hidden VPLs.
    #[allow(clippy::too_many_arguments)]
    fn step(
        &self,
        frame: &Frame,
        tracer: &Tracer,
        points: &[CameraPoint],
        pool: &Candidates,
        p: &SamplerParams,
        (f, rate): (u64, f32),
        r: &mut rand_pcg::Pcg32,
    ) -> Stepped {
        let n = p.slots;
        let current = self.current(frame, tracer, points, pool.floor);
        let draws: Vec<Draws> = current
            .iter()
            .map(|cur| Draws {
                j: r.random(),
                u: r.random(),
                propose: r.random::<f32>() < rate || cur.is_none(),
                escape: (0..p.knobs.mh_escape).map(|_| r.random()).collect(),
            })
            .collect();
        // Fresh candidates only when some chain proposes or may escape.
        let wanted = draws.iter().zip(&current).any(|(d, c)| {
            d.propose || (p.knobs.mh_escape > 0 && c.is_some_and(|(_, i)| i <= pool.floor))
        });
        let t_paths = Instant::now();
        let (fresh, fresh_paths_n) = if wanted {
            fresh_paths(frame, tracer, p.seed, f, p.candidates, false)
        } else {
            (Vec::new(), 0)
        };
        let paths_s = t_paths.elapsed().as_secs_f64();
        let pick = |x: f64| ((x * fresh.len() as f64) as usize).min(fresh.len() - 1);
        let mut memo = vec![None; fresh.len()];
        let step = Step {
            fresh: &fresh,
            points,
            tracer,
            clamp: p.clamp,
            floor: pool.floor,
        };
        if !fresh.is_empty() {
            step.eval(
                &mut memo,
                draws.iter().filter(|d| d.propose).map(|d| pick(d.j)),
            );
        }
        // Accept or keep.
        let (mut accepted, mut proposals) = (0usize, 0usize);
        let mut state: Vec<Option<(Vpl, f32)>> = current
            .into_iter()
            .zip(&draws)
            .map(|(cur, d)| {
                if !d.propose || fresh.is_empty() {
                    return cur;
                }
                proposals += 1;
                let j = pick(d.j);
                let ij = memo[j].expect("evaluated above");
                match cur {
                    Some((v, i)) if !mh_accept(i, ij, d.u) => Some((v, i)),
                    _ => {
                        accepted += 1;
                        Some((fresh[j], ij))
                    }
                }
            })
            .collect();
        // Escape: a chain on a VPL no camera point sees (I at the floor) takes the first
        // of its escape proposals that some camera point sees.
        let hidden = |s: &Option<(Vpl, f32)>| s.is_none_or(|(_, i)| i <= pool.floor);
        if !fresh.is_empty() && p.knobs.mh_escape > 0 {
            let escaping = state.iter().zip(&draws).filter(|(s, _)| hidden(s));
            step.eval(
                &mut memo,
                escaping.flat_map(|(_, d)| d.escape.iter().map(|&x| pick(x))),
            );
            for (s, d) in state.iter_mut().zip(&draws) {
                if hidden(s) {
                    let seen = d
                        .escape
                        .iter()
                        .map(|&x| pick(x))
                        .find(|&k| memo[k].expect("evaluated above") > pool.floor);
                    if let Some(k) = seen {
                        *s = Some((fresh[k], memo[k].expect("evaluated above")));
                    }
                }
            }
        }
        let (mut chosen, mut imp) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (v, i) in state.into_iter().flatten() {
            chosen.push(v);
            imp.push(i);
        }
        Stepped {
            chosen,
            imp,
            acceptance: accepted as f32 / proposals.max(1) as f32,
            fresh_paths: fresh_paths_n,
            paths_s,
        }
    }
}

impl VplSampler for Mh {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = self.params.clone();
        let t = Instant::now();
        let points = p.camera_points(frame, tracer);
        let t_pool = Instant::now();
        let (vpls, paths) = paths_by(
            frame,
            tracer,
            p.seed,
            |k| pool_path(p.seed, k, f, p.knobs.mh_rate),
            p.candidates,
            false,
        );
        let paths_s = t_pool.elapsed().as_secs_f64();
        // The chains' first frame (or a restart) draws them from the pool: with the full sums,
        // so that they start on their target.
        let first = self.chains.len() != p.slots;
        let stride = pool_stride(p.candidates, points.len());
        let pool = Candidates::sampled(
            vpls,
            (paths, paths_s),
            tracer,
            (&points, if first { 1 } else { stride }),
            p.knobs.eps(SamplerKind::Mh),
            p.clamp,
        );
        let mut paths_s = pool.paths_s;
        if pool.vpls.is_empty() {
            self.chains.clear();
            self.last_pool.clear();
            return Selection {
                paths: pool.paths,
                importance_s: t.elapsed().as_secs_f64() - paths_s,
                ..Default::default()
            };
        }
        let rate = (p.knobs.mh_rate + p.knobs.mh_follow * self.change(&pool)).min(1.0);
        // The next frame's change compares sums of the same kind: sampled ones, also after a
        // first frame of full sums (a stride's worth of them more, once).
        let sampled;
        let raw = if first && stride > 1 {
            sampled = importance_all_sampled(&pool.vpls, &points, tracer, p.clamp, stride);
            &sampled
        } else {
            &pool.raw
        };
        self.last_pool = pool
            .vpls
            .iter()
            .zip(raw)
            .map(|(v, &i)| (key(v), i))
            .collect();
        let n = p.slots;
        let mut r = rng(&[p.seed, f, 0x5a3b]);
        let (chosen, imp, acceptance, fresh_paths_n) = if first {
            // Chains start from a CDF draw over the pool.
            let idx = cdf_draw(&pool.importance, n, &mut r);
            let chosen: Vec<Vpl> = idx.iter().map(|&i| pool.vpls[i]).collect();
            let imp = idx.iter().map(|&i| pool.importance[i]).collect();
            (chosen, imp, 1.0, 0)
        } else {
            let st = self.step(frame, tracer, &points, &pool, &p, (f, rate), &mut r);
            paths_s += st.paths_s;
            (st.chosen, st.imp, st.acceptance, st.fresh_paths)
        };
        self.chains = chosen.iter().map(key).collect();
        let traced = pool.paths + fresh_paths_n;
        let mut s = weighted(
            chosen,
            &imp,
            pool.scale(n),
            traced,
            pool.b,
            Some(acceptance),
        );
        s.renewal_rate = Some(rate);
        s.importance_s = t.elapsed().as_secs_f64() - paths_s;
        s
    }
}

/// What evaluating fresh candidates needs.
struct Step<'a> {
    fresh: &'a [Vpl],
    points: &'a [CameraPoint],
    tracer: &'a Tracer,
    clamp: f32,
    floor: f32,
}

impl Step<'_> {
    /// Floored importance of the fresh candidates at `idx`, each evaluated once.
    fn eval(&self, memo: &mut [Option<f32>], idx: impl Iterator<Item = usize>) {
        let mut need: Vec<usize> = idx.filter(|&j| memo[j].is_none()).collect();
        need.sort_unstable();
        need.dedup();
        let got: Vec<f32> = need
            .par_iter()
            .map(|&j| importance(&self.fresh[j], self.points, self.tracer, self.clamp) + self.floor)
            .collect();
        for (j, i) in need.into_iter().zip(got) {
            memo[j] = Some(i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default pool (256 VPLs: 1024 candidates, 256 camera points) sums in full, so the
    /// figures measured at 256 VPLs are those of the full sums; larger pools keep their pairs
    /// near POOL_PAIRS with an odd stride.
    #[test]
    fn the_default_pool_sums_in_full_and_larger_ones_near_the_budget() {
        assert_eq!(pool_stride(1024, 256), 1);
        assert_eq!(pool_stride(512, 256), 1);
        assert_eq!(pool_stride(4096, 256), 5);
        assert_eq!(pool_stride(16384, 256), 17);
        assert_eq!(pool_stride(2048, 256), 3);
        for m in [1025, 3000, 9999, 65536] {
            let s = pool_stride(m, 256);
            assert!(
                !s.is_multiple_of(2) && m * 256 / s <= POOL_PAIRS,
                "m {m}: stride {s}"
            );
        }
    }
}
