//! `rejection`: Georgiev and Slusallek's (2010) importance by rejection. Fresh light paths as
//! for `uniform`; each of their VPLs is kept with probability `p = min(1, I / I_target + eps)`
//! and weighted `1 / (p P)` (P: paths traced), until the slots are full. No normalization
//! constant: `I_target` (the mean importance of a pilot set of fresh VPLs, traced from their
//! own path stream) only sets how many VPLs are kept; any positive value gives the same
//! expected image.

use super::common::{fresh_paths, PATHS_PER_FRAME};
use super::{SamplerKind, SamplerParams, Selection, VplSampler};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::importance::{importance, importance_all};
use crate::vpl::{trace_path, ShadedVpl, Vpl};
use rand::Rng;
use std::time::Instant;

/// Pilot paths of frame f use stream `PILOT + f`, apart from every frame's fresh paths.
const PILOT: u64 = 1 << 31;

pub struct Rejection {
    params: SamplerParams,
}

impl Rejection {
    pub fn new(params: &SamplerParams) -> Self {
        Rejection {
            params: params.clone(),
        }
    }
}

/// The probability of keeping a VPL of importance `i`.
pub fn keep_probability(i: f32, target: f32, eps: f32) -> f32 {
    if target > 0.0 {
        (i / target + eps).min(1.0)
    } else {
        1.0
    }
}

impl VplSampler for Rejection {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = &self.params;
        let t = Instant::now();
        let points = p.camera_points(frame, tracer);
        let (pilot, _) = fresh_paths(frame, tracer, p.seed, PILOT + f, p.slots, false);
        let pi = importance_all(&pilot, &points, tracer, p.clamp);
        let target = (pi.iter().map(|&x| x as f64).sum::<f64>() / pi.len().max(1) as f64) as f32;
        let n = p.slots;
        let mut kept: Vec<(Vpl, f32)> = Vec::with_capacity(n);
        let mut paths = 0u64;
        let mut traced = 0.0f64;
        'fill: while kept.len() < n && paths < 64 * n as u64 + 1024 {
            let batch = ((n - kept.len()) / 2).clamp(1, 4096) as u64;
            let first = f * PATHS_PER_FRAME + paths;
            let t0 = Instant::now();
            let batch_kept: Vec<Vec<(Vpl, f32)>> = {
                use rayon::prelude::*;
                (first..first + batch)
                    .into_par_iter()
                    .map(|id| {
                        trace_path(frame, tracer, p.seed, id)
                            .into_iter()
                            .filter_map(|v| {
                                let i = importance(&v, &points, tracer, p.clamp);
                                let q = keep_probability(
                                    i,
                                    target,
                                    p.knobs.eps(SamplerKind::Rejection),
                                );
                                let u: f32 = rng(&[p.seed, id, v.depth as u64, 0x4e7]).random();
                                (u < q).then_some((v, q))
                            })
                            .collect()
                    })
                    .collect()
            };
            traced += t0.elapsed().as_secs_f64();
            for k in batch_kept {
                if kept.len() >= n || kept.len() + k.len() > n {
                    break 'fill;
                }
                kept.extend(k);
                paths += 1;
            }
        }
        let w = 1.0 / paths.max(1) as f32;
        // The batches (paths and their importance) count as path tracing.
        Selection {
            shaded: kept.iter().map(|(v, q)| ShadedVpl::new(v, w / q)).collect(),
            vpls: kept.iter().map(|(v, _)| *v).collect(),
            paths,
            b: Some(target),
            importance_s: t.elapsed().as_secs_f64() - traced,
            ..Default::default()
        }
    }
}
