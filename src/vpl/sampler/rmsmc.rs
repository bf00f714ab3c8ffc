//! `rmsmc`: resample-move sequential Monte Carlo over the frames (Gilks and Berzuini 2001; the
//! particles are smc's, after Hedman et al. 2016). N particles, one per slot, each a light path
//! (its id, so its random numbers), a vertex coin `xi` and a primary-space weight `W`. Frame f's
//! target over paths is `pi_f(u) ∝ p(u) T_f(u)` with
//! `T_f(u) = sum_d (I_f(v_d) + phi_f) + phi_f` (its vertices' floored importance plus one floor
//! more, as smc's births), and particle i's SMC weight is `omega_i = W_i T_f(u_i)`.
//!
//! Each frame:
//! 1. *Reweight.* Every particle re-traces its path in the frame's scene and evaluates `T_f`.
//!    Keeping `W` is updating `omega` by the target's ratio `T_f(u) / T_{f-1}(u)` at the
//!    re-traced path (docs/math.md, section 7, "rmsmc").
//! 2. *Resample* when the effective sample size `(sum omega)^2 / sum omega^2` falls below
//!    `rmsmc_ess * N`: N stratified draws in proportion to `omega`, each copy weighted
//!    `W = sum omega / (N T_f(u))` (so `sum omega` is kept). Survivors stay in their slots,
//!    extra copies fill the slots of the dropped particles and get coins of their own.
//! 3. *Move.* Each slot, by a random number of its own, with probability
//!    `r_f = min(1, rmsmc_rate + rmsmc_follow * d_f)` proposes a fresh path of the frame (an
//!    independence proposal from p) and takes it with probability `min(1, T_f(u') / T_f(u))`, a
//!    Metropolis-Hastings step that keeps `pi_f`; `omega` stays, so `W = omega / T_f(u')`.
//!    `d_f` is the total-variation distance between the last frame's and this frame's
//!    importance over a *probe*: M candidates' paths re-traced every frame (the same paths at
//!    rate 0; at a rate r > 0 a fraction r of them renew a frame, as mh's pool), which the
//!    particles never touch, so the rate does not depend on any particle's state.
//! 4. *Scale.* The weights are scaled so that the particles' omega sum to the probe's estimate
//!    of `Z_f = E_p[T_f]` (self-normalized): a sum of omega carried from frame to frame is a
//!    product of one ratio estimate a frame and drifts as the target moves.
//! 5. *Light.* The particle's vertex `d` is picked by `xi` in proportion to `I_f(v_d) + phi_f` and
//!    weighted `W / P_f(d)`.
//!
//! `phi_f` is `eps` times the probe's mean importance. Where nothing moved, the probe's
//! importance is bit for bit the last frame's, so `d_f = 0`, `phi_f` and every `T_f(u_i)` are
//! unchanged, the effective sample size is the one left last frame (at least `rmsmc_ess * N`),
//! nothing is resampled and (at `rmsmc_rate` 0) nothing moves: every VPL and weight is the last
//! frame's, as frozen's.

use super::common::{cdf_draw, key, paths_by, tv_change, Key, PATHS_PER_FRAME};
use super::mh::pool_path;
use super::smc::{newborns, pick_vertex, vertices};
use super::{SamplerKind, SamplerParams, Selection, VplSampler};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::importance::importance_all;
use crate::vpl::{ShadedVpl, Vpl};
use glam::Vec3;
use rand::Rng;
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

/// The probe's stream at `rmsmc_rate` 0: its paths `PROBE_STREAM * 2^32 + k` are the same every
/// frame (frames use streams 0, 1, ..., mh's pool 2^31 and up). At a rate r > 0 the probe is
/// mh's normalization pool (`pool_path`): a fraction r of its paths renew a frame, so that the
/// error of its estimate of the target's scale averages out over time as the particles move.
const PROBE_STREAM: u64 = (1 << 31) - 1;

/// Proposals of frame f are paths `f * 2^32 + PROPOSAL + slot`, above the frame's candidates.
const PROPOSAL: u64 = 1 << 31;

/// One slot's particle.
#[derive(Clone, Copy, Debug)]
struct Particle {
    path: u64,
    /// Picks the vertex within the path.
    xi: f32,
    /// The primary-space weight: `omega / T_f(u)`.
    w: f64,
    /// The VPL in the last frame where the path had one (dark stand-in while it has none).
    last: Vpl,
}

/// A particle with its path's vertices in this frame and their importance.
struct Live {
    pa: Particle,
    vs: Vec<Vpl>,
    imp: Vec<f32>,
}

/// `T_f` of a path whose vertices have importance `imp`, with the floor `phi`.
fn target(imp: &[f32], phi: f32) -> f64 {
    imp.iter().map(|&i| (i + phi) as f64).sum::<f64>() + phi as f64
}

/// The effective sample size of weights `omega`: `(sum omega)^2 / sum omega^2`.
pub fn ess(omega: &[f64]) -> f64 {
    let s: f64 = omega.iter().sum();
    let s2: f64 = omega.iter().map(|x| x * x).sum();
    if s2 > 0.0 {
        s * s / s2
    } else {
        0.0
    }
}

/// Which particle each slot holds after resampling: `counts[i]` copies of particle i (they sum
/// to the slots). A particle kept at least once stays in its own slot; its other copies fill, in
/// order, the slots of particles kept not at all. Returns, per slot, the particle and whether
/// the slot holds an extra copy.
pub fn assign(counts: &[usize]) -> Vec<(usize, bool)> {
    let mut out: Vec<Option<(usize, bool)>> = counts
        .iter()
        .enumerate()
        .map(|(i, &c)| (c > 0).then_some((i, false)))
        .collect();
    let mut free = (0..counts.len()).filter(|&s| counts[s] == 0);
    for (i, &c) in counts.iter().enumerate() {
        for _ in 1..c {
            let s = free.next().expect("the counts sum to the slots");
            out[s] = Some((i, true));
        }
    }
    out.into_iter()
        .map(|x| x.expect("the counts sum to the slots"))
        .collect()
}

pub struct Rmsmc {
    params: SamplerParams,
    particles: Vec<Particle>,
    /// The probe's importance last frame, by key.
    last_probe: HashMap<Key, f32>,
    /// The floor of the last frame (stands in when the probe sees nothing).
    phi: f32,
}

impl Rmsmc {
    pub fn new(params: &SamplerParams) -> Self {
        Rmsmc {
            params: params.clone(),
            particles: Vec::new(),
            last_probe: HashMap::new(),
            phi: 0.0,
        }
    }
}

/// One slot's random numbers for a frame, drawn before anything about the particles is known.
struct Draws {
    moves: bool,
    u: f64,
    xi: f32,
}

impl VplSampler for Rmsmc {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = self.params.clone();
        let t = Instant::now();
        let n = p.slots;
        let eps = p.knobs.eps(SamplerKind::Rmsmc);
        let points = p.camera_points(frame, tracer);
        let mut selection = Selection::default();

        // The probe: the floor and how far the target moved.
        let t_paths = Instant::now();
        let rate0 = p.knobs.rmsmc_rate;
        let (probe, probe_paths) = paths_by(
            frame,
            tracer,
            p.seed,
            |k| {
                if rate0 > 0.0 {
                    pool_path(p.seed, k, f, rate0)
                } else {
                    PROBE_STREAM * PATHS_PER_FRAME + k
                }
            },
            p.candidates,
            false,
        );
        let mut paths_s = t_paths.elapsed().as_secs_f64();
        let raw = importance_all(&probe, &points, tracer, p.clamp);
        let mean = raw.iter().map(|&x| x as f64).sum::<f64>() / raw.len().max(1) as f64;
        let phi = if mean > 0.0 && eps > 0.0 {
            (eps as f64 * mean) as f32
        } else if self.phi > 0.0 {
            self.phi
        } else {
            // Nothing seen yet (or no floor asked for): a floor far below any importance.
            f32::MIN_POSITIVE.max(1e-20)
        };
        // The probe's estimate of Z_f = E_p[T_f]: its paths' T_f (a path with no vertex: one
        // floor) averaged over the paths.
        let z = (raw.iter().map(|&x| x as f64).sum::<f64>()
            + phi as f64 * (raw.len() as u64 + probe_paths) as f64)
            / probe_paths.max(1) as f64;
        let d = tv_change(&self.last_probe, &probe, &raw);
        self.last_probe = probe.iter().zip(&raw).map(|(v, &i)| (key(v), i)).collect();
        self.phi = phi;
        selection.b = Some((mean * (1.0 + eps as f64)) as f32);
        selection.paths = probe_paths;

        let first = self.particles.len() != n;
        let rate = if first {
            0.0
        } else {
            (p.knobs.rmsmc_rate + p.knobs.rmsmc_follow * d).min(1.0)
        };
        let mut r = rng(&[p.seed, f, 0x7e5a]);
        let draws: Vec<Draws> = (0..n)
            .map(|_| Draws {
                moves: r.random::<f32>() < rate,
                u: r.random(),
                xi: r.random(),
            })
            .collect();

        // 1. Births (first frame) or the kept particles re-traced.
        let live: Vec<Live> = if first {
            let nb = newborns(frame, tracer, &points, &p, f, n);
            paths_s += nb.paths_s;
            selection.paths += nb.paths;
            if nb.b.is_none() {
                self.particles.clear();
                selection.importance_s = t.elapsed().as_secs_f64() - paths_s;
                return selection;
            }
            nb.born
                .into_iter()
                .map(|(pa, vs, imp)| Live {
                    pa: Particle {
                        path: pa.path,
                        xi: pa.xi,
                        w: pa.w as f64,
                        last: pa.last,
                    },
                    vs,
                    imp,
                })
                .collect()
        } else {
            self.particles
                .par_iter()
                .map(|pa| {
                    let (vs, imp) = vertices(frame, tracer, &points, &p, pa.path, true);
                    Live { pa: *pa, vs, imp }
                })
                .collect()
        };
        let targets: Vec<f64> = live.iter().map(|l| target(&l.imp, phi)).collect();
        let omega: Vec<f64> = live.iter().zip(&targets).map(|(l, t)| l.pa.w * t).collect();

        // 2. Resample when the effective sample size falls.
        let total: f64 = omega.iter().sum();
        let (live, targets) = if total > 0.0 && ess(&omega) < p.knobs.rmsmc_ess as f64 * n as f64 {
            let w: Vec<f32> = omega.iter().map(|&x| (x / total) as f32).collect();
            let mut counts = vec![0usize; n];
            for i in cdf_draw(&w, n, &mut rng(&[p.seed, f, 0x7e5b])) {
                counts[i] += 1;
            }
            let c = total / n as f64;
            let mut out = Vec::with_capacity(n);
            let mut ts = Vec::with_capacity(n);
            for (s, (i, extra)) in assign(&counts).into_iter().enumerate() {
                let l = &live[i];
                let mut pa = l.pa;
                pa.w = c / targets[i];
                if extra {
                    pa.xi = draws[s].xi;
                }
                out.push(Live {
                    pa,
                    vs: l.vs.clone(),
                    imp: l.imp.clone(),
                });
                ts.push(targets[i]);
            }
            drop(live);
            (out, ts)
        } else {
            (live, targets)
        };
        let mut live = live;
        // Sum of omega, which the moves keep.
        let sum: f64 = live.iter().zip(&targets).map(|(l, t)| l.pa.w * t).sum();

        // 3. Moves: an independence proposal from p per moving slot.
        let proposals: Vec<(usize, Vec<Vpl>, Vec<f32>)> = draws
            .par_iter()
            .enumerate()
            .filter(|(_, d)| d.moves)
            .map(|(s, _)| {
                let id = f * PATHS_PER_FRAME + PROPOSAL + s as u64;
                let (vs, imp) = vertices(frame, tracer, &points, &p, id, true);
                (s, vs, imp)
            })
            .collect();
        let mut accepted = 0usize;
        for (s, vs, imp) in &proposals {
            let t_new = target(imp, phi);
            let t_old = targets[*s];
            if draws[*s].u * t_old < t_new {
                let l = &mut live[*s];
                l.pa.w = l.pa.w * t_old / t_new;
                l.pa.path = f * PATHS_PER_FRAME + PROPOSAL + *s as u64;
                l.vs = vs.clone();
                l.imp = imp.clone();
                accepted += 1;
            }
        }
        selection.paths += proposals.len() as u64;

        // 4. Light: each particle's vertex and weight, the weights scaled so that their omega sum
        // to the probe's Z_f (self-normalized: the particles give the target's shape, the probe
        // its scale; their own sum of omega, a product of a ratio estimate per frame since their
        // birth, drifts further from Z_f every frame the target moves).
        let scale = if sum > 0.0 { z / sum } else { 0.0 };
        let (mut vpls, mut shaded) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let mut particles = Vec::with_capacity(n);
        for mut l in live {
            let (v, weight) = if l.vs.is_empty() {
                let dark = Vpl {
                    power: Vec3::ZERO,
                    path: l.pa.path,
                    ..l.pa.last
                };
                (dark, 0.0)
            } else {
                let (d, prob) = pick_vertex(&l.imp, phi, l.pa.xi);
                l.pa.last = l.vs[d];
                (l.vs[d], (scale * l.pa.w / prob as f64) as f32)
            };
            shaded.push(ShadedVpl::new(&v, weight));
            vpls.push(v);
            particles.push(l.pa);
        }
        self.particles = particles;
        selection.vpls = vpls;
        selection.shaded = shaded;
        selection.renewal_rate = Some(rate);
        selection.acceptance = Some(accepted as f32 / proposals.len().max(1) as f32);
        selection.importance_s = t.elapsed().as_secs_f64() - paths_s;
        selection
    }
}

#[cfg(test)]
mod tests {
    use super::{assign, ess};

    #[test]
    fn survivors_keep_their_slots_and_copies_fill_the_dropped_ones() {
        // Particle 0 twice, 1 dropped, 2 once, 3 three times, 4 and 5 dropped.
        let a = assign(&[2, 0, 1, 3, 0, 0]);
        assert_eq!(
            a,
            vec![
                (0, false),
                (0, true),
                (2, false),
                (3, false),
                (3, true),
                (3, true)
            ]
        );
        assert_eq!(assign(&[1, 1, 1]), vec![(0, false), (1, false), (2, false)]);
    }

    #[test]
    fn the_effective_sample_size_counts_equal_weights_fully() {
        assert_eq!(ess(&[2.0; 8]), 8.0);
        assert!((ess(&[1.0, 0.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((ess(&[1.0, 1.0, 2.0]) - 16.0 / 6.0).abs() < 1e-12);
    }
}
