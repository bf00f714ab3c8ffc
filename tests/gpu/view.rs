//! `irad view`'s update step driven without a window (the app's state and frames), on the
//! backend under test: load, orbit, switch sampler, split view, save a frame, and the saved
//! frame against `irad render`'s pipeline built from the printed command line.

use crate::common;
use clap::Parser as _;
use irad::config::{Size, DEFAULT_STILL_SCENE};
use irad::frame::SamplerKind;
use irad::image::Hdr;
use irad::view::app::{App, Input, Start};
use std::sync::Arc;

fn start() -> Start {
    let mut render = common::render_config();
    render.backend = common::backend();
    render.sequence.scene = Some(DEFAULT_STILL_SCENE.into());
    render.sequence.size = Size {
        width: 40,
        height: 32,
    };
    render.vpls = 32;
    render.quality.aa = 1;
    render.sampler.kind = SamplerKind::Cdf;
    render.out = common::fresh_dir("view_update_step");
    Start {
        render,
        split: None,
        fixed_size: true,
    }
}

fn diff(a: &Hdr, b: &Hdr) -> f32 {
    common::rel_diff(a, b)
}

/// The whole session of the test, step by step.
#[test]
fn the_update_step_orbits_switches_splits_and_saves() {
    let t0 = std::time::Instant::now();
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &start()).unwrap();
    // Load: two frames of the still scene; the second has a flicker number (nothing moved).
    app.step().unwrap();
    app.step().unwrap();
    let h = &app.halves[0];
    assert_eq!(h.sampler, SamplerKind::Cdf);
    let first = h.output.as_ref().unwrap().image.hdr.clone();
    assert!(common::mean_lum(&first) > 0.01, "a lit Cornell box");
    let f1 = h.flicker.f1.expect("a still frame has a flicker number");
    assert!(f1 > 0.0, "cdf draws fresh VPLs every frame: {f1}");

    // Orbit 30 degrees to the right: the eye turns about the target at the same distance.
    let before = app.current_camera();
    app.apply(Input::Orbit {
        yaw: 30.0,
        pitch: 0.0,
    })
    .unwrap();
    let after = app.camera.unwrap();
    assert_eq!(after.target, before.target);
    let (d0, d1) = (before.eye - before.target, after.eye - after.target);
    assert!((d0.length() - d1.length()).abs() < 1e-4 * d0.length());
    let turned = d0.x.atan2(d0.z) - d1.x.atan2(d1.z);
    assert!(
        (turned.to_degrees().abs() - 30.0).abs() < 0.01,
        "{}",
        turned.to_degrees()
    );
    app.step().unwrap();
    let orbited = app.halves[0].output.as_ref().unwrap();
    assert!(diff(&orbited.image.hdr, &first) > 0.1, "the view turned");
    assert_eq!(
        app.halves[0].flicker.f1, None,
        "the view moved: no flicker number"
    );

    // Switch the sampler: the half is rebuilt with it.
    app.apply(Input::Sampler(SamplerKind::Uniform)).unwrap();
    app.step().unwrap();
    assert_eq!(app.samplers(), [SamplerKind::Uniform]);

    // Split view: uniform on the left, mh on the right, the same camera.
    app.apply(Input::Split(Some(SamplerKind::Mh))).unwrap();
    app.step().unwrap();
    app.step().unwrap();
    assert_eq!(app.samplers(), [SamplerKind::Uniform, SamplerKind::Mh]);
    let (l, r) = (
        app.halves[0].output.as_ref().unwrap(),
        app.halves[1].output.as_ref().unwrap(),
    );
    let d = diff(&l.image.hdr, &r.image.hdr);
    assert!(d > 0.0 && d < 0.3, "two samplers of the same view: {d}");
    for h in &app.halves {
        assert!(h.flicker.f1.is_some(), "{:?}", h.sampler);
    }
    // The heat map shows where the indirect light changed: not all black, not all white.
    app.apply(Input::Heat(true)).unwrap();
    let (w, h, heat) = app.shown(0).unwrap();
    assert_eq!(heat.len(), (w * h * 3) as usize);
    let lit = heat.iter().filter(|&&b| b > 0).count();
    assert!(lit > 0 && lit < heat.len(), "{lit} of {}", heat.len());
    app.apply(Input::Heat(false)).unwrap();
    assert_eq!(
        app.shown(0).unwrap().2,
        app.halves[0].output.as_ref().unwrap().image.ldr
    );

    // Save the frame: an EXR and a PNG per half, the EXR the frame shown.
    app.apply(Input::SaveFrame).unwrap();
    assert_eq!(app.saved.len(), 4, "{:?}", app.saved);
    let exr = Hdr::read(&app.saved[0]).unwrap();
    assert_eq!(exr, app.halves[0].output.as_ref().unwrap().image.hdr);
    let png = image::open(&app.saved[1]).unwrap();
    assert_eq!((png.width(), png.height()), (40, 32));

    // The printed command line gives the same settings and camera back, and `irad render`
    // of it renders the saved frame (uniform keeps no state between frames; the still scene's
    // frame is the index shown).
    app.apply(Input::CopyView).unwrap();
    let (spec, line) = app.message.split_once('\n').unwrap();
    assert!(
        spec.starts_with("--camera ") && line.contains(spec),
        "{}",
        app.message
    );
    let line = line.to_string();
    let args: Vec<&str> = line.split_whitespace().collect();
    let irad::cli::Command::Render(mut r) = irad::cli::Cli::try_parse_from(&args).unwrap().command
    else {
        panic!("{line}")
    };
    assert_eq!(r.sampler.kind, SamplerKind::Uniform, "{line}");
    assert_eq!(
        (r.vpls, r.sequence.size),
        (32, app.cfg.sequence.size),
        "{line}"
    );
    let index = app.halves[0].output.as_ref().unwrap().index;
    assert!(line.contains(&format!("--frames {index} ")), "{line}");
    r.out = app.cfg.out.join("render");
    irad::commands::render::render(&r).unwrap();
    let again = Hdr::read(&r.out.join(format!("frame_{index:04}.exr"))).unwrap();
    let c = common::compare(
        "view_update_step",
        "command_line",
        &again,
        &exr,
        // The camera printed to 4 decimals: a pixel's edge here and there.
        0.01,
    );
    assert!(c.rel < 0.01, "{line}: {}{}", c.rel, c.images);
    println!("{line}\n{:.1} s", t0.elapsed().as_secs_f64());
}

/// Time: playing advances one frame a step, in step with the frame index (the command line's
/// `--frames` is the index shown); scrubbing and pausing hold the time while the index goes
/// on (`--frames` is then the time's frame), and the still frames get a flicker number.
#[test]
fn the_time_plays_scrubs_and_pauses() {
    let t0 = std::time::Instant::now();
    let mut s = start();
    s.render.sequence.scene = Some("cornell-orbit".into());
    s.render.sequence.size = Size {
        width: 24,
        height: 24,
    };
    s.render.vpls = 8;
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &s).unwrap();
    assert!(app.duration() > 1.0, "an animated scene");
    let fps = app.cfg.sequence.fps;
    app.apply(Input::Play(true)).unwrap();
    app.step().unwrap();
    app.step().unwrap();
    assert!((app.time - 2.0 / fps).abs() < 1e-6, "{}", app.time);
    assert_eq!(app.render_frame(), 1, "playing from 0: the index shown");
    assert_eq!(app.halves[0].flicker.f1, None, "the scene moved");
    app.apply(Input::Play(false)).unwrap();
    app.apply(Input::Scrub(1.0)).unwrap();
    app.step().unwrap();
    app.step().unwrap();
    assert_eq!(app.time, 1.0);
    assert_eq!(app.index, 4);
    assert_eq!(
        app.render_frame(),
        fps.round() as u32,
        "the frame of time 1 s"
    );
    assert!(app.halves[0].flicker.f1.is_some(), "paused: a still frame");
    // Past the end: kept within the animation.
    app.apply(Input::Scrub(1e6)).unwrap();
    assert_eq!(app.time, app.duration());
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}
