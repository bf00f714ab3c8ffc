//! The samplers' estimators on a fixed frame (CPU twin, exact visibility): `cdf`, `rejection`,
//! `mh`, `smc` and `rmsmc` must average to what `uniform` averages to (`smc` and `rmsmc` also
//! under a moving light), `mh` must keep most of its VPLs from frame to frame, `frozen` must keep
//! its light paths, and `smc` and `rmsmc` their particles, bit for bit where nothing moves.

use glam::Vec3;
use irad::math::luminance;
use irad::reference::twin;
use irad::scene::builtin;
use irad::trace::Tracer;
use irad::vpl::sampler::knobs::SamplerKnobs;
use irad::vpl::sampler::{Sampler, SamplerKind, SamplerParams, PATHS_PER_FRAME};

const W: u32 = 12;
const H: u32 = 12;
const DMIN: f32 = 0.1;

fn params(kind: SamplerKind, seed: u64) -> SamplerParams {
    SamplerParams {
        kind,
        slots: 32,
        candidates: 128,
        clamp: DMIN,
        seed,
        width: W,
        height: H,
        knobs: SamplerKnobs {
            camera_points: 64,
            eps: Some(0.05),
            mh_rate: 1.0,
            mh_follow: 0.0,
            mh_escape: 0,
            smc_rate: 0.05,
            smc_follow: 0.0,
            rmsmc_ess: 0.5,
            rmsmc_rate: 0.0,
            rmsmc_follow: 10.0,
            ..SamplerKnobs::default()
        },
    }
}

/// `p` with its knobs set by `f`.
fn knobbed(mut p: SamplerParams, f: impl FnOnce(&mut SamplerKnobs)) -> SamplerParams {
    f(&mut p.knobs);
    p
}

/// The four image quadrants' mean indirect luminance of one estimate.
fn quadrants(img: &irad::image::Hdr) -> [f64; 4] {
    let mut q = [0.0f64; 4];
    for y in 0..H {
        for x in 0..W {
            q[((y >= H / 2) as usize) * 2 + (x >= W / 2) as usize] +=
                luminance(img.at(x, y)) as f64;
        }
    }
    q.map(|v| v / (W * H / 4) as f64)
}

/// The four image quadrants' mean indirect luminance of a selection's VPLs in `frame` (traced
/// by `tracer`), gathered with exact visibility at the pixel centres.
fn quadrant_image<'a>(
    frame: &'a irad::scene::Frame,
    tracer: &'a Tracer,
) -> impl Fn(&irad::vpl::sampler::Selection) -> [f64; 4] + 'a {
    let points = twin::pixel_points(frame, tracer, W, H);
    move |sel| {
        quadrants(&twin::gather(
            frame,
            tracer,
            &points,
            W,
            H,
            &sel.shaded,
            DMIN,
        ))
    }
}

/// The whole image's mean over the estimates (each the mean of its quadrants) and their
/// standard deviation.
fn whole_image(x: &[[f64; 4]]) -> (f64, f64) {
    let v: Vec<f64> = x.iter().map(|q| q.iter().sum::<f64>() / 4.0).collect();
    let m = v.iter().sum::<f64>() / v.len() as f64;
    let var = v.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
    (m, var.sqrt())
}

struct Estimates {
    mean: [f64; 4],
    se: [f64; 4],
}

impl Estimates {
    /// The standard error of the difference of quadrant `k`'s mean and `other`'s.
    fn se_of_difference(&self, other: &Estimates, k: usize) -> f64 {
        (self.se[k].powi(2) + other.se[k].powi(2)).sqrt()
    }

    /// Asserts that quadrant `k`'s mean (sampler `name`) matches `uniform`'s: z < 4, a
    /// statistical bound (|z| > 4 happens with probability 6e-5), not fitted to measurements.
    fn assert_matches(&self, name: &str, uniform: &Estimates, k: usize) {
        let z = (self.mean[k] - uniform.mean[k]).abs() / self.se_of_difference(uniform, k);
        println!(
            "quadrant {k}: {name} {:.5} +- {:.5}, uniform {:.5} +- {:.5}, z = {z:.2}",
            self.mean[k], self.se[k], uniform.mean[k], uniform.se[k]
        );
        assert!(
            z < 4.0,
            "{name} quadrant {k}: {} vs uniform {} (z = {z})",
            self.mean[k],
            uniform.mean[k]
        );
    }
}

/// Mean and standard error of per-frame estimates; with `batches`, by batch means (for
/// correlated chains).
fn stats(samples: &[[f64; 4]], batches: usize) -> Estimates {
    let groups: Vec<[f64; 4]> = samples
        .chunks(samples.len() / batches)
        .filter(|c| c.len() == samples.len() / batches)
        .map(|c| {
            let mut m = [0.0; 4];
            for s in c {
                for k in 0..4 {
                    m[k] += s[k] / c.len() as f64;
                }
            }
            m
        })
        .collect();
    let n = groups.len() as f64;
    let mut mean = [0.0; 4];
    let mut se = [0.0; 4];
    for k in 0..4 {
        mean[k] = groups.iter().map(|g| g[k]).sum::<f64>() / n;
        let var = groups.iter().map(|g| (g[k] - mean[k]).powi(2)).sum::<f64>() / (n - 1.0);
        se[k] = (var / n).sqrt();
    }
    Estimates { mean, se }
}

fn run(kind: SamplerKind, frames: u64, skip: u64) -> Vec<[f64; 4]> {
    run_with(params(kind, 11), frames, skip)
}

fn run_with(p: SamplerParams, frames: u64, skip: u64) -> Vec<[f64; 4]> {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let image = quadrant_image(&frame, &tracer);
    let mut s = Sampler::new(p);
    (0..frames)
        .filter_map(|f| {
            let sel = s.select(&frame, &tracer, f);
            (f >= skip).then(|| image(&sel))
        })
        .collect()
}

/// On a fixed frame, the averages of many cdf and rejection estimates and of many mh chain steps (after
/// burn-in) equal the uniform estimator's, per image quadrant, within 4 standard errors.
#[test]
fn cdf_and_mh_average_to_the_uniform_estimate() {
    let uniform = stats(&run(SamplerKind::Uniform, 240, 0), 240);
    let cdf = stats(&run(SamplerKind::Cdf, 240, 0), 240);
    let rejection = stats(&run(SamplerKind::Rejection, 240, 0), 240);
    let mh = stats(&run(SamplerKind::Mh, 420, 20), 20);
    let escape = stats(
        &run_with(
            knobbed(
                SamplerParams {
                    ..params(SamplerKind::Mh, 12)
                },
                |k| {
                    k.mh_escape = 8;
                },
            ),
            420,
            20,
        ),
        20,
    );
    // A lazy chain (the normalization pool renews a tenth of its paths a frame): its error
    // must average out over time too, which a pool that never renewed would not do.
    let lazy = stats(
        &run_with(
            knobbed(
                SamplerParams {
                    ..params(SamplerKind::Mh, 13)
                },
                |k| {
                    k.mh_rate = 0.1;
                },
            ),
            2020,
            20,
        ),
        20,
    );
    // A pool past the budget of full sums (6000 candidates x up to 64 camera points): each
    // candidate's importance summed over every third stratum only (`mh::pool_stride`), so b is
    // an unbiased estimate from fewer rays and must still give the uniform estimate.
    let sampled_pool = stats(
        &run_with(
            SamplerParams {
                candidates: 6000,
                ..params(SamplerKind::Mh, 16)
            },
            140,
            20,
        ),
        20,
    );
    // Particles that live ten frames on average, and that follow a target.
    let smc = stats(
        &run_with(
            knobbed(
                SamplerParams {
                    ..params(SamplerKind::Smc, 14)
                },
                |k| {
                    k.smc_rate = 0.1;
                },
            ),
            2020,
            20,
        ),
        20,
    );
    // Resample-move particles, a tenth of the slots moving a frame (at rate 0 a still frame
    // keeps its first draw for good, whose time average is one draw).
    let rmsmc = stats(
        &run_with(
            knobbed(params(SamplerKind::Rmsmc, 15), |k| {
                k.rmsmc_rate = 0.1;
            }),
            2020,
            20,
        ),
        20,
    );
    for k in 0..4 {
        for (name, e) in [
            ("cdf", &cdf),
            ("rejection", &rejection),
            ("mh", &mh),
            ("mh escape 8", &escape),
            ("mh rate 0.1", &lazy),
            ("mh sampled pool", &sampled_pool),
            ("smc rate 0.1", &smc),
            ("rmsmc rate 0.1", &rmsmc),
        ] {
            // Measured: z at most 1.51 (mh escape 8, quadrant 3), 0.94 for cdf.
            e.assert_matches(name, &uniform, k);
        }
        // The test has the power to see a wrong weight: one 30% too low (leaving out M/P
        // would be a factor of about 2.4) falls far outside the bound.
        for e in [&cdf, &rejection] {
            let wrong = e.mean[k] * 0.7;
            assert!((wrong - uniform.mean[k]).abs() > 4.0 * e.se_of_difference(&uniform, k));
        }
    }
}

/// Coherence on the still Cornell view: mh keeps most slots (fewer still with a lower
/// proposal rate), cdf replaces nearly all.
#[test]
fn mh_keeps_vpls_cdf_replaces_them() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let mean_replaced = |p: SamplerParams| {
        let mut s = Sampler::new(p);
        let r: Vec<f32> = (0..30)
            .map(|f| s.select(&frame, &tracer, f).replaced)
            .collect();
        assert_eq!(r[0], 1.0, "the first frame fills every slot");
        r[1..].iter().sum::<f32>() / (r.len() - 1) as f32
    };
    let cdf = mean_replaced(params(SamplerKind::Cdf, 3));
    let mh = mean_replaced(params(SamplerKind::Mh, 3));
    let lazy = mean_replaced(knobbed(
        SamplerParams {
            ..params(SamplerKind::Mh, 3)
        },
        |k| {
            k.mh_rate = 0.2;
        },
    ));
    println!("replaced per frame: cdf {cdf:.4}, mh {mh:.4}, mh at rate 0.2 {lazy:.4}");
    // Measured: cdf 1.0000, mh 0.6444, mh at rate 0.2 0.1045.
    assert!(cdf > 0.95, "cdf replaced {cdf}");
    assert!(mh < 0.75 && mh > 0.43, "mh replaced {mh}");
    assert!(lazy < 0.15, "mh at rate 0.2 replaced {lazy}");
}

/// What moves a kept MH VPL's weight `b / (N I) * (M / P)` in a still scene: not I (the camera
/// points are the same every frame) and only a little of b and M / P, which come from a pool
/// renewing at the chains' rate. Before the pool, b came from each frame's fresh candidates
/// and every kept weight jumped with it as much as cdf's b does. The proposal rate stays at its
/// base where nothing moves and rises under a moving light.
#[test]
fn kept_mh_weights_hold_still_and_the_rate_follows_the_scene() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let p = |kind, seed| {
        knobbed(
            SamplerParams {
                slots: 64,
                candidates: 256,
                ..params(kind, seed)
            },
            |k| {
                k.mh_rate = 0.05;
                k.mh_follow = 10.0;
            },
        )
    };
    // Mean |log ratio| of consecutive frames' b for cdf, and of kept VPLs' weights for mh, over
    // four seeds (one seed's ratio of the two lies anywhere in 0.26-0.42: seeds 21-28).
    let (mut cdf_jump, mut mh_jump) = (0.0f64, 0.0f64);
    for seed in 21..25 {
        let mut cdf = Sampler::new(p(SamplerKind::Cdf, seed));
        let bs: Vec<f64> = (0..40)
            .map(|f| cdf.select(&frame, &tracer, f).b.unwrap() as f64)
            .collect();
        cdf_jump += bs.windows(2).map(|w| (w[1] / w[0]).ln().abs()).sum::<f64>() / 39.0 / 4.0;
        let mut mh = Sampler::new(p(SamplerKind::Mh, seed));
        let mut last = mh.select(&frame, &tracer, 0);
        let (mut jump, mut kept) = (0.0f64, 0usize);
        for f in 1..40 {
            let s = mh.select(&frame, &tracer, f);
            assert_eq!(
                s.renewal_rate,
                Some(0.05),
                "frame {f}: nothing moved, the base rate"
            );
            for ((v, w), (v0, w0)) in s
                .vpls
                .iter()
                .zip(&s.shaded)
                .zip(last.vpls.iter().zip(&last.shaded))
            {
                if (v.path, v.depth) == (v0.path, v0.depth) {
                    jump += (luminance(w.flux) as f64 / luminance(w0.flux) as f64)
                        .ln()
                        .abs();
                    kept += 1;
                }
            }
            last = s;
        }
        println!("seed {seed}: {kept} kept");
        mh_jump += jump / kept as f64 / 4.0;
    }
    println!("mean |log change| per frame: cdf's b {cdf_jump:.5}, kept mh weights {mh_jump:.5}");
    // Measured: cdf 0.0781, mh 0.0257 (0.33x; a renewal of 5% of the pool a frame moves b by
    // about sqrt(0.05) = 0.22x, and M / P moves too). Drawn from fresh candidates, b moved as
    // much as cdf's (1x).
    assert!(cdf_jump > 0.005, "cdf's b barely moved: {cdf_jump}");
    assert!(
        mh_jump < 0.5 * cdf_jump,
        "kept weights moved {mh_jump} against cdf's b {cdf_jump}"
    );
    // A moving light moves the target: the rate rises above the base.
    let scene = builtin::load("cornell-light").unwrap().unwrap();
    let mut mh = Sampler::new(p(SamplerKind::Mh, 21));
    let mut rates = Vec::new();
    for f in 0..6 {
        let frame = scene.at(f as f32 / 24.0);
        tracer_for(&frame, |tr| {
            rates.push(mh.select(&frame, tr, f).renewal_rate.unwrap())
        });
    }
    println!("rates under a moving light: {rates:?}");
    assert!(rates[1..].iter().all(|&r| r > 0.1), "rates {rates:?}");
}

fn tracer_for(frame: &irad::scene::Frame, f: impl FnOnce(&Tracer)) {
    f(&Tracer::new(frame))
}

/// Determinism, for every sampler: two samplers with the same seed select bit-identical VPLs
/// frame after frame (the MH chains included); another seed selects other VPLs in every frame.
#[test]
fn same_seed_same_vpls_other_seed_other_vpls() {
    let scene = builtin::load("cornell-orbit").unwrap().unwrap();
    let tracer = Tracer::new(&scene.at(0.0));
    let bits = |v: &[irad::vpl::ShadedVpl]| -> Vec<u32> {
        v.iter()
            .flat_map(|s| [s.position, s.normal, s.flux])
            .flat_map(|c| c.to_array().map(f32::to_bits))
            .collect()
    };
    for kind in SamplerKind::ALL {
        let mut a = Sampler::new(params(kind, 5));
        let mut b = Sampler::new(params(kind, 5));
        let mut other = Sampler::new(params(kind, 6));
        for f in 0..4 {
            let frame = scene.at(f as f32 / 24.0);
            let (x, y) = (a.select(&frame, &tracer, f), b.select(&frame, &tracer, f));
            assert_eq!(bits(&x.shaded), bits(&y.shaded), "{kind:?} frame {f}");
            let z = other.select(&frame, &tracer, f);
            assert_ne!(x.shaded, z.shaded, "{kind:?} frame {f}: seed 6 = seed 5");
        }
    }
}

/// `frozen` gives bitwise the same VPL set every frame of a still scene (uniform does not),
/// and under a moving light the same paths, re-traced, so its VPLs move with the light.
#[test]
fn frozen_keeps_its_paths() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let mut frozen = Sampler::new(params(SamplerKind::Frozen, 4));
    let mut uniform = Sampler::new(params(SamplerKind::Uniform, 4));
    let first = frozen.select(&frame, &tracer, 0);
    let u0 = uniform.select(&frame, &tracer, 0);
    assert!(!first.vpls.is_empty());
    for f in 1..5 {
        let s = frozen.select(&frame, &tracer, f);
        assert_eq!(s.vpls, first.vpls, "frame {f}");
        assert_eq!(s.shaded, first.shaded, "frame {f}");
        assert_eq!(s.replaced, 0.0);
        assert_ne!(uniform.select(&frame, &tracer, f).vpls, u0.vpls);
    }
    // A moving light: the same path ids, but the VPLs have moved.
    let scene = builtin::load("cornell-light").unwrap().unwrap();
    let mut frozen = Sampler::new(SamplerParams {
        slots: 256,
        ..params(SamplerKind::Frozen, 4)
    });
    let (a, b) = (scene.at(0.0), scene.at(0.5));
    let sa = frozen.select(&a, &Tracer::new(&a), 0);
    let sb = frozen.select(&b, &Tracer::new(&b), 12);
    // Both frames use paths 0..P of the same stream (paths that escape leave no VPL).
    for s in [&sa, &sb] {
        assert!(s.vpls.iter().all(|v| v.path < s.paths), "paths {}", s.paths);
    }
    let first_hit = |s: &irad::vpl::sampler::Selection, path: u64| {
        s.vpls
            .iter()
            .find(|v| v.path == path && v.depth == 1)
            .map(|v| v.position)
    };
    let common: Vec<(Vec3, Vec3)> = (0..sa.paths.min(sb.paths))
        .filter_map(|p| Some((first_hit(&sa, p)?, first_hit(&sb, p)?)))
        .collect();
    let moved = common.iter().filter(|(x, y)| x.distance(*y) > 1e-3).count();
    assert!(common.len() > 50, "{} paths in both frames", common.len());
    assert!(
        moved > common.len() / 2,
        "moved {moved} of {}",
        common.len()
    );
}

/// `smc` in a still scene: a slot either keeps its particle, and then its VPL and weight are
/// bitwise the last frame's, or renews, about `smc_rate` of the slots a frame; and with `smc_follow` the rate stays exactly at its base
/// (the kept importance does not move), while under a moving camera it rises.
#[test]
fn smc_keeps_its_particles_bit_for_bit_where_nothing_moves() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let p = knobbed(
        SamplerParams {
            ..params(SamplerKind::Smc, 31)
        },
        |k| {
            k.smc_rate = 0.1;
            k.smc_follow = 10.0;
        },
    );
    let mut smc = Sampler::new(p.clone());
    let mut last = smc.select(&frame, &tracer, 0);
    let (mut kept, mut slots, mut replaced) = (0usize, 0usize, 0.0f64);
    let frames = 60;
    for f in 1..frames {
        let s = smc.select(&frame, &tracer, f);
        assert_eq!(
            s.renewal_rate,
            Some(0.1),
            "frame {f}: nothing moved, the base rate"
        );
        assert_eq!(s.vpls.len(), p.slots);
        for ((v, w), (v0, w0)) in s
            .vpls
            .iter()
            .zip(&s.shaded)
            .zip(last.vpls.iter().zip(&last.shaded))
        {
            if (v.path, v.depth) == (v0.path, v0.depth) {
                assert_eq!(v, v0, "frame {f}");
                assert_eq!(
                    [w.position, w.normal, w.flux].map(|c| c.to_array().map(f32::to_bits)),
                    [w0.position, w0.normal, w0.flux].map(|c| c.to_array().map(f32::to_bits)),
                    "frame {f}"
                );
                kept += 1;
            }
            slots += 1;
        }
        replaced += s.replaced as f64;
        last = s;
    }
    let replaced = replaced / (frames - 1) as f64;
    // Binomial: 59 frames x 32 slots at 0.1 gives a standard error of 0.0070.
    println!("smc replaced {replaced:.4} a frame at rate 0.1 ({kept} of {slots} kept)");
    assert!((replaced - 0.1).abs() < 0.028, "replaced {replaced}");
    // A moving camera moves the kept particles' importance: the rate rises.
    let orbit = builtin::load("cornell-orbit").unwrap().unwrap();
    let mut smc = Sampler::new(p);
    let rates: Vec<f32> = (0..6)
        .map(|f| {
            let fr = orbit.at(f as f32 / 4.0);
            smc.select(&fr, &Tracer::new(&fr), f).renewal_rate.unwrap()
        })
        .collect();
    println!("smc rates under a moving camera: {rates:?}");
    assert!(rates[1..].iter().all(|&r| r > 0.15), "rates {rates:?}");
}

/// `smc` under a moving light: particles (paths) drawn while the light was at one end of the
/// ceiling, re-traced in each frame as it slides, give on average the light that uniform's
/// fresh paths give in the last frame,
/// per image quadrant, over independent seeds. Slow renewal (rate 0.05, no follow) so that
/// most particles are old.
#[test]
fn smc_averages_to_the_uniform_estimate_under_a_moving_light() {
    let scene = builtin::load("cornell-light").unwrap().unwrap();
    let steps = 12u64;
    let time = |f: u64| f as f32 * 0.125;
    let last = scene.at(time(steps));
    let last_tracer = Tracer::new(&last);
    let image = quadrant_image(&last, &last_tracer);
    let seeds = 800u64;
    let (mut smc, mut uniform) = (Vec::new(), Vec::new());
    let mut old = 0usize;
    for seed in 0..seeds {
        let mut s = Sampler::new(knobbed(
            SamplerParams {
                ..params(SamplerKind::Smc, 1000 + seed)
            },
            |k| {
                k.smc_rate = 0.05;
            },
        ));
        for f in 0..steps {
            let fr = scene.at(time(f));
            s.select(&fr, &Tracer::new(&fr), f);
        }
        let sel = s.select(&last, &last_tracer, steps);
        old += sel.vpls.iter().filter(|v| v.path < PATHS_PER_FRAME).count();
        smc.push(image(&sel));
        let mut u = Sampler::new(SamplerParams {
            slots: 256,
            ..params(SamplerKind::Uniform, 1000 + seed)
        });
        uniform.push(image(&u.select(&last, &last_tracer, steps)));
    }
    let (smc_raw, uniform_raw) = (smc, uniform);
    let (smc, uniform) = (
        stats(&smc_raw, seeds as usize),
        stats(&uniform_raw, seeds as usize),
    );
    let old = old as f64 / (seeds as f64 * 32.0);
    println!("particles born in frame 0: {old:.3}");
    assert!(old > 0.4, "most particles are old: {old}");
    for k in 0..4 {
        smc.assert_matches("smc", &uniform, k);
    }
    // The whole image: the power to see a 7% error (what particles of one vertex each, drawn
    // in frame 0, lost by frame 12: their paths' later vertices that did not exist in frame 0).
    // Mean and standard error.
    let whole = |x: &[[f64; 4]]| {
        let (m, sd) = whole_image(x);
        (m, sd / (x.len() as f64).sqrt())
    };
    let ((ms, ss), (mu, su)) = (whole(&smc_raw), whole(&uniform_raw));
    let z = (ms - mu).abs() / (ss * ss + su * su).sqrt();
    println!("image: smc {ms:.5} +- {ss:.5}, uniform {mu:.5} +- {su:.5}, z = {z:.2}");
    assert!(z < 4.0, "image: smc {ms} vs uniform {mu} (z = {z})");
    assert!(0.07 * mu > 4.0 * (ss * ss + su * su).sqrt());
}

/// `rmsmc` where nothing moves: the probe's importance is the last frame's, so the move rate is
/// 0, no weight changes, nothing is resampled, and every VPL and weight is bit for bit frame 0's
/// (as frozen's). Under a moving light the rate rises and slots change.
#[test]
fn rmsmc_keeps_every_particle_bit_for_bit_where_nothing_moves() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let bits = |s: &irad::vpl::sampler::Selection| -> Vec<u32> {
        s.shaded
            .iter()
            .flat_map(|v| [v.position, v.normal, v.flux])
            .flat_map(|c| c.to_array().map(f32::to_bits))
            .collect()
    };
    let mut rm = Sampler::new(params(SamplerKind::Rmsmc, 41));
    let first = rm.select(&frame, &tracer, 0);
    assert_eq!(first.vpls.len(), 32);
    assert!(first.shaded.iter().any(|v| v.flux.max_element() > 0.0));
    for f in 1..12 {
        let s = rm.select(&frame, &tracer, f);
        assert_eq!(s.renewal_rate, Some(0.0), "frame {f}: nothing moved");
        assert_eq!(s.vpls, first.vpls, "frame {f}");
        assert_eq!(bits(&s), bits(&first), "frame {f}");
        assert_eq!(s.replaced, 0.0);
    }
    let light = builtin::load("cornell-light").unwrap().unwrap();
    let mut rm = Sampler::new(params(SamplerKind::Rmsmc, 41));
    let (mut rates, mut replaced) = (Vec::new(), Vec::new());
    for f in 0..6 {
        let fr = light.at(f as f32 / 8.0);
        let s = rm.select(&fr, &Tracer::new(&fr), f);
        rates.push(s.renewal_rate.unwrap());
        replaced.push(s.replaced);
    }
    println!("rmsmc under a moving light: rates {rates:?}, replaced {replaced:?}");
    assert!(rates[1..].iter().all(|&r| r > 0.2), "rates {rates:?}");
    assert!(
        replaced[1..].iter().all(|&r| r > 0.1),
        "replaced {replaced:?}"
    );
}

/// `rmsmc` under a moving light: in the last frame of 12 of the light's slide, its estimate
/// averages to uniform's, per image quadrant and over the whole image, over 400 seeds; and its
/// spread over the seeds is below that of `smc`'s fixed-weight particles (never reweighted,
/// renewing a twentieth of the slots a frame), whose weights went stale as the light moved.
/// With the stale weight put into rmsmc (each particle's SMC weight kept from frame to frame
/// instead of updated by the target's ratio at its re-traced path) quadrant 1 measured z = 4.14
/// and the test fails. Moves at --rmsmc-follow 10 (the tests' knobs); at the default 2, with
/// these 32 slots, the self-normalized estimate measured +8% in quadrant 3 (z = 4.19): a bias
/// of order 1 / N (docs/math.md, section 7, "rmsmc").
#[test]
fn rmsmc_averages_to_the_uniform_estimate_under_a_moving_light_with_less_spread_than_smc() {
    let scene = builtin::load("cornell-light").unwrap().unwrap();
    let steps = 12u64;
    let time = |f: u64| f as f32 * 0.125;
    let last = scene.at(time(steps));
    let last_tracer = Tracer::new(&last);
    let image = quadrant_image(&last, &last_tracer);
    let frames: Vec<(irad::scene::Frame, Tracer)> = (0..steps)
        .map(|f| {
            let fr = scene.at(time(f));
            let tr = Tracer::new(&fr);
            (fr, tr)
        })
        .collect();
    let seeds = 400u64;
    let (mut rm, mut smc, mut uniform) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..seeds {
        for (kind, out) in [(SamplerKind::Rmsmc, &mut rm), (SamplerKind::Smc, &mut smc)] {
            let mut s = Sampler::new(params(kind, 3000 + seed));
            for (f, (fr, tr)) in frames.iter().enumerate() {
                s.select(fr, tr, f as u64);
            }
            out.push(image(&s.select(&last, &last_tracer, steps)));
        }
        let mut u = Sampler::new(SamplerParams {
            slots: 256,
            ..params(SamplerKind::Uniform, 3000 + seed)
        });
        uniform.push(image(&u.select(&last, &last_tracer, steps)));
    }
    let n = seeds as usize;
    let (rm_q, uniform_q) = (stats(&rm, n), stats(&uniform, n));
    for k in 0..4 {
        rm_q.assert_matches("rmsmc", &uniform_q, k);
    }
    let ((mr, sr), (ms, ss), (mu, su)) =
        (whole_image(&rm), whole_image(&smc), whole_image(&uniform));
    let se = |s: f64| s / (n as f64).sqrt();
    let z = (mr - mu).abs() / (se(sr).powi(2) + se(su).powi(2)).sqrt();
    println!(
        "image, mean +- sd over {n} seeds: rmsmc {mr:.5} +- {sr:.5}, smc {ms:.5} +- {ss:.5}, \
         uniform (256 slots) {mu:.5} +- {su:.5}; rmsmc z = {z:.2}, sd rmsmc / smc {:.3}",
        sr / ss
    );
    // Measured: z = 1.99 (+2%), sd 0.69 of smc's (at N = 128 and follow 2, 0.62).
    assert!(z < 4.0, "image: rmsmc {mr} vs uniform {mu} (z = {z})");
    assert!(sr < 0.8 * ss, "rmsmc's spread {sr} against smc's {ss}");
}

/// `rmsmc` at its default knobs (no move where nothing moves, follow 2, resampling below half
/// the slots) on a fixed frame: over independent seeds its estimate in frame 3 (frame 0's, kept)
/// averages to uniform's, per image quadrant.
#[test]
fn rmsmc_at_its_defaults_averages_to_the_uniform_estimate_on_a_fixed_frame() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let image = quadrant_image(&frame, &tracer);
    let defaults = SamplerKnobs::default();
    let seeds = 300u64;
    let (mut rm, mut uniform) = (Vec::new(), Vec::new());
    for seed in 0..seeds {
        let mut s = Sampler::new(knobbed(params(SamplerKind::Rmsmc, 5000 + seed), |k| {
            k.rmsmc_rate = defaults.rmsmc_rate;
            k.rmsmc_follow = defaults.rmsmc_follow;
            k.rmsmc_ess = defaults.rmsmc_ess;
        }));
        let mut last = None;
        for f in 0..4 {
            last = Some(s.select(&frame, &tracer, f));
        }
        rm.push(image(&last.unwrap()));
        let mut u = Sampler::new(params(SamplerKind::Uniform, 5000 + seed));
        uniform.push(image(&u.select(&frame, &tracer, 3)));
    }
    let (rm, uniform) = (stats(&rm, seeds as usize), stats(&uniform, seeds as usize));
    for k in 0..4 {
        rm.assert_matches("rmsmc (defaults)", &uniform, k);
    }
}
