//! The light-path coin of `vpl::crevice`, between two parallel plates: a vertex whose lobe
//! gets out of its neighbourhood keeps its light on average, whatever the gap.

use crate::common::quads::{load, Quads};
use irad::trace::Tracer;
use irad::vpl::crevice::{keep, NEAR_KEEP, RAYS, REACH};
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
        let f = (((gap - tracer.epsilon()) / reach) as f64).powi(2);
        let gathered = 1.0 - (1.0 - side * f).max(0.0).powf(side);
        let n = 20000u64;
        let coins: Vec<Option<(f32, bool)>> = (0..n)
            .map(|path| {
                let x = glam::Vec3::new(0.0137, 0.0, -0.0291);
                keep(&tracer, x, glam::Vec3::Y, (7, path, 1))
            })
            .collect();
        // The light kept as VPLs the GPU gathers, and as VPLs the compensation alone reads.
        for (near, expected) in [(false, gathered), (true, 1.0 - gathered)] {
            let weights: Vec<f64> = coins
                .iter()
                .map(|c| match c {
                    Some((p, v)) if *v == near => 1.0 / *p as f64,
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
