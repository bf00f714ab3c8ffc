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
//! - `frozen`: `uniform` with the same light paths (path ids, so the same random numbers)
//!   every frame, re-traced in each frame's scene: VPLs slide with moving lights and objects
//!   and stay put in a still scene (what offline VPL renderers do for animations).
//! - `rejection`: Georgiev and Slusallek's (2010) importance by rejection: fresh paths as for
//!   `uniform`, each VPL kept with probability `p = min(1, I / I_target + eps)` and weighted
//!   `1 / (p P)`, no normalization constant (`I_target`: mean I of a pilot set of paths).
//! - `smc`: sequential Monte Carlo (after Hedman et al. 2016): one particle per slot, drawn as
//!   cdf draws it and kept with the weight of that draw; each frame every particle re-traces
//!   its own path in the new scene (through its Russian-roulette coins, weighted by their
//!   probabilities now over then), and a fraction `smc_rate` of the slots, chosen at random,
//!   take newborn particles. Lagging behind a moving target costs it variance, not bias.
//! - `rmsmc`: resample-move SMC (Gilks and Berzuini 2001) on smc's particles: each particle's
//!   SMC weight follows the ratio of the new target to the old at its re-traced path, the
//!   particles are resampled when their effective sample size falls below `rmsmc_ess` N, and
//!   Metropolis-Hastings moves (independence proposals from p) rejuvenate them at a rate that
//!   follows how far a fixed probe's importance moved (0 where nothing moved: frozen's VPLs).
//!
//! For cdf, mh and smc, I includes the defensive floor `eps * mean(I over the candidates)`.

mod cdf;
mod common;
pub mod knobs;
mod mh;
mod rejection;
mod rmsmc;
mod settings;
mod smc;
mod uniform;

pub use common::{cdf_draw, mh_accept, NEAR_SLOTS, PATHS_PER_FRAME};
pub use rmsmc::{assign as rmsmc_assign, ess as rmsmc_ess};
pub use settings::SamplerConfig;
pub use smc::spread as smc_spread;

use super::{ShadedVpl, Vpl};
use crate::scene::Frame;
use crate::trace::Tracer;
use serde::Serialize;

/// Which sampler picks the frame's VPLs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    /// Keller's instant radiosity: fresh light paths every frame
    Uniform,
    /// Importance by inverse transform of the CDF over fresh candidates
    Cdf,
    /// One Metropolis-Hastings chain per slot: VPLs stay until a better one is proposed
    Mh,
    /// Keller's instant radiosity with the same light paths every frame, re-traced in each
    /// frame's scene
    Frozen,
    /// Importance by rejection (Georgiev and Slusallek 2010): keep a fresh VPL with
    /// probability min(1, I / I_target + eps), weight 1 / p
    Rejection,
    /// Sequential Monte Carlo: particles drawn as cdf draws them keep their paths (re-traced
    /// in each frame's scene) and their weights; --smc-rate of the slots renew a frame
    Smc,
    /// Resample-move SMC: smc's particles with weights updated by the target's ratio, resampled
    /// when their effective sample size falls, rejuvenated by Metropolis-Hastings moves
    Rmsmc,
}

impl SamplerKind {
    /// Every sampler, in the order the help lists them.
    pub const ALL: [SamplerKind; 7] = [
        SamplerKind::Uniform,
        SamplerKind::Cdf,
        SamplerKind::Mh,
        SamplerKind::Frozen,
        SamplerKind::Rejection,
        SamplerKind::Smc,
        SamplerKind::Rmsmc,
    ];

    /// The name the settings and the CLI spell (`uniform`, `cdf`, `mh`, ...).
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Uniform => "uniform",
            SamplerKind::Cdf => "cdf",
            SamplerKind::Mh => "mh",
            SamplerKind::Frozen => "frozen",
            SamplerKind::Rejection => "rejection",
            SamplerKind::Smc => "smc",
            SamplerKind::Rmsmc => "rmsmc",
        }
    }

    /// The sampler named `name` (any case).
    pub fn parse(name: &str) -> Option<SamplerKind> {
        Self::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(name))
    }
}

impl std::fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The sampler's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct SamplerParams {
    pub kind: SamplerKind,
    /// N: VPL slots.
    pub slots: usize,
    /// M: candidate VPLs a frame (cdf, mh, smc), from `--candidates` or the slots.
    pub candidates: usize,
    /// The knobs (`candidates` above is M resolved from theirs).
    pub knobs: knobs::SamplerKnobs,
    pub clamp: f32,
    pub seed: u64,
    /// The image the camera points stratify.
    pub width: u32,
    pub height: u32,
}

impl SamplerParams {
    /// The frame's camera points for importance: `--camera-points` of them over the image.
    pub fn camera_points(
        &self,
        frame: &Frame,
        tracer: &Tracer,
    ) -> Vec<crate::vpl::importance::CameraPoint> {
        crate::vpl::importance::camera_points(
            frame,
            tracer,
            self.width,
            self.height,
            self.knobs.camera_points as usize,
            self.seed,
        )
    }
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
    /// MH: the probability that a chain proposed this frame (the base rate raised by how far
    /// the target moved); SMC: the probability that a slot renewed (the mean of its halves').
    pub renewal_rate: Option<f32>,
    /// Mean floored importance over the candidates.
    pub b: Option<f32>,
    /// Seconds spent on camera points, importance (and, for mh, re-tracing the chains'
    /// paths) and the sampler's draws, without tracing the candidates' paths.
    pub importance_s: f64,
}

/// One sampler's policy and its state across frames.
pub trait VplSampler: Send {
    /// Picks frame `f`'s VPLs (`replaced` is left for [`Sampler`] to fill in).
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection;
}

/// The sampler that `params.kind` names, and the slots it filled last frame.
pub struct Sampler {
    pub params: SamplerParams,
    inner: Box<dyn VplSampler>,
    /// The keys of the VPLs in the slots last frame.
    slots: Vec<common::Key>,
}

impl Sampler {
    pub fn new(params: SamplerParams) -> Self {
        let inner: Box<dyn VplSampler> = match params.kind {
            SamplerKind::Uniform => Box::new(uniform::Uniform::new(&params, false)),
            SamplerKind::Cdf => Box::new(cdf::Cdf::new(&params)),
            SamplerKind::Mh => Box::new(mh::Mh::new(&params)),
            SamplerKind::Frozen => Box::new(uniform::Uniform::new(&params, true)),
            SamplerKind::Rejection => Box::new(rejection::Rejection::new(&params)),
            SamplerKind::Smc => Box::new(smc::Smc::new(&params)),
            SamplerKind::Rmsmc => Box::new(rmsmc::Rmsmc::new(&params)),
        };
        Sampler {
            params,
            inner,
            slots: Vec::new(),
        }
    }

    /// Picks frame `f`'s VPLs.
    pub fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let mut s = self.inner.select(frame, tracer, f);
        let keys: Vec<common::Key> = s.vpls.iter().map(common::key).collect();
        s.replaced = common::replaced(&self.slots, &keys);
        self.slots = keys;
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng;
    use rand::Rng;

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
