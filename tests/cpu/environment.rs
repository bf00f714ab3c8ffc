//! Issue 23 item 4, the path tracer and the light paths under an environment, against
//! analytic answers: a diffuse plane of albedo `a` open to the environment has radiance
//! `a / pi` times its irradiance, `a L` under a uniform sky of radiance `L`; and the light
//! paths bring it the power the environment sends through it (docs/math.md, "The
//! environment").

use crate::common::quads::{self, Quads};
use glam::Vec3;
use irad::scene::{Environment, Scene};
use serde_json::json;
use std::f32::consts::PI;
use std::sync::Arc;

/// A 20 x 20 plane at y = 0 of albedo `a` (double-sided) seen straight down from 2 above
/// through a narrow lens (every pixel sees it), under `env`.
fn plane(a: f32, env: Environment) -> Scene {
    let mut q = Quads::default();
    let m = q.material(a, 0.0, true);
    q.quad([0.; 3], [0., 0., 10.], [10., 0., 0.], m, json!({}));
    let mut s = quads::load(&q.finish());
    s.set_camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, 0.5)
        .unwrap();
    s.environment = Some(Arc::new(env));
    s
}

fn reference_mean(scene: &Scene, spp: u32) -> Vec3 {
    let f = scene.at(0.0);
    let t = irad::trace::Tracer::new(&f);
    let s = irad::reference::ReferenceSettings {
        width: 16,
        height: 16,
        spp,
        seed: 3,
        ..Default::default()
    };
    irad::reference::render(&f, &t, &s, &|| {}).mean()
}

/// Furnace-like: under the uniform sky (radiance 1), albedo 0.6 gives 0.6 in every pixel.
#[test]
fn a_plane_under_the_sky_has_radiance_albedo_times_sky() {
    let scene = plane(0.6, Environment::sky());
    let m = reference_mean(&scene, 256);
    println!("plane under the sky: mean {m} (expected 0.6)");
    // Measured: within 0.0004 of 0.6 (65536 paths).
    assert!((m - Vec3::splat(0.6)).abs().max_element() < 0.003, "{m}");
}

/// Under an equirectangular map, next-event estimation (importance-sampled by the map) and
/// the cosine-sampled rays that reach the map (weighed against it by MIS) sum to
/// `a / pi * integral of L cos` over the upper hemisphere, integrated here texel by texel in
/// closed form.
#[test]
fn a_plane_under_a_map_has_radiance_albedo_times_irradiance_over_pi() {
    let (w, h) = (32u32, 16u32);
    let texels: Vec<Vec3> = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            if i == 9 && j == 2 {
                Vec3::new(80.0, 60.0, 40.0)
            } else {
                Vec3::new(0.2 + 0.05 * (i % 5) as f32, 0.4, 0.3 + 0.1 * (j % 3) as f32)
            }
        })
        .collect();
    let env = Environment::from_texels("test".into(), w, h, texels.clone()).unwrap();
    // Irradiance on the up-facing plane: texel (i, j) in the upper half covers
    // theta in [pi j/h, pi (j+1)/h]; the integral of cos over it is
    // (2 pi / w) (sin^2 theta1 - sin^2 theta0) / 2.
    let mut e = Vec3::ZERO;
    for j in 0..h / 2 {
        let (t0, t1) = (PI * j as f32 / h as f32, PI * (j + 1) as f32 / h as f32);
        let c = 2.0 * PI / w as f32 * (t1.sin().powi(2) - t0.sin().powi(2)) / 2.0;
        for i in 0..w {
            e += texels[(j * w + i) as usize] * c;
        }
    }
    let a = 0.5;
    let expected = e * a / PI;
    let m = reference_mean(&plane(a, env), 256);
    let err = ((m - expected) / expected).abs().max_element();
    println!("plane under a map: mean {m}, expected {expected}: relative error {err:.5}");
    // Measured 0.0024 (65536 paths).
    assert!(err < 0.006, "{m} vs {expected}");
}

/// The light paths from the sky bring a double-sided plane of area A the power
/// `2 pi L A` (pi L A on each side): the mean reflected power of their first vertices over
/// the albedo.
#[test]
fn light_paths_from_the_sky_carry_the_power_it_sends() {
    let scene = plane(0.5, Environment::sky());
    let f = scene.at(0.0);
    let t = irad::trace::Tracer::new(&f);
    let n = 100_000u64;
    let vpls = irad::vpl::trace_paths(&f, &t, 5, 0, n);
    let mut per_path = vec![0.0f64; n as usize];
    for v in vpls.iter().filter(|v| v.depth == 1) {
        per_path[v.path as usize] += irad::math::luminance(v.power) as f64;
    }
    let mean = per_path.iter().sum::<f64>() / n as f64;
    let var = per_path.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let se = (var / n as f64).sqrt();
    let expected = 2.0 * std::f64::consts::PI * 400.0;
    println!("first-vertex power {mean:.1} +- {se:.1}, expected {expected:.1}");
    // Measured 2525.9 +- 11.6.
    assert!(
        (mean - expected).abs() < 4.0 * se,
        "{mean} +- {se} vs {expected}"
    );
    assert!(se < 0.01 * expected);
}

/// The environment gets its share of the emitter samples beside emitter triangles (half of
/// what the punctual lights leave), and a sample count that cannot give each kind of light
/// one is refused, naming `light_samples`.
#[test]
fn the_environment_shares_the_emitter_samples() {
    use irad::scene::SampleKind;
    let mut scene = irad::scene::builtin::load("cornell").unwrap().unwrap();
    scene.environment = Some(Arc::new(Environment::sky()));
    let f = scene.at(0.0);
    let count = |n: usize| {
        let s = f.emitter_samples(1, n);
        let env = s
            .iter()
            .filter(|l| matches!(l.kind, SampleKind::Environment { .. }))
            .count();
        let area = s.iter().filter(|l| l.kind == SampleKind::Area).count();
        (env, area)
    };
    assert_eq!(count(2), (1, 1));
    assert_eq!(count(9), (4, 5));
    // Beside a point light (two slots, back to back), two samples leave one to the
    // environment: half the light, doubled.
    let mut q = Quads::default();
    let m = q.material(0.5, 0.0, true);
    q.quad([0.; 3], [0., 0., 2.], [2., 0., 0.], m, json!({}));
    let mut doc = q.finish();
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] =
        json!({ "KHR_lights_punctual": { "lights": [{ "type": "point", "intensity": 683.0 }] } });
    doc["nodes"].as_array_mut().unwrap().push(
        json!({ "translation": [0., 1., 0.], "extensions": { "KHR_lights_punctual": { "light": 0 } } }),
    );
    doc["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(1));
    let mut lamp = quads::load(&doc);
    lamp.environment = Some(Arc::new(Environment::sky()));
    let kinds: Vec<SampleKind> = lamp
        .at(0.0)
        .emitter_samples(1, 2)
        .iter()
        .map(|l| l.kind)
        .collect();
    assert!(
        kinds.len() == 2
            && kinds[0] == SampleKind::PointHalf
            && matches!(kinds[1], SampleKind::Environment { .. }),
        "{kinds:?}"
    );
    let mut cfg = irad::config::Render::default();
    cfg.quality.light_samples = 1;
    let t = irad::trace::Tracer::new(&f);
    let e = irad::resolve::resolve(&cfg, &scene, &f, &t, &Default::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "`light_samples` 1: scene 'cornell' has emitting triangles and an environment, which need at least 2 samples (one for each)"
    );
}
