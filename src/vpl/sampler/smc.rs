//! `smc`: sequential Monte Carlo over the frames (after Hedman et al. 2016): N particles, one
//! per slot, each a light path (its id, so its random numbers) with a weight fixed when it was
//! drawn. Each frame a particle re-traces its path in the frame's scene, so its VPLs move with
//! moving lights and objects, and lights its slot with one of the path's vertices, picked in
//! proportion to their importance by a random number of its own. A fraction `smc_rate` of the
//! slots a frame, chosen at random whatever their particles are, take newborn particles: paths
//! drawn from the frame's fresh candidate paths in proportion to their importance.
//!
//! Why a weight that never changes is right (docs/math.md, section 7): a particle is a point of
//! the paths' random numbers (primary sample space), and the frame's scene maps it to its
//! vertices. Re-tracing moves the vertices but not the point, so the particle's density in that
//! space is the one it was drawn with, in any later frame, and the weight of its draw (that of
//! resampled importance sampling, unbiased for that density) stays unbiased whatever the scene
//! did since, as long as the draw could pick every path: the importance it draws by is floored,
//! paths that left no vertex included. The particle is a whole path and not one vertex because
//! a vertex's path may reach that depth in one frame and not in another (a Russian-roulette coin
//! or a ray leaving through the open front): a vertex drawn in frame g is a sample of only the
//! vertices that existed in frame g. Measured on `cornell-light` with the light moved half-way
//! across the ceiling, vertices re-traced from the old frame (weighted for their coins) carried
//! 21% less of the light past the first bounce than the new frame's paths.
//!
//! Within the path, vertex d is picked with probability `P(d) = (I_d + floor) / sum (I + floor)`
//! (I in this frame, the floor of the particle's birth, fixed) and weighted `W / P(d)`, which
//! averages to the whole path's light times W.
//!
//! What changes a kept VPL's contribution, then: only its path in the new scene. In a still
//! scene a kept VPL is bit for bit the one of the last frame, weight included (mh's kept
//! weights still move with its normalization pool). Under a moving light it moves with the
//! light as frozen's do, without a normalization that jumps. A chain that lags behind a moving
//! target costs mh bias (its weight `b / (N I_f)` assumes the chain is at the current target);
//! a particle that lags costs only variance (its weight is that of the density it was drawn
//! from), so the renewal rate trades flicker against variance, not against a wrong mean.
//!
//! Why not temporal reservoirs (ReSTIR): a reservoir re-weights its kept sample every frame by
//! the sum of weights it has seen (every kept VPL's weight moves a little each frame, as mh's
//! did with b), and combining last frame's reservoir with fresh candidates without bias needs
//! last frame's target at the fresh candidates, which a sampler that sees one frame at a time
//! does not have.
//!
//! `smc_follow` raises the rate where the kept weights are off: for each particle,
//! `t = (I_f + floor) / (I_g + floor)` (its path's importance now over at birth) says how far its
//! weight is from the one a newborn there would get; the spread of t over the particles,
//! `D = 1/2 sum |t_i / sum t - 1 / n|` (0 when all moved alike, exactly 0 in a still scene),
//! raises the rate to `min(1, smc_rate + smc_follow * D)`. So that no slot's renewal depends on
//! its own particle, the slots are split into two halves (even and odd) and each half's rate is
//! measured on the other half.

use super::common::{cdf_draw, Candidates, PATHS_PER_FRAME};
use super::{SamplerKind, SamplerParams, Selection, VplSampler};
use crate::math::rng;
use crate::scene::Frame;
use crate::trace::Tracer;
use crate::vpl::importance::{importance, CameraPoint};
use crate::vpl::{trace_path, ShadedVpl, Vpl};
use glam::Vec3;
use rand::Rng;
use rayon::prelude::*;
use std::time::Instant;

/// One slot's particle.
#[derive(Clone, Copy, Debug)]
pub(super) struct Particle {
    pub(super) path: u64,
    /// Picks the vertex within the path (inverse CDF of `P(d)`).
    pub(super) xi: f32,
    /// The slot's weight, `(mean importance of the candidate paths) / (N * importance of this
    /// path)` at birth.
    pub(super) w: f32,
    /// The path's importance (without floors) and the vertex floor, at birth.
    i: f32,
    floor: f32,
    /// The VPL in the last frame where the path had one (stands in, with no power, while it
    /// has none).
    pub(super) last: Vpl,
}

pub struct Smc {
    params: SamplerParams,
    particles: Vec<Particle>,
}

impl Smc {
    pub fn new(params: &SamplerParams) -> Self {
        Smc {
            params: params.clone(),
            particles: Vec::new(),
        }
    }
}

/// The spread of the kept particles' importance ratios `t`: `1/2 sum |t_i / sum t - 1 / n|`
/// (0 for no particle or when every ratio is the same).
pub fn spread(t: &[f64]) -> f64 {
    let sum: f64 = t.iter().sum();
    if t.is_empty() || sum <= 0.0 {
        return 0.0;
    }
    let n = t.len() as f64;
    0.5 * t.iter().map(|&x| (x / sum - 1.0 / n).abs()).sum::<f64>()
}

/// The vertex that `xi` picks among a path's vertices of importance `imp` (floored by
/// `floor`), and its probability.
pub fn pick_vertex(imp: &[f32], floor: f32, xi: f32) -> (usize, f32) {
    if imp.len() <= 1 {
        return (0, 1.0);
    }
    let total: f64 = imp.iter().map(|&i| (i + floor) as f64).sum();
    let u = xi as f64 * total;
    let mut acc = 0.0f64;
    for (d, &i) in imp.iter().enumerate() {
        acc += (i + floor) as f64;
        if u < acc || d == imp.len() - 1 {
            return (d, ((i + floor) as f64 / total) as f32);
        }
    }
    unreachable!()
}

/// A path's vertices in this frame with their importance (skipped for a single vertex, whose
/// pick needs none, unless `always`).
pub(super) fn vertices(
    frame: &Frame,
    tracer: &Tracer,
    points: &[CameraPoint],
    p: &SamplerParams,
    path: u64,
    always: bool,
) -> (Vec<Vpl>, Vec<f32>) {
    let v = trace_path(frame, tracer, p.seed, path);
    let imp = if v.len() > 1 || always {
        v.iter()
            .map(|x| importance(x, points, tracer, p.clamp))
            .collect()
    } else {
        vec![0.0; v.len()]
    };
    (v, imp)
}

/// Each half's renewal rate, from the other half's spread of importance now over at birth.
fn rates(
    particles: &[Particle],
    p: &SamplerParams,
    retraced: &[(Vec<Vpl>, Vec<f32>)],
    first: bool,
    follow: bool,
) -> [f32; 2] {
    if first {
        [1.0f32; 2]
    } else if follow {
        let t: Vec<f64> = particles
            .iter()
            .zip(retraced)
            .map(|(pa, (_, imp))| {
                let now: f32 = imp.iter().sum();
                (now + pa.floor) as f64 / (pa.i + pa.floor).max(f32::MIN_POSITIVE) as f64
            })
            .collect();
        let half = |h: usize| -> Vec<f64> { t.iter().skip(h).step_by(2).copied().collect() };
        let (d0, d1) = (spread(&half(0)), spread(&half(1)));
        [
            (p.knobs.smc_rate + p.knobs.smc_follow * d1 as f32).min(1.0),
            (p.knobs.smc_rate + p.knobs.smc_follow * d0 as f32).min(1.0),
        ]
    } else {
        [p.knobs.smc_rate; 2]
    }
}

impl VplSampler for Smc {
    fn select(&mut self, frame: &Frame, tracer: &Tracer, f: u64) -> Selection {
        let p = self.params.clone();
        let t = Instant::now();
        let n = p.slots;
        let first = self.particles.len() != n;
        let points = p.camera_points(frame, tracer);
        // The kept particles' paths in this frame, with their vertices' importance.
        let follow = p.knobs.smc_follow > 0.0;
        let retraced: Vec<(Vec<Vpl>, Vec<f32>)> = if first {
            Vec::new()
        } else {
            self.particles
                .par_iter()
                .map(|pa| vertices(frame, tracer, &points, &p, pa.path, follow))
                .collect()
        };
        // Each half's rate, from the other half's spread.
        let rates = rates(&self.particles, &p, &retraced, first, follow);
        // Which slots renew: drawn before anything about the particles is known.
        let mut ru = rng(&[p.seed, f, 0x5c3c]);
        let renew: Vec<bool> = (0..n)
            .map(|s| {
                let u: f32 = ru.random();
                first || u < rates[s % 2]
            })
            .collect();
        let k = renew.iter().filter(|&&x| x).count();
        let mut selection = Selection::default();
        let mut paths_s = 0.0;
        // Newborns: (particle, its vertices and their importance).
        let mut newborn = Vec::new();
        if k > 0 {
            let nb = newborns(frame, tracer, &points, &p, f, k);
            (paths_s, selection.paths, selection.b) = (nb.paths_s, nb.paths, nb.b);
            if nb.b.is_none() {
                // No candidate left a vertex.
                self.particles.clear();
                selection.importance_s = t.elapsed().as_secs_f64() - paths_s;
                return selection;
            }
            newborn = nb.born;
        }
        let mut born = newborn.into_iter();
        let mut retraced = retraced.into_iter();
        let mut particles = Vec::with_capacity(n);
        let (mut vpls, mut shaded) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for &renewed in &renew {
            let now = retraced.next();
            let (mut pa, vs, imp) = if renewed {
                born.next().expect("one newborn per renewed slot")
            } else {
                let (vs, imp) = now.expect("a kept particle was re-traced");
                (self.particles[particles.len()], vs, imp)
            };
            let (v, weight) = particle_vpl(&mut pa, &vs, &imp);
            shaded.push(ShadedVpl::new(&v, weight));
            vpls.push(v);
            particles.push(pa);
        }
        self.particles = particles;
        selection.vpls = vpls;
        selection.shaded = shaded;
        selection.renewal_rate = Some(0.5 * (rates[0] + rates[1]));
        selection.importance_s = t.elapsed().as_secs_f64() - paths_s;
        selection
    }
}

/// The VPL a particle lights this frame with and its weight: the vertex its coin picks among
/// `vs` (importance `imp`), or, with no vertex this frame, its last one dark.
fn particle_vpl(pa: &mut Particle, vs: &[Vpl], imp: &[f32]) -> (Vpl, f32) {
    if vs.is_empty() {
        // No vertex in this frame: the slot is dark.
        let dark = Vpl {
            power: Vec3::ZERO,
            ..pa.last
        };
        return (dark, 0.0);
    }
    let (d, prob) = pick_vertex(imp, pa.floor, pa.xi);
    pa.last = vs[d];
    (vs[d], pa.w / prob)
}

/// What the newborns of a frame are: each particle with its vertices and their importance,
/// and the candidates' paths, their seconds and `b` (None: no candidate left a vertex).
pub(super) struct Newborns {
    pub(super) born: Vec<(Particle, Vec<Vpl>, Vec<f32>)>,
    pub(super) paths_s: f64,
    pub(super) paths: u64,
    pub(super) b: Option<f32>,
}

/// `k` newborn particles drawn as cdf draws them from the frame's candidate paths.
pub(super) fn newborns(
    frame: &Frame,
    tracer: &Tracer,
    points: &[CameraPoint],
    p: &SamplerParams,
    f: u64,
    k: usize,
) -> Newborns {
    let n = p.slots;
    let c = Candidates::new(
        frame,
        tracer,
        points,
        p.seed,
        f,
        p.candidates,
        p.knobs.eps(SamplerKind::Smc),
        p.clamp,
    );
    let mut out = Newborns {
        born: Vec::with_capacity(k),
        paths_s: c.paths_s,
        paths: c.paths,
        b: None,
    };
    if c.vpls.is_empty() {
        return out;
    }
    out.b = Some(c.b);
    // The candidate paths (those that left no vertex too) and their floored importance:
    // the sum of their vertices' plus one floor more, so that every path can be drawn.
    let np = c.paths as usize;
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); np];
    for (j, v) in c.vpls.iter().enumerate() {
        members[(v.path - f * PATHS_PER_FRAME) as usize].push(j);
    }
    let target: Vec<f32> = members
        .iter()
        .map(|m| m.iter().map(|&j| c.raw[j]).sum::<f32>() + c.floor * (m.len() + 1) as f32)
        .collect();
    let mean = target.iter().map(|&x| x as f64).sum::<f64>() / np as f64;
    let mut r = rng(&[p.seed, f, 0x5a3b]);
    let idx = cdf_draw(&target, k, &mut r);
    for i in idx {
        let m = &members[i];
        let vs: Vec<Vpl> = m.iter().map(|&j| c.vpls[j]).collect();
        let imp: Vec<f32> = m.iter().map(|&j| c.raw[j]).collect();
        let pa = Particle {
            path: f * PATHS_PER_FRAME + i as u64,
            xi: r.random(),
            w: (mean / (n as f64 * target[i] as f64)) as f32,
            i: imp.iter().sum(),
            floor: c.floor,
            last: vs.first().copied().unwrap_or(Vpl {
                position: Vec3::ZERO,
                normal: Vec3::Y,
                albedo: Vec3::ZERO,
                power: Vec3::ZERO,
                depth: 0,
                path: f * PATHS_PER_FRAME + i as u64,
                tri: 0,
                near: None,
                fan: None,
            }),
        };
        out.born.push((pa, vs, imp));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{pick_vertex, spread};

    #[test]
    fn the_spread_is_zero_when_all_moved_alike_and_grows_with_the_difference() {
        assert_eq!(spread(&[]), 0.0);
        assert_eq!(spread(&[1.0; 5]), 0.0);
        // Two of four carry all the mass: half of it would have to move.
        assert!((spread(&[1.0, 1.0, 0.0, 0.0]) - 0.5).abs() < 1e-12);
        assert!(spread(&[1.0, 1.1, 0.9, 1.0]) < spread(&[1.0, 2.0, 0.5, 1.0]));
    }

    #[test]
    fn a_vertex_is_picked_in_proportion_to_its_floored_importance() {
        // (1 + 1), (0 + 1), (5 + 1) of 9.
        let imp = [1.0, 0.0, 5.0];
        let counts = (0..9000).fold([0u32; 3], |mut c, j| {
            let (d, prob) = pick_vertex(&imp, 1.0, (j as f32 + 0.5) / 9000.0);
            assert!((prob - [2.0, 1.0, 6.0][d] / 9.0).abs() < 1e-6);
            c[d] += 1;
            c
        });
        assert_eq!(counts, [2000, 1000, 6000]);
        assert_eq!(pick_vertex(&[3.0], 0.0, 0.99), (0, 1.0));
    }
}
