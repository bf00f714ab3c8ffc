//! `cdf`: N stratified inverse-transform draws from the CDF of I over the frame's M fresh
//! candidates, weight `b / (N I) * (M / P)`.

use super::common::{cdf_draw, weighted, Candidates};
use super::{SamplerKind, SamplerParams, Selection, VplSampler};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::Vpl;
use std::time::Instant;

pub struct Cdf {
    params: SamplerParams,
}

impl Cdf {
    pub fn new(params: &SamplerParams) -> Self {
        Cdf {
            params: params.clone(),
        }
    }
}

impl VplSampler for Cdf {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = &self.params;
        let t = Instant::now();
        let points = p.camera_points(frame, tracer);
        let c = Candidates::new(
            frame,
            tracer,
            &points,
            p.seed,
            f,
            p.candidates,
            p.knobs.eps(SamplerKind::Cdf),
            p.clamp,
        );
        if c.vpls.is_empty() {
            return Selection {
                paths: c.paths,
                importance_s: t.elapsed().as_secs_f64() - c.paths_s,
                ..Default::default()
            };
        }
        let mut r = rng(&[p.seed, f, 0x5a3b]);
        let idx = cdf_draw(&c.importance, p.slots, &mut r);
        let chosen: Vec<Vpl> = idx.iter().map(|&i| c.vpls[i]).collect();
        let imp: Vec<f32> = idx.iter().map(|&i| c.importance[i]).collect();
        let mut s = weighted(chosen, &imp, c.scale(p.slots), c.paths, c.b, None);
        s.importance_s = t.elapsed().as_secs_f64() - c.paths_s;
        s
    }
}
