//! Issue 23 item 2: any scale. The same small Cornell-like box modelled at scales 1e-3..1e3
//! and placed up to 1e6 units from the origin renders the same frame, on the GPU and in the
//! reference (see docs/math.md, "Scale").

use crate::common::{self, quads::cornell_like, quads::load};
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
