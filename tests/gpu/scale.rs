//! Issue 23 item 2: any scale. The same small Cornell-like box modelled at scales 1e-3..1e3
//! and placed up to 1e6 units from the origin renders the same frame, on the GPU and in the
//! reference (see docs/math.md, "Scale").

use crate::common::{self, quads::cornell_like, quads::cornell_like_and_far_cube, quads::load};
use irad::image::Hdr;
use irad::scene::Scene;

const TEST: &str = "scale";
const SIZE: u32 = 24;

fn scene(scale: f32, offset: f32) -> Scene {
    load(&cornell_like(scale, [offset, 0.5 * offset, -0.25 * offset]))
}

fn gpu(scene: &Scene) -> Hdr {
    common::gpu_frame(scene, SIZE, 64)
}

fn reference(scene: &Scene) -> Hdr {
    common::reference_frame(scene, SIZE, 64)
}

/// Measured on lavapipe: GPU within 0.00012 of the unscaled frame everywhere (the loader
/// moves far scenes to the origin, its matrices composed exactly); the reference within
/// 0.00001 (the tracer works in the frame times a power of two; before, obvhs's absolute 1e-4
/// node epsilon made the 1e-3 box 1.1% darker: 0.036 here).
const GPU_BOUND: f32 = 0.001;
const REFERENCE_BOUND: f32 = 1e-4;

#[test]
fn the_same_box_at_any_scale_and_place_renders_the_same_frame() {
    let scales = [1e-3f32, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3];
    let offsets = [0.0f32, 1e3, 1e6];
    let base = gpu(&scene(1.0, 0.0));
    let base_ref = reference(&scene(1.0, 0.0));
    println!("mean |frame - unscaled| / mean (GPU; reference in brackets)");
    println!("  scale   offset 0          1e3          1e6");
    let mut worst: (f32, f32) = (0.0, 0.0);
    let mut failures = Vec::new();
    for &s in &scales {
        let mut line = format!("{s:7.0e}");
        for &o in &offsets {
            let sc = scene(s, o);
            let name = format!("gpu-{s:e}-{o:e}");
            let c = common::compare(TEST, &name, &gpu(&sc), &base, GPU_BOUND);
            let g = c.rel;
            worst.0 = worst.0.max(g);
            line += &format!("   {g:.5}");
            if (s == 1e-3 || s == 1e-2 || s == 1e3) && o != 1e3 {
                let name = format!("reference-{s:e}-{o:e}");
                let c = common::compare(TEST, &name, &reference(&sc), &base_ref, REFERENCE_BOUND);
                worst.1 = worst.1.max(c.rel);
                line += &format!(" [{:.5}]", c.rel);
                if c.rel.is_nan() || c.rel > REFERENCE_BOUND {
                    failures.push(format!(
                        "scale {s:e} offset {o:e}: reference {}{}",
                        c.rel, c.images
                    ));
                }
            } else {
                line += "          ";
            }
            if g.is_nan() || g > GPU_BOUND {
                failures.push(format!("scale {s:e} offset {o:e}: GPU {g}{}", c.images));
            }
        }
        println!("{line}");
    }
    println!("worst: GPU {:.5}, reference {:.5}", worst.0, worst.1);
    assert!(failures.is_empty(), "{failures:?}");
}

/// Frame 0 of `scene` on the GPU as [`gpu`] renders it, with the distance clamp `clamp`
/// (None: the default) and `vpls` VPLs.
fn gpu_clamped(scene: &Scene, clamp: Option<f32>, vpls: u32) -> Hdr {
    gpu_compensated(scene, clamp, vpls, irad::gpu::Compensate::Paths(0))
}

/// [`gpu_clamped`] with `compensate` (`gpu_clamped`: off, the clamp alone).
fn gpu_compensated(
    scene: &Scene,
    clamp: Option<f32>,
    vpls: u32,
    compensate: irad::gpu::Compensate,
) -> Hdr {
    let mut cfg = common::render_config();
    cfg.quality.compensate = compensate;
    cfg.sequence.size = irad::config::Size {
        width: SIZE,
        height: SIZE,
    };
    cfg.vpls = vpls;
    cfg.quality.aa = 1;
    cfg.backend = common::backend();
    cfg.clamp = clamp;
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(cfg.backend).unwrap());
    let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
    p.render_frame(0, true).unwrap().image.hdr
}

/// Mean luminance over blocks of 6 x 6 pixels: what a frame shows, without the noise of
/// which VPLs and ISM points a scene's random numbers drew.
fn blocks(img: &Hdr) -> Vec<f32> {
    let n = SIZE / 6;
    let mut b = vec![0.0f32; (n * n) as usize];
    for y in 0..SIZE {
        for x in 0..SIZE {
            let c = img.data[(y * SIZE + x) as usize];
            b[((y / 6) * n + x / 6) as usize] += irad::math::luminance(c) / 36.0;
        }
    }
    b
}

/// Mean |a - b| over blocks ([`blocks`]), over the mean of `b`'s, and the relative difference
/// of the means.
fn block_diff(a: &Hdr, b: &Hdr) -> (f32, f32) {
    let (a, b) = (blocks(a), blocks(b));
    let mean = b.iter().sum::<f32>() / b.len() as f32;
    let d = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum::<f32>() / b.len() as f32;
    (
        d / mean,
        a.iter().sum::<f32>() / b.iter().sum::<f32>() - 1.0,
    )
}

/// A 0.2 cube 50 units from the box (behind the camera) makes its bounding box 20 times
/// larger. The default clamp follows the box's free path, not the bounding box, so the frame
/// keeps the box alone's (1024 VPLs; measured over 6 x 6-pixel blocks: 0.0064 of the mean,
/// the means -0.2%; a second seed of the box alone differs by 0.034, +3.0%: the far cube
/// changes few of the random numbers). With the clamp of the rule before (2% of the
/// diagonal, 1.45 against 0.080) and no compensation the box is 8.8% darker; with that clamp
/// 35% of the lamp's light meets a surface within it, so `--compensate auto` traces its 64
/// paths a pixel and gives the light back (measured +2.0% in the mean; seeds differ by 3%).
#[test]
fn a_far_small_object_leaves_the_box_as_it_was() {
    let alone = load(&cornell_like(1.0, [0.0; 3]));
    let with = load(&cornell_like_and_far_cube([50.0, 0.0, 50.0]));
    let base = gpu_clamped(&alone, None, 1024);
    let far = gpu_clamped(&with, None, 1024);
    let f = with.at(0.0);
    let (lo, hi) = f.bounds();
    let old = 0.02 * (hi - lo).length();
    let before = gpu_clamped(&with, Some(old), 1024);
    let (d, m) = block_diff(&far, &base);
    let (db, mb) = block_diff(&before, &base);
    println!("against the box alone, over 6 x 6 blocks (and the means):");
    println!("  with the far cube          {d:.4} ({m:+.4})");
    println!("  and the clamp before {old:.3} {db:.4} ({mb:+.4})");
    if d > 0.01 || common::show_images() {
        common::save_images(TEST, "far-cube", &far, &base);
    }
    let auto = gpu_compensated(&with, Some(old), 1024, irad::gpu::Compensate::Auto);
    let (da, ma) = block_diff(&auto, &base);
    println!("  and compensated (auto)     {da:.4} ({ma:+.4})");
    assert!(d < 0.01 && m.abs() < 0.01, "{d} {m}");
    assert!(mb < -0.05, "{mb}");
    assert!(ma.abs() < 0.05, "{ma}");
}
