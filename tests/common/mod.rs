//! What the integration tests share: the adapters to test on, the folders tests write into,
//! and image comparisons that leave the actual, expected and difference images behind when
//! they fail. Each test binary (`tests/gpu`, `tests/cli`, `tests/cpu`) includes this module
//! with `#[path = "../common/mod.rs"] mod common;` and uses what it needs of it.

#![allow(dead_code)]

pub mod gltf;
pub mod quads;

use irad::gpu::{adapters, BackendChoice};
use irad::image::Hdr;
use irad::math::luminance;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Mesa's EGL (probing Wayland) prints "error: XDG_RUNTIME_DIR is invalid or not set" every
/// time a test opens the GL backend on a machine without a desktop session; `irad` itself
/// points the variable at a private folder first thing in `main`
/// (`gpu::quiet_mesa_runtime_dir`). A test binary has no `main` of its own, so this runs the
/// same function from the binary's constructors (`.init_array`), before the test harness
/// starts a thread and before any test opens an adapter. It leaves a usable
/// `XDG_RUNTIME_DIR` as it is.
#[cfg(target_os = "linux")]
#[used]
#[link_section = ".init_array"]
static QUIET_MESA: extern "C" fn() = {
    extern "C" fn quiet_mesa() {
        irad::gpu::quiet_mesa_runtime_dir();
    }
    quiet_mesa
};

/// The backends to test: every one of Vulkan and GL that has a usable adapter here (looked
/// up once a process).
/// The render settings the GPU tests start from: the library's defaults with the `uniform`
/// sampler (Keller's: fresh, independent VPLs every frame, no state between frames) and no
/// temporal accumulation, which their tolerances were measured with. The library's default
/// sampler is `mh`, whose chains carry state from frame to frame, and it accumulates 8
/// frames; tests of a sampler or of accumulation name them.
pub fn render_config() -> irad::config::Render {
    let mut c = irad::config::Render::default();
    c.sampler.kind = irad::vpl::sampler::SamplerKind::Uniform;
    c.quality.accumulate = 0;
    c
}

/// Frame 0 of `scene` rendered on the GPU at `size` x `size` with `vpls` VPLs (the tests'
/// [`render_config`], no supersampling), on the backend under test.
pub fn gpu_frame(scene: &irad::scene::Scene, size: u32, vpls: u32) -> Hdr {
    let backend = backend();
    let mut cfg = render_config();
    cfg.sequence.size = irad::config::Size {
        width: size,
        height: size,
    };
    cfg.vpls = vpls;
    cfg.quality.aa = 1;
    cfg.backend = backend;
    let gpu = std::sync::Arc::new(irad::gpu::Gpu::new(backend).unwrap());
    let mut p = irad::frame::Pipeline::new(gpu, scene.clone(), &cfg).unwrap();
    p.render_frame(0, true).unwrap().image.hdr
}

/// Frame 0 of `scene` path-traced at `size` x `size` with `spp` samples a pixel, seed 1.
pub fn reference_frame(scene: &irad::scene::Scene, size: u32, spp: u32) -> Hdr {
    reference_capped_from(scene, size, spp, 1, irad::reference::RR_CAP_DEPTH)
}

/// A reference of `scene` (`size` x `size`, `spp` samples a pixel, seed `seed`) whose
/// roulette is capped from bounce `rr_cap_depth` on (`ReferenceSettings::rr_cap_depth`).
pub fn reference_capped_from(
    scene: &irad::scene::Scene,
    size: u32,
    spp: u32,
    seed: u64,
    rr_cap_depth: u32,
) -> Hdr {
    let mut f = scene.at(0.0);
    let t = irad::trace::Tracer::new(&f);
    // As `irad reference` draws its emitter samples (commands::reference).
    t.keep_lit_emitters(&mut f);
    let s = irad::reference::ReferenceSettings {
        width: size,
        height: size,
        spp,
        seed,
        rr_cap_depth,
    };
    irad::reference::render(&f, &t, &s, &|| {})
}

pub fn backends() -> Vec<BackendChoice> {
    static FOUND: OnceLock<Vec<BackendChoice>> = OnceLock::new();
    let found = FOUND.get_or_init(|| {
        [BackendChoice::Vulkan, BackendChoice::Gl]
            .into_iter()
            .filter(|&b| adapters(b).iter().any(|(_, ok)| *ok))
            .collect()
    });
    assert!(
        !found.is_empty(),
        "no usable Vulkan or GL adapter: install mesa-vulkan-drivers or libegl-mesa0"
    );
    found.clone()
}

/// The first usable backend: lavapipe (Vulkan), else llvmpipe (GL).
pub fn backend() -> BackendChoice {
    backends()[0]
}

/// The folder `target/tmp/test-output/<name>` (created) where a test writes its images.
pub fn output_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("test-output")
        .join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A folder `<temp>/irad-<name>-<pid>` for a command's outputs, removed if an earlier test
/// left it (not created: commands create their output folders).
pub fn fresh_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("irad-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Whether `IRAD_TEST_IMAGES` asks for the images of comparisons that pass too.
pub fn show_images() -> bool {
    std::env::var_os("IRAD_TEST_IMAGES").is_some()
}

/// Mean luminance of `img`.
pub fn mean_lum(img: &Hdr) -> f32 {
    img.data.iter().map(|&c| luminance(c)).sum::<f32>() / img.data.len() as f32
}

/// Mean over pixels of |lum actual - lum expected|, over the expected image's mean luminance.
pub fn rel_diff(actual: &Hdr, expected: &Hdr) -> f32 {
    assert_eq!(
        (actual.width, actual.height),
        (expected.width, expected.height),
        "images of different sizes"
    );
    let d: f32 = actual
        .data
        .iter()
        .zip(&expected.data)
        .map(|(&x, &y)| (luminance(x) - luminance(y)).abs())
        .sum();
    d / actual.data.len() as f32 / mean_lum(expected).max(1e-9)
}

/// Writes `actual`, `expected` and |actual - expected| into `output_dir(test)` as
/// `<name>-actual`, `<name>-expected` and `<name>-difference`, each as EXR (the values) and
/// as PNG (exposure 1; the difference x4 to be seen), and returns a line naming them, for a
/// panic message.
pub fn save_images(test: &str, name: &str, actual: &Hdr, expected: &Hdr) -> String {
    let dir = output_dir(test);
    let difference = actual.zip_map(expected, |a, b| (a - b).abs());
    let mut exr = Vec::new();
    for (what, img, gain) in [
        ("actual", actual, 1.0),
        ("expected", expected, 1.0),
        ("difference", &difference, 4.0),
    ] {
        let path = dir.join(format!("{name}-{what}.exr"));
        img.write_exr(&path).unwrap();
        img.write_png(&dir.join(format!("{name}-{what}.png")), gain)
            .unwrap();
        exr.push(path.display().to_string());
    }
    let line = format!(
        "images: {} (and .png beside each; the difference's x4)",
        exr.join(", ")
    );
    println!("{line}");
    line
}

/// What [`compare`] measured, and the images it wrote ("" when it wrote none).
pub struct Compared {
    pub rel: f32,
    pub images: String,
}

/// [`rel_diff`] of `actual` against `expected`, printed; where it exceeds `bound` (or is NaN,
/// or `IRAD_TEST_IMAGES` is set) the three images are written ([`save_images`]) and
/// `images` names them. The caller asserts, with `images` in its message.
pub fn compare(test: &str, name: &str, actual: &Hdr, expected: &Hdr, bound: f32) -> Compared {
    let rel = rel_diff(actual, expected);
    println!("{name}: mean |actual - expected| / mean = {rel:.5} (bound {bound})");
    let images = if rel > bound || rel.is_nan() || show_images() {
        format!("; {}", save_images(test, name, actual, expected))
    } else {
        String::new()
    };
    Compared { rel, images }
}

/// Writes one 8-bit RGB image (`w` x `h`, 3 bytes a pixel) as PNG into `output_dir(test)`.
pub fn save_rgb8(test: &str, file: &str, w: u32, h: u32, bytes: Vec<u8>) -> PathBuf {
    let path = output_dir(test).join(file);
    image::RgbImage::from_raw(w, h, bytes)
        .unwrap()
        .save(&path)
        .unwrap();
    path
}

/// The `irad` binary cargo built for these tests, as a command to add arguments to.
pub fn irad_command() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_irad"))
}

/// Runs `irad args` to its end: its exit status and what it printed.
pub fn irad(args: &[&str]) -> std::process::Output {
    irad_command().args(args).output().unwrap()
}
