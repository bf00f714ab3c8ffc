//! The light-path coin of `vpl::crevice`, between two parallel plates: a vertex whose lobe
//! gets out of its neighbourhood keeps its light on average, whatever the gap.

use crate::common::quads::{load, Quads};
use irad::trace::Tracer;
use irad::vpl::crevice::{coin, FAR, NEAR_KEEP, RAYS, REACH};
use serde_json::json;

/// Two 2 x 2 plates facing each other `gap` apart (the lower at y = 0, facing up).
fn plates(gap: f32) -> irad::scene::Scene {
    let mut q = Quads::default();
    let grey = q.material(0.5, 0.0, true);
    let (u, v) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
    q.quad([0.0, 0.0, 0.0], v, u, grey, json!({}));
    q.quad([0.0, gap, 0.0], u, v, grey, json!({}));
    load(&q.finish())
}

/// At the middle of the lower plate, a ray gets out of the neighbourhood (`REACH` of the
/// scene's size) when `gap / cos(theta) > reach` (the gap less the ray's offset): for
/// cosine-distributed rays, a share `f = (gap / reach)^2` of the lobe. The coin's `RAYS` rays are stratified on a `side x side`
/// grid of the square that `math::cosine_hemisphere` maps (`cos(theta) = sqrt(1 - u.x)`), so
/// only the last column's `side` rays can get out, each with probability `side * f`: the
/// vertex has a ray out with probability `1 - (1 - side f)^side`, and as it is then kept
/// with probability p and weighted 1 / p, that is its light kept on average. Sweeping the
/// gap from the reach down to 1/32 of it, the mean over 20000 coins is that within four
/// standard errors, and no VPL is weighted more than 4-fold. With the 16 rays (a 4 x 4 grid) a
/// vertex a quarter of the reach from the other plate, as in the 1 cm gap of the 2 m sweep
/// room, keeps two thirds of its light on average (docs/math.md, "Inside the 1 cm gap").
/// A kept vertex with a ray out whose rays all end within [`FAR`] reaches is read by the
/// compensation alone, within that distance: between plates a quarter of the reach apart, only
/// a ray within 1/16 of grazing gets that far, so most of them are (at least 85%); a reach apart,
/// every vertex has a quarter of its rays out and is the GPU's.
#[test]
fn a_vertex_between_plates_keeps_its_light_on_average() {
    let side = (RAYS as f64).sqrt();
    assert_eq!(side * side, RAYS as f64, "RAYS is a square");
    for a in [1.0f32, 0.5, 0.25, 0.125, 1.0 / 16.0, 1.0 / 32.0] {
        let scene = plates(0.04 * a);
        let frame = scene.at(0.0);
        let tracer = Tracer::new(&frame);
        let reach = REACH * tracer.size();
        assert!((reach - 0.04).abs() < 1e-6, "reach {reach}");
        let gap = reach * a;
        // The rays leave from the point offset by the tracer's epsilon toward the other plate.
        let f = (((gap - tracer.epsilon_at(glam::Vec3::ZERO)) / reach) as f64).powi(2);
        let gathered = 1.0 - (1.0 - side * f).max(0.0).powf(side);
        let n = 20000u64;
        let coins: Vec<Option<(f32, Option<f32>)>> = (0..n)
            .map(|path| {
                let x = glam::Vec3::new(0.0137, 0.0, -0.0291);
                coin(&tracer, x, glam::Vec3::Y, (7, path, 1)).kept
            })
            .collect();
        // Kept with no ray out: read within the reach, and kept with probability NEAR_KEEP
        // (a vertex with a ray out is kept with probability 1/4 or more).
        let closed = |p: f32, near: Option<f32>| {
            let c = p == NEAR_KEEP;
            assert_eq!(near, c.then_some(reach).or(near.filter(|_| !c)));
            c
        };
        // A kept vertex with a ray out but fewer than a quarter: the compensation's alone
        // within FAR reaches, or the GPU's.
        let partly: Vec<Option<f32>> = coins
            .iter()
            .flatten()
            .filter(|(p, near)| *p < 1.0 && !closed(*p, *near))
            .map(|(_, near)| *near)
            .collect();
        let local = partly.iter().filter(|n| **n == Some(FAR * reach)).count();
        assert_eq!(
            local + partly.iter().filter(|n| n.is_none()).count(),
            partly.len()
        );
        let local = local as f64 / partly.len().max(1) as f64;
        println!(
            "gap {gap:.5} m: {} of the kept vertices had a ray out but fewer than a quarter, {local:.3} of them read by the compensation alone",
            partly.len()
        );
        if a == 0.25 {
            assert!(local >= 0.85, "{local}");
        }
        if a == 1.0 {
            assert!(partly.is_empty());
        }
        // The light kept from vertices with a ray out (the GPU's VPLs, and those read by the
        // compensation within FAR reaches), and from those with none.
        for (near, expected) in [(false, gathered), (true, 1.0 - gathered)] {
            let weights: Vec<f64> = coins
                .iter()
                .map(|c| match c {
                    Some((p, v)) if closed(*p, *v) == near => 1.0 / *p as f64,
                    _ => 0.0,
                })
                .collect();
            let mean = weights.iter().sum::<f64>() / n as f64;
            let var = weights.iter().map(|w| (w - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            let se = (var / n as f64).sqrt();
            let largest = weights.iter().cloned().fold(0.0, f64::max);
            println!(
                "gap {gap:.5} m (reach / {:.0}), near {near}: light kept {mean:.4} +- {se:.4}, expected {expected:.4}, largest weight {largest}",
                1.0 / a
            );
            assert!(
                (mean - expected).abs() <= 4.0 * se + 1e-3,
                "gap {gap} m, near {near}: the coin keeps {mean:.4} +- {se:.4} of the light, expected {expected:.4}"
            );
            let bound = if near { 1.0 / NEAR_KEEP as f64 } else { 4.0 };
            assert!(
                largest <= bound,
                "gap {gap} m, near {near}: a weight of {largest}"
            );
        }
    }
}

/// Two albedo-1 plates 2 m across, 1 mm apart (y = 0 and 0.001), and a 10 cm lamp between
/// them facing down: a scene that is all crevice.
fn all_crevice() -> Quads {
    let mut q = Quads::default();
    let white = q.material(1.0, 0.0, true);
    let lamp = q.material(1.0, 10.0, false);
    let (u, v) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
    q.quad([0.0, 0.0, 0.0], v, u, white, json!({}));
    q.quad([0.0, 0.001, 0.0], u, v, white, json!({}));
    q.quad(
        [0.0, 0.0002, 0.0],
        [0.05, 0.0, 0.0],
        [0.0, 0.0, -0.05],
        lamp,
        json!({}),
    );
    q
}

/// A scene that is all crevice: two albedo-1 plates 2 m across, 1 mm apart, and a lamp
/// between them. Every light path bounces between the plates until the 16384-bounce cut (its
/// coin tossed at every 16th vertex past bounce 256, `vpl::paths::DEEP`), and every vertex is
/// the compensation's (no ray of it gets out), so its VPLs take no slot: a frame's paths stop
/// at `NEAR_SLOTS` VPLs a slot (207 paths here, 2 s), where they would otherwise go on to 64
/// paths a slot (65,536 paths of 16384 bounces).
#[test]
fn a_scene_all_crevice_stops_its_light_paths() {
    let scene = load(&all_crevice().finish());
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let mut cfg = crate::common::render_config();
    cfg.vpls = 1024;
    cfg.sampler.kind = irad::vpl::sampler::SamplerKind::Uniform;
    let params = irad::resolve::sampler_params(&cfg, &frame, &tracer);
    assert_eq!(params.slots, 1024);
    let s = irad::vpl::sampler::Sampler::new(params).select(&frame, &tracer, 0);
    let near = s.vpls.iter().filter(|v| v.near.is_some()).count();
    println!(
        "{} paths, {} VPLs, {near} of them the compensation's",
        s.paths,
        s.vpls.len()
    );
    let most = irad::vpl::sampler::NEAR_SLOTS * 1024;
    assert!(
        s.paths > 0 && near > s.vpls.len() * 9 / 10,
        "{near} of {}",
        s.vpls.len()
    );
    assert!(
        s.vpls.len() >= most && s.vpls.len() <= most + irad::vpl::paths::MAX_DEPTH as usize,
        "{} VPLs",
        s.vpls.len()
    );
}

/// A camera between the plates of a scene that is all crevice: every point it sees is sealed,
/// and every walk of the compensation (`compensation::path`) would go on for its 65536 sealed
/// bounces (a 2 m gap of 1 mm lets a walk out after about a million), 16 of them a camera ray,
/// 64 camera rays a round, 16 rounds: hours for a frame. A frame's walks are held to
/// `compensation::PILOT_WALKS` + `compensation::WALKS` sealed bounces in all, so the frame
/// ends (in seconds here) and its light is finite and not black.
#[test]
fn a_camera_inside_a_crevice_gets_its_compensation_in_bounded_time() {
    use irad::compensation::{compensate_in_rounds, Light, MAX_ROUNDS};
    let mut q = all_crevice();
    q.camera([0.0, 0.0005, 0.9], 0.5);
    let scene = load(&q.finish());
    let frame = scene.at(0.0);
    let tracer = Tracer::new(&frame);
    let vpls: Vec<irad::vpl::ShadedVpl> = irad::vpl::trace_paths(&frame, &tracer, 1, 0, 64)
        .iter()
        .map(|v| irad::vpl::ShadedVpl::new(v, 1.0 / 64.0))
        .collect();
    let samples = frame.emitter_samples(1, 256);
    let light = Light {
        samples: &samples,
        vpls: &vpls,
        clamp: 0.04,
    };
    let (w, h) = (8, 8);
    let seen = vec![glam::Vec3::ZERO; w * h];
    let t = std::time::Instant::now();
    let out = compensate_in_rounds(
        &frame,
        &tracer,
        (w as u32, h as u32),
        &light,
        (64, &seen, MAX_ROUNDS),
        1,
    );
    println!(
        "{} of {} pixels compensated in {:.1} s, mean {:.3}",
        out.len(),
        w * h,
        t.elapsed().as_secs_f64(),
        out.iter().map(|o| irad::math::luminance(o.1)).sum::<f32>() / (w * h) as f32
    );
    assert!(out.len() > w * h / 2, "{} pixels", out.len());
    assert!(out
        .iter()
        .all(|o| o.1.is_finite() && o.1.min_element() >= 0.0));
}
