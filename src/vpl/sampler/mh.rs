//! `mh`: one Metropolis-Hastings chain per slot, one step a frame (see the module docs).
//!
//! The candidates (the proposals, and the normalization b) are the VPLs of one fixed set of
//! light paths, the same path ids in every frame, re-traced in each frame's scene: P is fixed
//! by the first frame (the paths that give at least M VPLs). So in a still scene b, M / P and
//! every kept chain's weight are bitwise the same from frame to frame, and under a moving
//! light or object they move only as the re-traced paths do. Given the candidate set, the
//! chains' stationary distribution is `I / sum I` over the candidates and the weight
//! `b / (N I) * (M / P) = sum I / (N P I)`, so the estimate's mean is the uniform estimate
//! of those P paths: unbiased over the seed, with no ratio bias from b.

use super::common::{cdf_draw, key, mh_accept, weighted, Candidates, Key, PATHS_PER_FRAME};
use super::{SamplerParams, Selection, VplSampler};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::importance::{camera_points, importance, CameraPoint};
use crate::vpl::{trace_path, Vpl};
use rand::Rng;
use std::collections::HashMap;
use std::time::Instant;

/// The stream of the candidates' paths (path ids `MH_STREAM * 2^32 + k`), apart from every
/// frame's fresh paths.
const MH_STREAM: u64 = (1 << 32) - 2;

pub struct Mh {
    params: SamplerParams,
    /// The VPL each chain is on, by key; empty before the first frame.
    chains: Vec<Key>,
    /// P: the number of candidate paths, fixed by the first frame with VPLs.
    paths: Option<u64>,
}

impl Mh {
    pub fn new(params: &SamplerParams) -> Self {
        Mh {
            params: params.clone(),
            chains: Vec::new(),
            paths: None,
        }
    }

    /// Each chain's VPL in this frame with its importance: the candidate with its key, else
    /// its path re-traced (None: the path no longer reaches that depth).
    fn current(
        &self,
        frame: &Frame,
        tracer: &Tracer,
        points: &[CameraPoint],
        c: &Candidates,
    ) -> Vec<Option<(Vpl, f32)>> {
        use rayon::prelude::*;
        let p = &self.params;
        let index: HashMap<Key, usize> = c
            .vpls
            .iter()
            .enumerate()
            .map(|(i, v)| (key(v), i))
            .collect();
        let floor = c.floor;
        self.chains
            .par_iter()
            .map(|&(path, depth)| {
                if let Some(&i) = index.get(&(path, depth)) {
                    return Some((c.vpls[i], c.importance[i]));
                }
                let v = trace_path(frame, tracer, p.seed, path)
                    .into_iter()
                    .find(|v| v.depth == depth)?;
                let i = importance(&v, points, tracer, p.dmin) + floor;
                Some((v, i))
            })
            .collect()
    }

    /// One step of every chain: propose a uniformly chosen candidate (with probability
    /// `mh_rate`), accept with min(1, I'/I), then escape a VPL no camera point sees.
    fn step(
        &self,
        current: Vec<Option<(Vpl, f32)>>,
        c: &Candidates,
        r: &mut impl Rng,
    ) -> (Vec<Vpl>, Vec<f32>, f32) {
        let p = &self.params;
        let n = current.len();
        let mut chosen = Vec::with_capacity(n);
        let mut imp = Vec::with_capacity(n);
        let (mut accepted, mut proposals) = (0usize, 0usize);
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
        (chosen, imp, accepted as f32 / proposals.max(1) as f32)
    }
}

impl VplSampler for Mh {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = self.params.clone();
        let t = Instant::now();
        let points = camera_points(frame, tracer, p.width, p.height, p.camera_points, p.seed);
        let c = match self.paths {
            Some(count) => Candidates::of_paths(
                frame,
                tracer,
                &points,
                p.seed,
                MH_STREAM * PATHS_PER_FRAME,
                count,
                p.eps,
                p.dmin,
            ),
            None => Candidates::new(
                frame,
                tracer,
                &points,
                p.seed,
                MH_STREAM,
                p.candidates,
                p.eps,
                p.dmin,
            ),
        };
        if c.vpls.is_empty() {
            self.chains.clear();
            self.paths = None;
            return Selection {
                paths: c.paths,
                importance_s: t.elapsed().as_secs_f64() - c.paths_s,
                ..Default::default()
            };
        }
        let n = p.slots;
        let mut r = rng(&[p.seed, f, 0x5a3b]);
        let (chosen, imp, acceptance) = if self.chains.len() == n {
            let current = self.current(frame, tracer, &points, &c);
            self.step(current, &c, &mut r)
        } else {
            // Chains start from a CDF draw.
            let idx = cdf_draw(&c.importance, n, &mut r);
            let chosen: Vec<Vpl> = idx.iter().map(|&i| c.vpls[i]).collect();
            let imp = idx.iter().map(|&i| c.importance[i]).collect();
            (chosen, imp, 1.0)
        };
        self.chains = chosen.iter().map(key).collect();
        self.paths = Some(c.paths);
        let mut s = weighted(chosen, &imp, c.scale(n), c.paths, c.b, Some(acceptance));
        s.importance_s = t.elapsed().as_secs_f64() - c.paths_s;
        s
    }
}
