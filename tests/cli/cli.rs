//! The `irad` binary end to end: outputs, conventions and clear errors.

use crate::common::{self, irad};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    common::fresh_dir(&format!("cli-{name}"))
}

#[test]
fn reference_writes_frames_and_record_with_red_on_the_left() {
    let out = tmp("ref");
    let o = irad(&[
        "reference",
        "cornell-orbit",
        "--size",
        "20x16",
        "--spp",
        "16",
        "--frames",
        "3..5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "frame_0003.exr",
        "frame_0003.png",
        "frame_0004.exr",
        "frame_0004.png",
        "run.json",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    assert!(!out.join("frame_0002.exr").exists() && !out.join("frame_0005.exr").exists());
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["frames"].as_array().unwrap().len(), 2);
    assert_eq!(run["frames"][1]["frame"], 4);
    assert!((run["frames"][1]["time"].as_f64().unwrap() - 4.0 / 24.0).abs() < 1e-6);
    let img = irad::image::Hdr::read(&out.join("frame_0003.exr")).unwrap();
    assert_eq!((img.width, img.height), (20, 16));
    // Red wall on the left, green on the right (camera orientation).
    let col = |x: u32| (0..16).map(|y| img.at(x, y)).sum::<glam::Vec3>();
    println!(
        "left column red/green {}, right column green/red {}",
        col(3).x / col(3).y,
        col(16).y / col(16).x
    );
    // Measured 9.33 (red / green, left) and 1.74 (green / red, right).
    assert!(col(3).x > 6.3 * col(3).y, "left column {}", col(3));
    assert!(col(16).y > 1.3 * col(16).x, "right column {}", col(16));
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_arguments_fail_before_rendering_with_clear_messages() {
    let o = irad(&["reference", "--size", "0x16"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("out of range"));
    let o = irad(&["reference", "--frames", "4..2"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("empty"), "{e}");
    let o = irad(&["reference", "no-such-scene"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("no-such-scene") && e.contains("built-in"),
        "{e}"
    );
    // An output folder that cannot be made: a path below a regular file.
    let file = tmp("file");
    std::fs::write(&file, b"x").unwrap();
    let o = irad(&[
        "reference",
        "--size",
        "4x4",
        "--spp",
        "1",
        "--out",
        file.join("sub").to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("cannot create the output folder"),
        "{e}"
    );
    std::fs::remove_file(&file).unwrap();
}

#[test]
fn scenes_lists_every_builtin() {
    let o = irad(&["scenes"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8_lossy(&o.stdout);
    for name in [
        "cornell",
        "cornell-orbit",
        "cornell-light",
        "cornell-box",
        "furnace",
    ] {
        assert!(
            s.lines().any(|l| l.starts_with(name)),
            "{name} not listed:\n{s}"
        );
    }
}

const SMALL: &[&str] = &[
    "--size",
    "32x32",
    "--vpls",
    "16",
    "--light-samples",
    "4",
    "--shadow-size",
    "32",
    "--ism-points",
    "512",
];

#[test]
fn render_writes_frames_preview_and_record() {
    let out = tmp("render");
    let mut args = vec![
        "render",
        "cornell-box",
        "--frames",
        "2..4",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(SMALL);
    let o = irad(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "frame_0002.exr",
        "frame_0002.png",
        "frame_0003.exr",
        "frame_0003.png",
        "preview.gif",
        "run.json",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert!(run["adapter"]["name"].as_str().unwrap().len() > 1);
    let frames = run["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    for f in frames {
        assert!(f["seconds"].as_f64().unwrap() > 0.0);
        for stage in [
            "scene",
            "bvh",
            "vpls",
            "gbuffer",
            "shadow_maps",
            "direct",
            "ism_splat",
            "ism_pullpush",
            "gather",
            "compose",
        ] {
            assert!(
                f["stages"][stage].as_f64().is_some(),
                "stage {stage} missing"
            );
        }
        assert!(f["vpls"].as_u64().unwrap() > 0 && f["vpls"].as_u64().unwrap() <= 16);
    }
    let gif = image::open(out.join("preview.gif"));
    assert!(gif.is_ok(), "preview.gif does not decode");
    // The PNG is the EXR through the sRGB curve (IEC 61966-2-1, written out here apart from
    // irad's), channel by channel: swapped R/B or another curve fail. Cornell's red and green
    // walls give channels far apart and dark ones, where gamma 2.2 and sRGB part.
    let hdr = irad::image::Hdr::read(&out.join("frame_0003.exr")).unwrap();
    let png = image::open(out.join("frame_0003.png")).unwrap().to_rgb8();
    let srgb = |v: f32| {
        let v = (v as f64).clamp(0.0, 1.0);
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5).floor() as u8
    };
    let expected: Vec<u8> = hdr
        .data
        .iter()
        .flat_map(|c| c.to_array().map(srgb))
        .collect();
    let red_blue = expected
        .chunks_exact(3)
        .filter(|p| p[0].abs_diff(p[2]) > 40)
        .count();
    let off = png.as_raw().iter().zip(&expected);
    let max = off.clone().map(|(a, e)| a.abs_diff(*e)).max().unwrap();
    println!(
        "png vs sRGB of the exr: max |diff| {max}, {} channels differ; {red_blue} pixels with |R - B| > 40",
        off.filter(|(a, e)| a != e).count()
    );
    // Measured (lavapipe): no channel differs; 637 of 1024 pixels with |R - B| > 40.
    if max > 0 {
        let diff: Vec<u8> = png
            .as_raw()
            .iter()
            .zip(&expected)
            .map(|(a, e)| a.abs_diff(*e).saturating_mul(32))
            .collect();
        for (bytes, name) in [(expected, "expected"), (diff, "diff")] {
            image::RgbImage::from_raw(32, 32, bytes)
                .unwrap()
                .save(out.join(format!("frame_0003_{name}.png")))
                .unwrap();
        }
        panic!(
            "frame_0003.png is off by {max} from the sRGB of frame_0003.exr; see {}",
            out.display()
        );
    }
    assert!(red_blue > 425, "{red_blue}");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn render_rejects_bad_arguments_before_rendering() {
    let out = tmp("render-bad");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--size", "0x0"], "out of range"),
        (&["--size", "9000x10"], "out of range"),
        (&["--vpls", "0"], "out of range"),
        (&["--vpls", "40000"], "lower --vpls or --ism-size"),
        (&["--ism-size", "48"], "power of two"),
        (&["--clamp=-1"], "--clamp -1 is out of range"),
        (&["--clamp", "-1"], "--clamp -1 is out of range"),
        (&["--ism-bias", "nan"], "--ism-bias NaN"),
        (&["--pull-levels", "100"], "--pull-levels 100"),
        (&["--fps", "0"], "--fps"),
    ];
    for (extra, msg) in cases {
        let mut args = vec!["render", "cornell", "--frames", "0", "--out", o];
        args.extend_from_slice(extra);
        let r = irad(&args);
        let e = String::from_utf8_lossy(&r.stderr);
        assert!(
            !r.status.success() && e.contains(msg),
            "{extra:?}: expected '{msg}' in: {e}"
        );
        assert!(
            !out.join("frame_0000.exr").exists(),
            "{extra:?} rendered a frame"
        );
    }
    // An output folder below a regular file cannot be made.
    let file = tmp("render-file");
    std::fs::write(&file, b"x").unwrap();
    let mut args = vec!["render", "cornell", "--frames", "0"];
    args.extend_from_slice(SMALL);
    let sub = file.join("sub");
    args.extend_from_slice(&["--out", sub.to_str().unwrap()]);
    let r = irad(&args);
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(
        !r.status.success() && e.contains("cannot create the output folder"),
        "{e}"
    );
    std::fs::remove_file(&file).unwrap();
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn metrics_compares_folders_and_names_bad_files() {
    use glam::Vec3;
    use irad::image::Hdr;
    let root = tmp("metrics");
    let (test, reference) = (root.join("test"), root.join("ref"));
    std::fs::create_dir_all(&test).unwrap();
    std::fs::create_dir_all(&reference).unwrap();
    let img = |v: f32, w: u32| Hdr {
        width: w,
        height: 2,
        data: vec![Vec3::splat(v); (w * 2) as usize],
    };
    // The test alternates by +-0.1 around a still reference: F1 = 0.2 exactly.
    for f in 0..4u32 {
        img(0.5, 3)
            .write_exr(&reference.join(format!("frame_{f:04}.exr")))
            .unwrap();
        img(if f % 2 == 0 { 0.6 } else { 0.4 }, 3)
            .write_exr(&test.join(format!("frame_{f:04}.exr")))
            .unwrap();
    }
    let o = irad(&[
        "metrics",
        test.to_str().unwrap(),
        reference.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(test.join("metrics.json")).unwrap()).unwrap();
    assert!(
        (m["flicker_f1"].as_f64().unwrap() - 0.2).abs() < 1e-5,
        "{}",
        m["flicker_f1"]
    );
    assert_eq!(
        std::fs::read_to_string(test.join("metrics.csv"))
            .unwrap()
            .lines()
            .count(),
        5
    );

    let fails = |why: &str, file: &str| {
        let o = irad(&[
            "metrics",
            test.to_str().unwrap(),
            reference.to_str().unwrap(),
        ]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && e.contains(file),
            "{why}: expected {file} in: {e}"
        );
    };
    // A reference frame of another size.
    img(0.5, 4)
        .write_exr(&reference.join("frame_0002.exr"))
        .unwrap();
    fails("mismatched size", "frame_0002.exr");
    img(0.5, 3)
        .write_exr(&reference.join("frame_0002.exr"))
        .unwrap();
    // A test frame without a reference frame.
    img(0.5, 3).write_exr(&test.join("frame_0004.exr")).unwrap();
    fails("missing frame", "frame_0004.exr");
    std::fs::remove_file(test.join("frame_0004.exr")).unwrap();
    // An unreadable file.
    std::fs::write(reference.join("frame_0001.exr"), b"not an image").unwrap();
    fails("unreadable", "frame_0001.exr");
    std::fs::remove_dir_all(&root).unwrap();
}

/// Printing commands whose reader has gone (`irad scenes FILE | head -1`) exit quietly with
/// status 0: no "failed printing to stdout" panic, nothing on stderr. The pipe's read end is
/// closed before irad starts, so every write fails (no race with the reader).
#[test]
fn printing_into_a_closed_pipe_exits_quietly() {
    let cases: &[&[&str]] = &[
        &["scenes"],
        &["scenes", "cornell"],
        &["scenes", "cornell", "--generate", "/nonexistent-unused"],
        &["reference", "cornell", "--size", "4x4", "--spp", "1"],
    ];
    for args in cases {
        let mut args = args.to_vec();
        let out = tmp("pipe");
        if args[0] == "reference" {
            args.extend(["--out", out.to_str().unwrap()]);
        }
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let o = common::irad_command()
            .args(&args)
            .stdout(writer)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "irad {}: {e}", args.join(" "));
        assert!(
            !e.contains("panicked") && !e.contains("Broken pipe"),
            "irad {}: {e}",
            args.join(" ")
        );
        let _ = std::fs::remove_dir_all(&out);
    }
}

/// `--camera` replaces the scene's camera, animated or not, in every frame. From below the
/// light of the Cornell box looking up at it (20 degrees): the light (Le red 18.387) fills the
/// middle and, by the geometry, 0.60 of the picture (0.46 x 0.38 m seen from 1.518 m, cos 0.98,
/// in a 0.535 m square view); the orbiting camera of cornell-orbit is ignored in frames 0 and
/// 2 alike. Looking straight down at the floor, no pixel is near the light's radiance. The
/// reference path tracer takes the same camera.
#[test]
fn a_render_with_camera_sees_what_the_camera_points_at() {
    let read = |d: &PathBuf, f: &str| irad::image::Hdr::read(&d.join(f)).unwrap();
    let frac_lit = |img: &irad::image::Hdr| {
        img.data.iter().filter(|p| p.x > 15.0).count() as f32 / img.data.len() as f32
    };
    let up = "0,-0.5,0.3:0,0.99,0.01:20";
    let out = tmp("camera-up");
    let o = irad(
        &[
            &[
                "render",
                "cornell-orbit",
                "--camera",
                up,
                "--frames",
                "0..3",
            ],
            SMALL,
            &["--out", out.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["frame_0000.exr", "frame_0002.exr"] {
        let img = read(&out, f);
        let c = img.at(16, 16);
        // Measured 0.60 lit and a centre of 18.6 (Le plus the light's own indirect light).
        let lit = frac_lit(&img);
        assert!((lit - 0.60).abs() < 0.06, "{f}: {lit} of the pixels lit");
        assert!((c.x - 18.387).abs() < 0.5, "{f}: centre {c}");
    }
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["settings"]["sequence"]["camera"], up);
    // Without --camera the orbit camera sees the light small, near the top: measured 0.008.
    let plain = tmp("camera-plain");
    let o = irad(
        &[
            &["render", "cornell-orbit", "--frames", "0"],
            SMALL,
            &["--out", plain.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lit = frac_lit(&read(&plain, "frame_0000.exr"));
    assert!(lit < 0.05, "{lit}");
    // Looking down at the floor: measured brightest red 0.52.
    let down = tmp("camera-down");
    let o = irad(
        &[
            &["render", "cornell", "--camera", "0,0.5,0.5:0,-1,0.5:40"],
            SMALL,
            &["--out", down.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = read(&down, "frame_0000.exr");
    let max = img.data.iter().map(|p| p.x).fold(0.0, f32::max);
    assert!(max > 0.05 && max < 2.0, "brightest red {max}");
    // The reference from below the light: measured 0.53 lit at 4 samples a pixel.
    let r = tmp("camera-ref");
    let o = irad(&[
        "reference",
        "cornell",
        "--camera",
        up,
        "--size",
        "32x32",
        "--spp",
        "4",
        "--out",
        r.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lit = frac_lit(&read(&r, "frame_0000.exr"));
    assert!((lit - 0.60).abs() < 0.1, "reference: {lit} lit");
    for d in [out, plain, down, r] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// A newcomer's slips: `--out` naming a file, a misspelled built-in, and one frame counted
/// as one (each message checked; none renders anything).
#[test]
fn a_newcomers_slips_get_plain_answers() {
    let dir = tmp("slips");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("notes.txt");
    std::fs::write(&file, b"mine").unwrap();
    let o = irad(&[
        "render",
        "--size",
        "8x8",
        "--frames",
        "0",
        "--out",
        file.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("is a file, not a folder"),
        "{err}"
    );
    assert!(!err.contains("os error 17"), "{err}");
    assert_eq!(
        std::fs::read(&file).unwrap(),
        b"mine",
        "the user's file changed"
    );
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let o = irad(&[
        "render",
        "cornel-orbit",
        "--size",
        "8x8",
        "--frames",
        "0",
        "--out",
        out,
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("did you mean 'cornell-orbit'?"), "{err}");
    // Far from every built-in: no guess.
    let o = irad(&[
        "render", "kitchen", "--size", "8x8", "--frames", "0", "--out", out,
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("not a built-in scene") && !err.contains("did you mean"),
        "{err}"
    );
    let one = dir.join("one");
    let o = irad(&[
        "reference",
        "cornell",
        "--size",
        "8x8",
        "--spp",
        "2",
        "--out",
        one.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && text.contains("wrote 1 frame to"),
        "{text}"
    );
}

/// Issue 24 item 3: a scene whose buffer lies outside its folder is refused by every command
/// that loads scenes, naming the URI and `--allow-outside-paths`, which lets it load.
#[test]
fn a_buffer_outside_the_scene_folder_needs_allow_outside_paths() {
    use base64::Engine;
    let top = tmp("outside");
    let dir = top.join("scene");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.gltf"))
        .unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    std::fs::write(top.join("outside.bin"), bin).unwrap();
    doc["buffers"][0]["uri"] = serde_json::json!("../outside.bin");
    let scene = dir.join("s.gltf");
    std::fs::write(&scene, doc.to_string()).unwrap();
    let scene = scene.to_str().unwrap();
    let out = top.join("out");
    let out = out.to_str().unwrap();
    let reference = [
        "reference",
        scene,
        "--size",
        "4x4",
        "--spp",
        "1",
        "--out",
        out,
    ];
    for args in [&["scenes", scene][..], &reference[..]] {
        let o = irad(args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(e.contains("buffer 0 refers to '../outside.bin'"), "{e}");
        assert!(e.contains("--allow-outside-paths"), "{e}");
        let o = irad(&[args, &["--allow-outside-paths"]].concat());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{args:?}: {e}");
    }
}

/// Issue 24 item 7: shadow maps past the memory cap and a candidate count past its cap are
/// refused before any work, naming their flags, and no output folder is made.
#[test]
fn oversized_shadow_maps_and_candidates_are_refused_before_any_folder() {
    let out = tmp("too-big");
    let o = out.to_str().unwrap();
    for (args, flags) in [
        (
            &["--shadow-size", "4096", "--light-samples", "64"][..],
            &["--shadow-size", "--light-samples", "4 GiB"][..],
        ),
        (
            &["--sampler", "mh", "--candidates", "16777216"][..],
            &["--candidates", "1048576"][..],
        ),
    ] {
        let base = ["render", "cornell", "--frames", "0..1", "--out", o];
        let r = irad(&[&base[..], args].concat());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{args:?} ran");
        for f in flags {
            assert!(err.contains(f), "{f} missing: {err}");
        }
        assert!(!out.exists(), "{args:?} made {o}");
    }
}

/// Issue 24 item 8: `irad bench` refuses the flags it would ignore (each --configs entry sets
/// the VPL count and size), and a bad --configs entry is named as such.
#[test]
fn bench_refuses_flags_it_ignores_and_names_configs() {
    for (args, expect) in [
        (&["--vpls", "0"][..], "--vpls is not used by `irad bench`"),
        (&["--size", "64x64"], "--size is not used by `irad bench`"),
        (
            &["--configs", "0@64x64"],
            "--configs 0@64x64: the VPL count 0 is out of range",
        ),
    ] {
        let r = irad(&[&["bench"][..], args].concat());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{args:?} ran");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!err.contains("--vpls 0 is"), "{err}");
    }
}
