//! The GPU path held to its CPU twin and to analytic answers, on every adapter CI has
//! (lavapipe through Vulkan and llvmpipe through GL).

use glam::Vec3;
use irad::config;
use irad::frame::Pipeline;
use irad::gpu::{adapters, BackendChoice};
use irad::image::Hdr;
use irad::reference::twin;
use irad::scene::builtin;
use irad::trace::Tracer;

/// The backends to test: every one of Vulkan and GL that has a usable adapter here.
fn backends() -> Vec<BackendChoice> {
    let found: Vec<BackendChoice> = [BackendChoice::Vulkan, BackendChoice::Gl]
        .into_iter()
        .filter(|&b| adapters(b).iter().any(|(_, ok)| *ok))
        .collect();
    assert!(
        !found.is_empty(),
        "no usable Vulkan or GL adapter: install mesa-vulkan-drivers or libegl-mesa0"
    );
    found
}

/// Render settings at `w` x `h` with `vpls` VPLs and `light_samples` emitter samples (the
/// defaults otherwise: 64^2 ISM tiles, 4096 points a VPL, 3 pull-push levels).
fn config(w: u32, h: u32, vpls: u32, light_samples: u32) -> config::Render {
    let mut c = config::Render::default();
    c.sequence.size = config::Size {
        width: w,
        height: h,
    };
    c.vpls = vpls;
    c.quality.light_samples = light_samples;
    c.sampler.camera_points = 64;
    c.sampler.mh_escape = 0;
    c
}

/// A pipeline for a built-in scene with distance clamp `dmin`, on its own device.
fn pipeline(scene: &str, mut cfg: config::Render, dmin: f32, backend: BackendChoice) -> Pipeline {
    let scene = builtin::load(scene).unwrap().unwrap();
    cfg.clamp = Some(dmin);
    cfg.backend = backend;
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(backend).unwrap());
    Pipeline::new(gpu, scene, &cfg).unwrap()
}

/// Mean over pixels of |a - b| / (mean luminance of b), luminance; writes both images and
/// their difference under target/test-output on failure (the caller asserts).
fn compare(name: &str, a: &Hdr, b: &Hdr, bound: f32) -> f32 {
    let lum = irad::math::luminance;
    let mean_b = b.data.iter().map(|&c| lum(c)).sum::<f32>() / b.data.len() as f32;
    let diff = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(&x, &y)| (lum(x) - lum(y)).abs())
        .sum::<f32>()
        / a.data.len() as f32;
    let rel = diff / mean_b.max(1e-6);
    println!(
        "{name}: mean |gpu - cpu| / mean = {:.4} (bound {bound})",
        rel
    );
    if rel > bound || rel.is_nan() || std::env::var_os("IRAD_TEST_IMAGES").is_some() {
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("test-output");
        std::fs::create_dir_all(&dir).unwrap();
        a.write_exr(&dir.join(format!("{name}-gpu.exr"))).unwrap();
        a.write_png(&dir.join(format!("{name}-gpu.png")), 1.0)
            .unwrap();
        b.write_png(&dir.join(format!("{name}-cpu.png")), 1.0)
            .unwrap();
        let d = Hdr {
            width: a.width,
            height: a.height,
            data: a
                .data
                .iter()
                .zip(&b.data)
                .map(|(&x, &y)| (x - y).abs() * 4.0)
                .collect(),
        };
        d.write_png(&dir.join(format!("{name}-diff.png")), 1.0)
            .unwrap();
        println!("images written to {}", dir.display());
    }
    rel
}

#[test]
fn gpu_matches_cpu_twin_direct_and_indirect() {
    for backend in backends() {
        let (w, h) = (64, 64);
        let mut p = pipeline("cornell", config(w, h, 256, 16), 0.07, backend);
        let out = p.render_frame(0, true).unwrap();
        let frame = p.scene.at(0.0);
        let tracer = Tracer::new(&frame);
        let points = twin::pixel_points(&frame, &tracer, w, h);
        let lights = frame.emitter_samples(1, 16);
        let name = format!("{backend:?}").to_lowercase();
        let direct_cpu = twin::direct(&frame, &tracer, &points, w, h, &lights);
        let rel = compare(
            &format!("{name}-direct"),
            out.image.direct.as_ref().unwrap(),
            &direct_cpu,
            0.03,
        );
        assert!(
            rel <= 0.03,
            "{name}: direct light differs from the CPU twin by {rel}"
        );
        let indirect_cpu =
            twin::gather(&frame, &tracer, &points, w, h, &out.selection.shaded, 0.07);
        let rel = compare(
            &format!("{name}-indirect"),
            out.image.indirect.as_ref().unwrap(),
            &indirect_cpu,
            0.10,
        );
        assert!(
            rel <= 0.10,
            "{name}: ISM gather differs from exact visibility by {rel}"
        );
        // The composed frame is emission + direct + indirect.
        let emission = twin::emission(&frame, &points, w, h);
        let sum = Hdr {
            width: w,
            height: h,
            data: (0..(w * h) as usize)
                .map(|i| {
                    emission.data[i]
                        + out.image.direct.as_ref().unwrap().data[i]
                        + out.image.indirect.as_ref().unwrap().data[i]
                })
                .collect(),
        };
        let rel = compare(&format!("{name}-compose"), &out.image.hdr, &sum, 0.01);
        assert!(
            rel <= 0.01,
            "{name}: compose is not emission + direct + indirect ({rel})"
        );
    }
}

#[test]
fn white_furnace_through_the_gpu() {
    for backend in backends() {
        let mut p = pipeline("furnace", config(32, 32, 4096, 64), 0.0, backend);
        let out = p.render_frame(0, false).unwrap();
        let mean = out.image.hdr.mean();
        println!("{backend:?}: furnace mean {mean} (expected 2.0)");
        assert!(
            (mean - Vec3::splat(2.0)).abs().max_element() < 0.03 * 2.0,
            "{backend:?}: furnace mean {mean}"
        );
    }
}

#[test]
fn same_seed_same_frames() {
    for backend in backends() {
        let mut a = pipeline("cornell-box", config(48, 48, 128, 8), 0.07, backend);
        let mut b = pipeline("cornell-box", config(48, 48, 128, 8), 0.07, backend);
        for f in [0, 7] {
            let (x, y) = (
                a.render_frame(f, false).unwrap(),
                b.render_frame(f, false).unwrap(),
            );
            assert!(
                x.image.hdr == y.image.hdr && x.image.ldr == y.image.ldr,
                "{backend:?}: frame {f} differs between runs"
            );
        }
        // And a re-render of the same frame in the same pipeline is identical too.
        let again = a.render_frame(7, false).unwrap();
        assert!(again.image.hdr == b.render_frame(7, false).unwrap().image.hdr);
    }
}
