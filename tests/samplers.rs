//! The samplers' estimators on a fixed frame (CPU twin, exact visibility): `cdf`, `rejection`
//! and `mh` must average to what `uniform` averages to, `mh` must keep most of its VPLs from
//! frame to frame, and `frozen` must keep its light paths.

use glam::Vec3;
use irad::math::luminance;
use irad::reference::twin;
use irad::scene::builtin;
use irad::trace::Tracer;
use irad::vpl::sampler::{Sampler, SamplerKind, SamplerParams};

const W: u32 = 12;
const H: u32 = 12;
const DMIN: f32 = 0.1;

fn params(kind: SamplerKind, seed: u64) -> SamplerParams {
    SamplerParams {
        kind,
        slots: 32,
        candidates: 128,
        camera_points: 64,
        eps: 0.05,
        mh_rate: 1.0,
        mh_escape: 0,
        dmin: DMIN,
        seed,
        width: W,
        height: H,
    }
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

struct Estimates {
    mean: [f64; 4],
    se: [f64; 4],
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
    let points = twin::pixel_points(&frame, &tracer, W, H);
    let mut s = Sampler::new(p);
    (0..frames)
        .filter_map(|f| {
            let sel = s.select(&frame, &tracer, f);
            (f >= skip).then(|| {
                quadrants(&twin::gather(
                    &frame,
                    &tracer,
                    &points,
                    W,
                    H,
                    &sel.shaded,
                    DMIN,
                ))
            })
        })
        .collect()
}

/// On a fixed frame, the averages of many cdf and rejection estimates, and of mh's chain steps
/// (after burn-in) over many seeds, equal the uniform estimator's, per image quadrant, within 4
/// standard errors. mh's candidates are one fixed set of paths per seed, so its chains average
/// to that set's estimate: the standard error comes from the spread over seeds.
#[test]
fn cdf_and_mh_average_to_the_uniform_estimate() {
    let uniform = stats(&run(SamplerKind::Uniform, 240, 0), 240);
    let cdf = stats(&run(SamplerKind::Cdf, 240, 0), 240);
    let rejection = stats(&run(SamplerKind::Rejection, 240, 0), 240);
    // Per seed, the mean of frames 5..20.
    let over_seeds = |escape: u32, first: u64| {
        let means: Vec<[f64; 4]> = (first..first + 80)
            .map(|seed| {
                let p = SamplerParams {
                    mh_escape: escape,
                    ..params(SamplerKind::Mh, seed)
                };
                stats(&run_with(p, 20, 5), 1).mean
            })
            .collect();
        stats(&means, means.len())
    };
    let mh = over_seeds(0, 100);
    let escape = over_seeds(8, 300);
    for k in 0..4 {
        for (name, e) in [
            ("cdf", &cdf),
            ("rejection", &rejection),
            ("mh", &mh),
            ("mh escape 8", &escape),
        ] {
            let z = (e.mean[k] - uniform.mean[k]).abs()
                / (e.se[k].powi(2) + uniform.se[k].powi(2)).sqrt();
            println!(
                "quadrant {k}: {name} {:.5} +- {:.5}, uniform {:.5} +- {:.5}, z = {z:.2}",
                e.mean[k], e.se[k], uniform.mean[k], uniform.se[k]
            );
            // Measured: z at most 1.51 (mh escape 8, quadrant 3), 0.94 for cdf. The bound is
            // statistical (|z| > 4 happens with probability 6e-5), not fitted to these values.
            assert!(
                z < 4.0,
                "{name} quadrant {k}: {} vs uniform {} (z = {z})",
                e.mean[k],
                uniform.mean[k]
            );
        }
        // The test has the power to see a wrong weight: one 30% too low (leaving out M/P
        // would be a factor of about 2.4) falls far outside the bound.
        for e in [&cdf, &rejection, &mh] {
            let wrong = e.mean[k] * 0.7;
            assert!(
                (wrong - uniform.mean[k]).abs()
                    > 4.0 * (e.se[k].powi(2) + uniform.se[k].powi(2)).sqrt()
            );
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
    let lazy = mean_replaced(SamplerParams {
        mh_rate: 0.2,
        ..params(SamplerKind::Mh, 3)
    });
    println!("replaced per frame: cdf {cdf:.4}, mh {mh:.4}, mh at rate 0.2 {lazy:.4}");
    // Measured (mh on its fixed candidate set): cdf 1.0000, mh 0.7037, mh at rate 0.2 0.1121.
    assert!(cdf > 0.95, "cdf replaced {cdf}");
    assert!(mh < 0.8 && mh > 0.47, "mh replaced {mh}");
    assert!(lazy < 0.16, "mh at rate 0.2 replaced {lazy}");
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
    for kind in [
        SamplerKind::Uniform,
        SamplerKind::Cdf,
        SamplerKind::Mh,
        SamplerKind::Frozen,
        SamplerKind::Rejection,
    ] {
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

/// mh in a still scene: b is bitwise the same every frame and a kept chain's VPL keeps its
/// weight bitwise (its candidates are the same paths every frame), so only replaced slots
/// change the image.
#[test]
fn mh_kept_weights_do_not_move_in_a_still_scene() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let mut s = Sampler::new(params(SamplerKind::Mh, 6));
    let first = s.select(&frame, &tracer, 0);
    let mut prev = first.clone();
    let mut kept = 0;
    for f in 1..10 {
        let sel = s.select(&frame, &tracer, f);
        assert_eq!(sel.b, first.b, "frame {f}");
        for k in 0..sel.vpls.len() {
            let same =
                |a: &irad::vpl::Vpl, b: &irad::vpl::Vpl| (a.path, a.depth) == (b.path, b.depth);
            if same(&sel.vpls[k], &prev.vpls[k]) {
                assert_eq!(sel.shaded[k], prev.shaded[k], "frame {f} slot {k}");
                kept += 1;
            }
        }
        prev = sel;
    }
    assert!(kept > 9 * 32 / 5, "kept {kept}");
}
