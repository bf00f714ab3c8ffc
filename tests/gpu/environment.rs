//! Issue 23 item 4: a model without lights renders under the default sky, or under an
//! equirectangular map, on the GPU as the path tracer renders it (docs/math.md, "The
//! environment").

use crate::common::{self, quads};
use irad::image::Hdr;
use irad::scene::{Environment, Scene};
use std::sync::Arc;

const TEST: &str = "environment";
const SIZE: u32 = 48;

/// relMSE and relative bias of the GPU frame against the reference, printed and held to
/// relMSE <= `mse` and |bias| <= `bias`.
fn check(name: &str, scene: &Scene, vpls: u32, spp: u32, mse: f64, bias: f64) {
    let gpu = common::gpu_frame(scene, SIZE, vpls);
    let reference = common::reference_frame(scene, SIZE, spp);
    let e = irad::metrics::frame_error(&gpu, &reference).unwrap();
    println!(
        "{name}: GPU mean {:.4} against the reference's {:.4}: relMSE {:.4}, bias {:+.2}%",
        common::mean_lum(&gpu),
        common::mean_lum(&reference),
        e.rel_mse,
        100.0 * e.rel_bias
    );
    let images = if e.rel_mse > mse || e.rel_bias.abs() > bias || common::show_images() {
        common::save_images(TEST, name, &gpu, &reference)
    } else {
        String::new()
    };
    assert!(e.rel_mse <= mse, "{name}: relMSE {} {images}", e.rel_mse);
    assert!(
        e.rel_bias.abs() <= bias,
        "{name}: bias {} {images}",
        e.rel_bias
    );
    // The sky is seen at the top of the frame.
    assert!(gpu.at(SIZE / 2, 0).max_element() > 0.0, "{name}: black sky");
}

#[test]
fn a_model_without_lights_renders_under_the_default_sky_as_the_reference() {
    let scene = quads::load(&quads::lightless_model());
    assert!(scene.unlit.is_some(), "the loader notes the missing light");
    assert!(scene.environment.as_ref().is_some_and(|e| e.is_uniform()));
    // Measured: relMSE 0.0075, bias -1.2%.
    check("sky", &scene, 256, 256, 0.05, 0.05);
}

/// A small map: a warm sun patch high in the -z half, a blue sky gradient above the horizon,
/// a dim brown ground below.
pub fn test_map() -> (u32, u32, Vec<[f32; 3]>) {
    let (w, h) = (32u32, 16u32);
    let mut t = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let v = (j as f32 + 0.5) / h as f32;
            let c = if (12..=13).contains(&i) && j == 3 {
                [60.0, 50.0, 35.0]
            } else if v < 0.5 {
                [0.3 + 0.6 * v, 0.5 + 0.6 * v, 1.2]
            } else {
                [0.25, 0.18, 0.1]
            };
            t.push(c);
        }
    }
    (w, h, t)
}

/// Writes [`test_map`] as a Radiance .hdr file into the test's output folder.
pub fn write_test_map(name: &str) -> std::path::PathBuf {
    let (w, h, t) = test_map();
    let img = image::Rgb32FImage::from_raw(w, h, t.concat()).unwrap();
    let path = common::output_dir(TEST).join(name);
    img.save(&path).unwrap();
    path
}

#[test]
fn a_model_under_an_equirectangular_map_renders_as_the_reference() {
    let path = write_test_map("map.hdr");
    let mut scene = quads::load(&quads::lightless_model());
    let env = irad::scene::load::read_environment(&path).unwrap();
    assert_eq!((env.width, env.height), (32, 16));
    scene.environment = Some(Arc::new(env));
    // Measured: relMSE 0.0141, bias +0.5%.
    check("map", &scene, 256, 256, 0.05, 0.05);
}

/// The background alone: with nothing in view, every pixel is the map's texel its direction
/// falls in, on the GPU as in the reference.
#[test]
fn the_background_is_the_map() {
    let path = write_test_map("background.hdr");
    let mut scene = quads::load(&quads::lightless_model());
    scene.environment = Some(Arc::new(
        irad::scene::load::read_environment(&path).unwrap(),
    ));
    // Looking up and away from the model.
    scene
        .set_camera(
            glam::Vec3::new(0.0, 1.0, 4.0),
            glam::Vec3::new(0.0, 3.0, 6.0),
            1.2,
        )
        .unwrap();
    let gpu: Hdr = common::gpu_frame(&scene, SIZE, 16);
    let reference = common::reference_frame(&scene, SIZE, 4);
    // Measured 0.0017 (the pixels' centres against their areas' means).
    let c = common::compare(TEST, "background", &gpu, &reference, 0.02);
    assert!(c.rel <= 0.02, "background differs by {}{}", c.rel, c.images);
}

/// An interior lit through an opening: the sky's directional shadow maps must not let it
/// through the walls. The GPU's direct light on `cornell-box` (open at the front) under the sky
/// against its CPU twin's (1024 samples, ray-cast visibility), over the pixels that see
/// geometry. Measured +1.2%; +4.2% with maps over the sphere and a directional light's full
/// depth bias.
#[test]
fn the_sky_does_not_leak_through_the_walls_of_a_room() {
    use irad::reference::twin;
    let mut scene = irad::scene::builtin::load("cornell-box").unwrap().unwrap();
    scene.environment = Some(Arc::new(Environment::sky()));
    let size = 96;
    let mut cfg = common::render_config();
    cfg.sequence.size = irad::config::Size {
        width: size,
        height: size,
    };
    cfg.quality.aa = 1;
    cfg.backend = common::backend();
    let gpu = Arc::new(irad::gpu::Gpu::new(cfg.backend).unwrap());
    let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
    let o = p.render_frame(0, true).unwrap();
    let f = scene.at(0.0);
    let tr = irad::trace::Tracer::new(&f);
    let pts = twin::pixel_points(&f, &tr, size, size);
    let exact = twin::direct(&f, &tr, &pts, size, size, &f.emitter_samples(5, 1024));
    let mean = |img: &Hdr| twin::mean_over_surfaces(img, &pts);
    let gpu_direct = o.image.direct.unwrap();
    let (g, t) = (mean(&gpu_direct), mean(&exact));
    println!("cornell-box under the sky: direct light GPU {g:.4}, twin {t:.4}");
    assert!(
        (g / t - 1.0).abs() < 0.025,
        "GPU {g} against the twin's {t}"
    );
}
