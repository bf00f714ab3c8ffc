//! The clamping-bias compensation (`src/compensation`) held to an exact answer with exact
//! visibility (no ISMs): in the white furnace (albedo 0.5, every wall emits 1) the light
//! reflected everywhere is exactly 1. With a clamp, a frame's estimate of it (emitter
//! samples and VPLs, both clamped as the GPU clamps them with `--compensate`) falls short at
//! the box's edges and corners; the compensation's paths must give back the rest, and its
//! later bounces (the light the clamp took from the surfaces the rays land on) must count.

use irad::compensation::{path, Light, Nearby, MAX_BOUNCES};
use irad::math::luminance;
use irad::reference::twin;
use irad::scene::SampleKind;
use irad::vpl::ShadedVpl;
use rand::Rng;
use std::f32::consts::PI;

#[test]
fn clamped_light_plus_compensation_is_the_furnace_s_exact_light() {
    let scene = irad::scene::builtin::load("furnace").unwrap().unwrap();
    let f = scene.at(0.0);
    let t = irad::trace::Tracer::new(&f);
    let n = 4000u64;
    let vpls: Vec<ShadedVpl> = irad::vpl::trace_paths(&f, &t, 3, 0, n)
        .iter()
        .map(|v| ShadedVpl {
            position: v.position,
            normal: v.normal,
            flux: v.power * v.albedo / n as f32,
            near: v.near,
        })
        .collect();
    let samples = f.emitter_samples(3, 1024);
    // A clamp of 0.4 (the box is 2 wide): a wide band along every edge falls short.
    let clamp = 0.4;
    let light = Light {
        samples: &samples,
        vpls: &vpls,
        clamp,
    };
    let nearby = Nearby::new(&vpls, &t);
    let (w, h) = (24, 24);
    let points = twin::pixel_points(&f, &t, w, h);
    let indirect = twin::gather(&f, &t, &points, w, h, &vpls, clamp);
    let mut r = irad::math::rng(&[7]);
    // Over the pixels within the clamp of another wall: the frame's clamped estimate, with
    // the first-order compensation, with the full one.
    let (mut sums, mut pixels) = ([0.0f64; 3], 0);
    for (i, s) in points.iter().enumerate() {
        let Some(s) = s else { continue };
        let direct: f32 = samples
            .iter()
            .filter_map(|l| {
                let (e, p, np) = l.irradiance_at(s.x, s.n)?;
                assert_eq!(l.kind, SampleKind::Area);
                let near = ((s.x - p).length_squared() / (clamp * clamp)).min(1.0);
                (!t.occluded(s.x, s.n, p, np)).then_some(luminance(e) * near * 0.5 / PI)
            })
            .sum();
        let paths = 256;
        let mut c = [0.0f64; 2];
        for _ in 0..paths {
            let u = glam::Vec2::new(r.random(), r.random());
            for (k, bounces) in [1, MAX_BOUNCES].into_iter().enumerate() {
                c[k] += luminance(path(&f, &t, s, (&light, &nearby), (u, bounces), &mut r)) as f64;
            }
        }
        if c[1] == 0.0 {
            continue;
        }
        pixels += 1;
        let frame = (direct + luminance(indirect.data[i])) as f64;
        sums[0] += frame;
        sums[1] += frame + c[0] / paths as f64;
        sums[2] += frame + c[1] / paths as f64;
    }
    let mean = sums.map(|s| s / pixels as f64);
    println!(
        "{pixels} pixels near an edge: reflected light {:.4} clamped, {:.4} with the first \
         bounce of the compensation, {:.4} with all (exact: 1)",
        mean[0], mean[1], mean[2]
    );
    // Measured: 291 pixels, 0.9397 clamped, 0.9926 first bounce, 0.9991 all.
    assert!(pixels > 200 && mean[0] < 0.96, "{pixels} pixels, {mean:?}");
    assert!((mean[2] - 1.0).abs() < 0.003, "compensated {:.4}", mean[2]);
    assert!(mean[1] < 0.996, "the first bounce alone {:.4}", mean[1]);
}

/// No built-in scene gets the note of `frame::Pipeline::new` about emitters' light within the
/// clamp (their lamps face open rooms; the furnace's walls emit, and only their edges' light
/// meets another wall that near).
#[test]
fn no_built_in_scene_is_told_to_compensate() {
    for name in irad::scene::builtin::BUILTINS.iter().map(|b| b.name) {
        let scene = irad::scene::builtin::load(name).unwrap().unwrap();
        let f = scene.at(0.0);
        let t = irad::trace::Tracer::new(&f);
        let cfg = irad::config::Render::default();
        let clamp = irad::resolve::sampler_params(&cfg, &f, &t).clamp;
        let share = irad::compensation::near_field_share(&f, &t, clamp);
        println!("{name}: clamp {clamp:.4}, near field {share:.3}");
        assert!(share < irad::resolve::NEAR_FIELD_SHARE, "{name}: {share}");
    }
}
