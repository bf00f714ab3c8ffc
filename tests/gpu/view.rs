//! `irad view`'s update step driven without a window (the app's state and frames), on the
//! backend under test: load, orbit, switch sampler, split view, save a frame, and the saved
//! frame against `irad render`'s pipeline built from the printed command line.

use crate::common;
use clap::Parser as _;
use irad::config::{Size, DEFAULT_STILL_SCENE};
use irad::frame::SamplerKind;
use irad::image::Hdr;
use irad::view::app::{App, Component, Input, Start, Variant};
use irad::view::overlay::{self, Overlay};
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
        refine_after: 0,
        cache: None,
        component: Component::Full,
        overlays: Default::default(),
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
    app.apply(Input::Split(Some(SamplerKind::Mh.into())))
        .unwrap();
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
    assert_eq!(
        app.clipboard.as_deref(),
        Some(app.message.as_str()),
        "C puts what it prints on the clipboard"
    );
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

/// The overlays: VPLs as points at their projected positions (green when the slot kept its
/// VPL: frozen; red when replaced: cdf), the shadow-map faces the renderer drew, the ISM atlas
/// inset, and the direct and indirect components, which add up to the frame.
#[test]
fn the_overlays_show_vpls_faces_the_atlas_and_the_components() {
    let t0 = std::time::Instant::now();
    let mut s = start();
    s.render.sampler.kind = SamplerKind::Frozen;
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &s).unwrap();
    app.step().unwrap();
    let first = app.halves[0].output.as_ref().unwrap();
    // The faces the overlay draws are those the shadow pass drew in the first frame.
    let drawn = first.image.drawn.shadow_faces;
    assert!(
        app.halves[0].kept.iter().all(|&k| !k),
        "a first frame keeps nothing"
    );
    app.step().unwrap();
    let plain = app.shown(0).unwrap();
    let (w, h) = (plain.0, plain.1);
    let changed = |a: &[u8], b: &[u8]| -> Vec<usize> {
        (0..a.len() / 3)
            .filter(|&i| a[i * 3..][..3] != b[i * 3..][..3])
            .collect()
    };

    // VPLs: frozen keeps every slot; the points are green, where the VPLs project.
    let half = &app.halves[0];
    let n = half.output.as_ref().unwrap().selection.vpls.len();
    assert!(
        half.kept.len() == n && n > 24,
        "{n} VPLs (whole paths within 32)"
    );
    assert!(half.kept.iter().all(|&k| k), "frozen keeps its VPLs");
    assert_eq!(half.output.as_ref().unwrap().selection.replaced, 0.0);
    app.apply(Input::Overlay(Overlay::Vpls, true)).unwrap();
    let with = app.shown(0).unwrap();
    let marks = app.vpl_marks(0);
    assert!(marks.len() >= 8, "{} VPLs in view", marks.len());
    let px = |img: &[u8], x: i32, y: i32| {
        let i = (y as usize * w as usize + x as usize) * 3;
        [img[i], img[i + 1], img[i + 2]]
    };
    let last = marks.last().unwrap();
    assert_eq!(
        px(&with.2, last.x, last.y),
        last.colour,
        "the heaviest VPL's point"
    );
    for m in &marks {
        assert!(m.kept && m.colour[1] > m.colour[0], "green: kept {m:?}");
    }
    let colours: Vec<[u8; 3]> = marks.iter().map(|m| m.colour).collect();
    let moved = changed(&with.2, &plain.2);
    assert!(!moved.is_empty());
    for &i in &moved {
        let (x, y) = ((i % w as usize) as i32, (i / w as usize) as i32);
        assert!(colours.contains(&px(&with.2, x, y)), "pixel {x},{y}");
        let r = overlay::mark_radius(h);
        assert!(
            marks
                .iter()
                .any(|m| (m.x - x).abs() <= r && (m.y - y).abs() <= r),
            "pixel {x},{y} is next to no VPL"
        );
    }
    // cdf draws fresh VPLs every frame: every point red.
    app.apply(Input::Sampler(SamplerKind::Cdf)).unwrap();
    app.step().unwrap();
    app.step().unwrap();
    assert!(app.halves[0].kept.iter().all(|&k| !k));
    let marks = app.vpl_marks(0);
    assert!(!marks.is_empty() && marks.iter().all(|m| !m.kept && m.colour[0] > m.colour[1]));
    app.apply(Input::Overlay(Overlay::Vpls, false)).unwrap();

    // Shadow faces: as many as the shadow pass drew in the first frame, drawn in their colours.
    assert!(drawn > 0);
    assert_eq!(app.shadow_faces(0).len() as u64, drawn);
    let plain = app.shown(0).unwrap();
    app.apply(Input::Overlay(Overlay::ShadowFaces, true))
        .unwrap();
    let with = app.shown(0).unwrap();
    let moved = changed(&with.2, &plain.2);
    assert!(moved.len() > 5, "{} pixels", moved.len());
    let front = moved
        .iter()
        .filter(|&&i| with.2[i * 3..][..3] == overlay::FACE_COLOURS[0])
        .count();
    assert!(front > 0, "the front faces' strokes");
    app.apply(Input::Overlay(Overlay::ShadowFaces, false))
        .unwrap();

    // The ISM atlas: the inset holds the atlas read back, the rest of the image is unchanged.
    app.apply(Input::Overlay(Overlay::Ism, true)).unwrap();
    let with = app.shown(0).unwrap();
    let atlas = app.ism_atlas(0).unwrap();
    let cfg = &app.cfg.quality;
    // 32 slots' tiles in rows of 6.
    assert_eq!((atlas.0, atlas.1), (6 * cfg.ism_size, 6 * cfg.ism_size));
    let holes = atlas.2.chunks(3).filter(|p| p == &[90, 0, 0]).count();
    assert!(holes * 2 < (atlas.0 * atlas.1) as usize, "{holes} holes");
    let mut expect = plain.2.clone();
    overlay::draw_inset(&mut expect, w, h, &atlas);
    assert_eq!(with.2, expect);
    let (x0, y0, iw, ih) = overlay::inset_box(w, h, atlas.0, atlas.1);
    for i in changed(&with.2, &plain.2) {
        let (x, y) = (i as u32 % w, i as u32 / w);
        assert!(x >= x0 && y >= y0 && x < x0 + iw && y < y0 + ih);
    }
    app.apply(Input::Overlay(Overlay::Ism, false)).unwrap();

    // Components: each shown tone-mapped; direct + indirect is the frame but for emission.
    let o = app.halves[0].output.as_ref().unwrap();
    let (d, ind) = (
        o.image.direct.clone().unwrap(),
        o.image.indirect.clone().unwrap(),
    );
    let full = o.image.hdr.clone();
    let ldr = o.image.ldr.clone();
    let e = app.cfg.exposure;
    app.apply(Input::Component(Component::Direct)).unwrap();
    assert_eq!(app.shown(0).unwrap().2, d.to_srgb8(e));
    app.apply(Input::Component(Component::Indirect)).unwrap();
    assert_eq!(app.shown(0).unwrap().2, ind.to_srgb8(e));
    app.apply(Input::Component(Component::Full)).unwrap();
    assert_eq!(app.shown(0).unwrap().2, ldr);
    let sum = d.zip_map(&ind, |a, b| a + b);
    let lum = irad::math::luminance;
    let mut off = 0;
    for (f, s) in full.data.iter().zip(&sum.data) {
        let (lf, ls) = (lum(*f), lum(*s));
        if (lf - ls).abs() > 1e-3 * lf.max(1e-3) {
            off += 1;
            assert!(
                lf > ls,
                "only emission is in the frame and in neither part: {lf} {ls}"
            );
        }
    }
    println!("{off} of {} pixels differ (emission)", full.data.len());
    assert!(off * 10 < full.data.len(), "{off}");
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}

/// `--split cdf,progressive`: instant radiosity with cdf on the left, progressive radiosity
/// on the right, each with its own state; the frames are saved under the two names.
#[test]
fn the_split_view_compares_a_sampler_with_a_method() {
    let t0 = std::time::Instant::now();
    let mut s = start();
    // One solve, no refinement: the test's time.
    s.render.meshing = irad::radiosity::Meshing::Uniform;
    let v = irad::view::View {
        render: s.render.clone(),
        split: vec!["cdf".into(), "progressive".into()],
        fixed_size: true,
        ..Default::default()
    };
    let mut st = v.start().unwrap();
    st.refine_after = 0;
    st.cache = None;
    assert_eq!(
        st.split,
        Some(Variant {
            method: irad::config::Method::Progressive,
            sampler: SamplerKind::Cdf
        })
    );
    let bad = irad::view::View {
        split: vec!["cdf".into(), "radiosity".into()],
        ..v.clone()
    };
    let e = format!("{:#}", bad.validate().unwrap_err());
    assert!(e.contains("`split`") && e.contains("progressive"), "{e}");
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &st).unwrap();
    app.step().unwrap();
    app.step().unwrap();
    let (l, r) = (&app.halves[0], &app.halves[1]);
    assert_eq!((l.variant.name(), r.variant.name()), ("cdf", "progressive"));
    let (lo, ro) = (l.output.as_ref().unwrap(), r.output.as_ref().unwrap());
    assert_eq!(lo.solved, None, "instant radiosity solves nothing");
    assert_eq!(
        ro.solved,
        Some(false),
        "the solution kept in the second frame"
    );
    assert!(lo.selection.vpls.len() == 32 && ro.selection.vpls.is_empty());
    let d = diff(&lo.image.hdr, &ro.image.hdr);
    assert!(d > 0.0 && d < 0.3, "two methods of the same view: {d}");
    assert!(
        r.flicker.f1.unwrap() < 1e-6,
        "a kept solution does not flicker"
    );
    assert!(l.flicker.f1.unwrap() > 0.0);
    app.apply(Input::SaveFrame).unwrap();
    let names: Vec<String> = app
        .saved
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [
            "view_0000_cdf.exr",
            "view_0000_cdf.png",
            "view_0000_progressive.exr",
            "view_0000_progressive.png"
        ]
    );
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}

/// With `irad compare`'s reference cached for the view's frames, each half shows its relMSE
/// and its flicker against it, also while the animation plays (where the frame-to-frame
/// flicker has no number); past the cached frames, none.
#[test]
fn the_flicker_against_a_cached_reference() {
    let t0 = std::time::Instant::now();
    let mut s = start();
    s.render.sequence.scene = Some("cornell-orbit".into());
    s.render.sequence.size = Size {
        width: 24,
        height: 24,
    };
    s.render.vpls = 8;
    s.render.sampler.kind = SamplerKind::Uniform;
    let root = common::fresh_dir("view_reference_cache");
    s.cache = Some(root.clone());
    // The reference of frames 0-2, its halves 0.2 and 0.4 (4 spp: 2 + 2, mean 0.3).
    let cmp = irad::config::Compare {
        sequence: s.render.sequence.clone(),
        spp: 4,
        cache: root.clone(),
        ..Default::default()
    };
    let dir = irad::commands::compare::plan::dir(&cmp, "cornell-orbit");
    for (half, v) in [("a", 0.2), ("b", 0.4)] {
        std::fs::create_dir_all(dir.join(half)).unwrap();
        for f in 0..3 {
            let mut img = Hdr::new(24, 24);
            img.data.fill(glam::Vec3::splat(v));
            img.write_exr(&dir.join(half).join(format!("frame_{f:04}.exr")))
                .unwrap();
        }
    }
    // Another size's reference is not this view's.
    let other = irad::config::Compare {
        sequence: irad::config::Sequence {
            size: Size {
                width: 32,
                height: 32,
            },
            ..cmp.sequence.clone()
        },
        ..cmp.clone()
    };
    std::fs::create_dir_all(irad::commands::compare::plan::dir(&other, "cornell-orbit")).unwrap();
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &s).unwrap();
    app.apply(Input::Play(true)).unwrap();
    let mut reference = Hdr::new(24, 24);
    reference.data.fill(glam::Vec3::splat(0.3));
    let mut images: Vec<Hdr> = Vec::new();
    for f in 0..4u32 {
        app.step().unwrap();
        let h = &app.halves[0];
        let img = h.output.as_ref().unwrap().image.hdr.clone();
        assert_eq!(h.flicker.f1, None, "playing: nothing is still");
        if f == 3 {
            assert_eq!(h.reference, None, "frame 3 has no reference");
            break;
        }
        let r = h.reference.as_ref().expect("a cached reference");
        assert_eq!((r.spp, r.frame), (4, f));
        let want = irad::metrics::frame_error(&img, &reference)
            .unwrap()
            .rel_mse;
        assert!(
            (r.relmse - want).abs() < 1e-9 * want.max(1.0),
            "{} {want}",
            r.relmse
        );
        match images.last() {
            None => assert_eq!(r.f1, None),
            Some(before) => {
                // e_t - e_t-1 with a constant reference: the frames' change.
                let lum = irad::math::luminance;
                let n = img.data.len() as f64;
                let want: f64 = img
                    .data
                    .iter()
                    .zip(&before.data)
                    .map(|(a, b)| (lum(*a) - lum(*b)).abs() as f64)
                    .sum::<f64>()
                    / n;
                let f1 = r.f1.unwrap();
                assert!(
                    f1 > 0.0 && (f1 - want).abs() < 1e-6 * want.max(1e-3),
                    "{f1} {want}"
                );
                assert_eq!(r.frames, f);
            }
        }
        images.push(img);
    }
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}

/// Refining while still: after `refine_after` still frames the height steps up by half, up to
/// the room; the first move goes back to the size the rule had picked.
#[test]
fn a_still_view_refines_and_a_move_goes_back() {
    let t0 = std::time::Instant::now();
    let mut s = start();
    s.render.sequence.size = Size {
        width: 64,
        height: 64,
    };
    s.fixed_size = false;
    s.refine_after = 2;
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &s).unwrap();
    assert_eq!(app.auto.as_ref().unwrap().max_height, 64);
    app.set_height(40);
    let size = |app: &App| {
        let o = app.halves[0].output.as_ref().unwrap();
        (o.image.hdr.width, o.image.hdr.height)
    };
    app.step().unwrap();
    app.step().unwrap();
    assert_eq!(size(&app), (40, 40));
    assert_eq!(app.interactive, None);
    // The second still frame: the next frame is 60 -> 64 (a multiple of 8, at most the room).
    app.step().unwrap();
    assert_eq!(size(&app), (40, 40));
    let small = Size {
        width: 40,
        height: 40,
    };
    assert_eq!(app.interactive, Some(small));
    app.step().unwrap();
    assert_eq!(size(&app), (64, 64));
    for _ in 0..3 {
        app.step().unwrap();
        assert_eq!(size(&app), (64, 64), "at the room: kept while still");
    }
    app.apply(Input::Orbit {
        yaw: 5.0,
        pitch: 0.0,
    })
    .unwrap();
    app.step().unwrap();
    assert_eq!(size(&app), (40, 40), "moved: back to the rule's size");
    assert_eq!(app.interactive, None);
    // Showing something else is not a move.
    app.refine_after = 10;
    app.step().unwrap();
    app.apply(Input::Heat(true)).unwrap();
    app.step().unwrap();
    assert_eq!(app.still_steps, 2);
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}

/// Off the step: with `background` on (the window's setting), a settings change builds the new
/// halves on another thread while the old ones go on drawing; they are swapped in at a step
/// once ready. Copying or saving waits for them.
#[test]
fn a_settings_change_builds_off_the_step_while_the_old_halves_draw() {
    let t0 = std::time::Instant::now();
    let gpu = Arc::new(irad::gpu::Gpu::new(common::backend()).unwrap());
    let mut app = App::new(gpu, &start()).unwrap();
    app.background = true;
    app.step().unwrap();
    let vpls = |app: &App| app.halves[0].output.as_ref().unwrap().selection.vpls.len();
    assert_eq!(vpls(&app), 32);
    app.apply(Input::Vpls(16)).unwrap();
    app.step().unwrap();
    assert!(app.building(), "the new halves are built on another thread");
    assert_eq!(vpls(&app), 32, "the old halves drew this frame");
    let e = app.apply(Input::CopyView).unwrap_err();
    assert!(format!("{e}").contains("rebuilt"), "{e}");
    let mut steps = 0;
    while app.building() {
        app.step().unwrap();
        steps += 1;
        assert!(t0.elapsed().as_secs() < 120, "the build never finished");
    }
    // The step that swapped them in drew with them.
    assert_eq!(vpls(&app), 16);
    app.apply(Input::CopyView).unwrap();
    assert!(app.message.contains("--vpls 16"), "{}", app.message);
    println!(
        "{steps} steps while building, {:.1} s",
        t0.elapsed().as_secs_f64()
    );
}
