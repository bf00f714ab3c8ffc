//! Issue 23 item 4 on the command line: a scene without lights renders under the default sky
//! with a note, `--environment` chooses another or none, and its errors name the flag.

use crate::common::{self, irad, quads};
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    common::fresh_dir(&format!("cli-env-{name}"))
}

/// The lightless model written as a .gltf file into a fresh folder.
fn scene_file(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("model.gltf");
    std::fs::write(&path, quads::lightless_model().to_string()).unwrap();
    path
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn run_json(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap()
}

#[test]
fn a_scene_without_lights_renders_under_the_sky_with_a_note() {
    let dir = tmp("sky");
    let scene = scene_file(&dir);
    let scene = scene.to_str().unwrap();
    let out = dir.join("render");
    let o = irad(&[
        "render",
        scene,
        "--frames",
        "0",
        "--size",
        "24x24",
        "--vpls",
        "16",
        "--light-samples",
        "8",
        "--shadow-size",
        "64",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("note:") && err.contains("no emitter") && err.contains("default environment"),
        "{err}"
    );
    assert!(!err.contains("error"), "{err}");
    assert_eq!(run_json(&out)["environment"], "sky");
    let img = irad::image::Hdr::read(&out.join("frame_0000.exr")).unwrap();
    assert!(common::mean_lum(&img) > 0.1, "a dark frame");

    // `irad scenes` says what lights it.
    let o = irad(&["scenes", scene]);
    let listed = String::from_utf8_lossy(&o.stdout);
    assert!(
        listed.contains("environment sky (the default: nothing in the file lights the scene)"),
        "{listed}"
    );

    let out = dir.join("reference");
    let o = irad(&[
        "reference",
        scene,
        "--size",
        "16x16",
        "--spp",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("default environment"), "{err}");
    assert_eq!(run_json(&out)["environment"], "sky");
}

#[test]
fn environment_flag_chooses_a_map_or_none_and_names_itself_in_errors() {
    let dir = tmp("flag");
    let scene = scene_file(&dir);
    let scene = scene.to_str().unwrap();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let reference = |env: &str| {
        irad(&[
            "reference",
            scene,
            "--size",
            "8x8",
            "--spp",
            "2",
            "--overwrite",
            "--out",
            out,
            "--environment",
            env,
        ])
    };
    // A map read from outside the scene's folder: the user named it.
    let map = common::output_dir("cli-environment").join("map.hdr");
    image::Rgb32FImage::from_pixel(8, 4, image::Rgb([0.5, 0.7, 1.0]))
        .save(&map)
        .unwrap();
    let o = reference(map.to_str().unwrap());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("note:"), "{}", stderr(&o));
    assert_eq!(
        run_json(Path::new(out))["environment"],
        map.to_str().unwrap()
    );
    // `none` refuses a scene without lights as irad did before it had environments.
    let o = reference("none");
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(
        err.contains("no emitter") && err.contains("--environment none"),
        "{err}"
    );
    // Files that are not maps.
    let missing = dir.join("missing.hdr");
    let text = dir.join("text.exr");
    std::fs::write(&text, b"not an image").unwrap();
    let black = dir.join("black.hdr");
    image::Rgb32FImage::from_pixel(4, 2, image::Rgb([0.0, 0.0, 0.0]))
        .save(&black)
        .unwrap();
    let negative = dir.join("negative.exr");
    image::Rgb32FImage::from_pixel(4, 2, image::Rgb([1.0, -2.0, 0.0]))
        .save(&negative)
        .unwrap();
    for (file, words) in [
        (missing.as_path(), &["cannot be read"][..]),
        (text.as_path(), &["cannot be read as a exr image"][..]),
        (black.as_path(), &["black everywhere"][..]),
        (negative.as_path(), &["pixel (0, 0)", "not negative"][..]),
        (scene.as_ref(), &["not a .hdr or .exr file"][..]),
    ] {
        let o = reference(file.to_str().unwrap());
        let err = stderr(&o);
        assert!(!o.status.success(), "{}: accepted", file.display());
        assert!(err.contains("--environment"), "{err}");
        for w in words {
            assert!(err.contains(w), "'{w}' missing from: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
    }
}
