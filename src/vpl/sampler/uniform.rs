//! `uniform` and `frozen`: Keller's instant radiosity, whole light paths until the slots are
//! full, each VPL weighted 1 / (paths used).

use super::common::fresh_paths;
use super::{SamplerParams, Selection, VplSampler};
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::ShadedVpl;

/// Fresh paths every frame (`frozen: false`) or the same paths every frame, re-traced in each
/// frame's scene (`frozen: true`).
pub struct Uniform {
    seed: u64,
    slots: usize,
    frozen: bool,
}

impl Uniform {
    pub fn new(p: &SamplerParams, frozen: bool) -> Self {
        Uniform {
            seed: p.seed,
            slots: p.slots,
            frozen,
        }
    }
}

impl VplSampler for Uniform {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let stream = if self.frozen { 0 } else { f };
        let (vpls, paths) = fresh_paths(frame, tracer, self.seed, stream, self.slots, true);
        let w = 1.0 / paths.max(1) as f32;
        Selection {
            shaded: vpls.iter().map(|v| ShadedVpl::new(v, w)).collect(),
            vpls,
            paths,
            ..Default::default()
        }
    }
}
