//! How a frame is submitted: one submission a frame gives the same image as one submission
//! per pass, and per-pass times come back in every profiling mode, on every adapter here.

use irad::config;
use irad::frame::{Pipeline, SamplerKind};
use irad::gpu::renderer::PASSES;
use irad::gpu::{adapters, profile, BackendChoice, Profiling};
use irad::scene::builtin;

fn backends() -> Vec<BackendChoice> {
    let found: Vec<BackendChoice> = [BackendChoice::Vulkan, BackendChoice::Gl]
        .into_iter()
        .filter(|&b| adapters(b).iter().any(|(_, ok)| *ok))
        .collect();
    assert!(!found.is_empty(), "no usable Vulkan or GL adapter");
    found
}

/// A small MH pipeline for a built-in scene, on its own device.
fn pipeline(scene: &str, vpls: u32, backend: BackendChoice) -> Pipeline {
    let mut c = config::Render::default();
    c.sequence.size = config::Size {
        width: 48,
        height: 40,
    };
    c.sequence.seed = 3;
    c.vpls = vpls;
    c.clamp = Some(0.07);
    c.backend = backend;
    c.sampler.kind = SamplerKind::Mh;
    c.sampler.camera_points = 64;
    c.sampler.mh_escape = 0;
    c.quality.ism_size = 32;
    c.quality.ism_points = 2048;
    c.quality.light_samples = 8;
    c.quality.shadow_size = 128;
    let scene = builtin::load(scene).unwrap().unwrap();
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(backend).unwrap());
    Pipeline::new(gpu, scene, &c).unwrap()
}

/// Frame 2 rendered with a pipeline whose renderer uses `mode`.
fn render(backend: BackendChoice, mode: Profiling) -> irad::frame::FrameOutput {
    let mut p = pipeline("cornell-orbit", 64, backend);
    p.renderer.profiling = mode;
    for f in 0..2 {
        p.render_frame(f, false).unwrap();
    }
    p.render_frame(2, true).unwrap()
}

#[test]
fn one_submission_gives_the_serialized_frame_and_per_pass_times() {
    for backend in backends() {
        let serial = render(backend, Profiling::Serialized);
        println!("{backend:?} Serialized: {:?}", serial.image.timings);
        let mut modes = vec![Profiling::Off];
        let gpu = irad::gpu::Gpu::new(backend).unwrap();
        let stamps = profile::has_timestamps(&gpu);
        println!("{backend:?}: timestamp queries {stamps}");
        if stamps {
            modes.push(Profiling::Timestamps);
        }
        for mode in modes {
            let one = render(backend, mode);
            assert_eq!(one.image.profiling, mode);
            // The same commands in the same order: the same bits.
            assert!(
                one.image.hdr == serial.image.hdr
                    && one.image.ldr == serial.image.ldr
                    && one.image.direct == serial.image.direct
                    && one.image.indirect == serial.image.indirect,
                "{backend:?}: {mode:?} differs from the serialized frame"
            );
            let names: Vec<&str> = one.image.timings.iter().map(|t| t.0).collect();
            println!("{backend:?} {mode:?}: {:?}", one.image.timings);
            let passes: Vec<&str> = if mode == Profiling::Off {
                vec![]
            } else {
                PASSES.to_vec()
            };
            let want: Vec<&str> = [vec!["upload"], passes, vec!["readback"]].concat();
            assert_eq!(names, want, "{backend:?} {mode:?}");
            // Every time is finite, and the passes' GPU times fit in the frame's wall time.
            let sum: f64 = one.image.timings.iter().map(|t| t.1).sum();
            assert!(one
                .image
                .timings
                .iter()
                .all(|t| t.1.is_finite() && t.1 >= 0.0));
            assert!(
                sum <= one.seconds,
                "{backend:?} {mode:?}: {sum} > {}",
                one.seconds
            );
            if mode == Profiling::Timestamps {
                // The gather and the ISM splat do real work at 64 VPLs: a timestamp pair
                // that measured nothing would show 0.
                let t = |n: &str| one.image.timings.iter().find(|t| t.0 == n).unwrap().1;
                assert!(t("gather") > 0.0 && t("ism_splat") > 0.0 && t("shadow_maps") > 0.0);
            }
        }
        let serial_names: Vec<&str> = serial.image.timings.iter().map(|t| t.0).collect();
        assert_eq!(serial_names.len(), PASSES.len() + 2);
    }
}

/// Frames 0..5 of `scene` with and without reuse across frames.
fn reuse_run(scene: &str, backend: BackendChoice) -> Vec<irad::gpu::renderer::Reuse> {
    let mut keep = pipeline(scene, 64, backend);
    let mut redraw = pipeline(scene, 64, backend);
    redraw.renderer.reuse = false;
    (0..5)
        .map(|f| {
            let (a, b) = (
                keep.render_frame(f, true).unwrap(),
                redraw.render_frame(f, true).unwrap(),
            );
            // A kept tile or hemicube is the one a redraw would give: the same bits.
            let d = |x: &Option<irad::image::Hdr>, y: &Option<irad::image::Hdr>| {
                let (x, y) = (x.as_ref().unwrap(), y.as_ref().unwrap());
                x.data
                    .iter()
                    .zip(&y.data)
                    .map(|(p, q)| (*p - *q).abs().max_element())
                    .fold(0.0f32, f32::max)
            };
            println!(
                "max diff direct {} indirect {}",
                d(&a.image.direct, &b.image.direct),
                d(&a.image.indirect, &b.image.indirect)
            );
            assert!(
                a.image.hdr == b.image.hdr
                    && a.image.direct == b.image.direct
                    && a.image.indirect == b.image.indirect,
                "{backend:?} {scene} frame {f}: reuse changed the image"
            );
            let r = b.image.reused;
            assert!(!r.shadow_maps_kept && r.ism_tiles_kept == 0 && !r.geometry_kept);
            println!("{backend:?} {scene} frame {f}: {:?}", a.image.reused);
            a.image.reused
        })
        .collect()
}

#[test]
fn reuse_keeps_what_did_not_move_and_gives_the_same_frames() {
    for backend in backends() {
        // The camera orbits a still box: hemicubes kept after frame 0; MH keeps most VPLs
        // and so most ISM tiles.
        let r = reuse_run("cornell-orbit", backend);
        assert_eq!(r[0].ism_tiles_drawn, 64);
        assert!(!r[0].shadow_maps_kept && !r[0].geometry_kept);
        for x in &r[1..] {
            assert!(
                x.geometry_kept && x.lights_kept && x.shadow_maps_kept,
                "{x:?}"
            );
            assert_eq!(x.ism_tiles_kept + x.ism_tiles_drawn, 64);
        }
        let kept: u32 = r[1..].iter().map(|x| x.ism_tiles_kept).sum();
        assert!(kept > 0, "no ISM tile kept under MH: {r:?}");
        // A moving box: nothing is kept.
        for x in reuse_run("cornell-box", backend).iter().skip(1) {
            assert!(
                !x.geometry_kept && !x.shadow_maps_kept && x.ism_tiles_kept == 0,
                "{x:?}"
            );
        }
    }
}
