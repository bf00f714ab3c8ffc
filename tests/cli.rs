//! The `irad` binary end to end: outputs, conventions and clear errors.

use std::path::PathBuf;
use std::process::Command;

fn irad(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_irad"))
        .args(args)
        .output()
        .unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("irad-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
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
    assert!(col(3).x > 2.0 * col(3).y, "left column {}", col(3));
    assert!(col(16).y > 1.3 * col(16).x, "right column {}", col(16));
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_arguments_fail_before_rendering_with_clear_messages() {
    let o = irad(&["reference", "--size", "0x16"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("out of range"));
    let o = irad(&["reference", "--frames", "4..2"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("empty"));
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
