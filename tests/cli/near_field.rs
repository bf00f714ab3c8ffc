//! A render says when its emitters' light meets a surface within the distance clamp (a lamp
//! under a ceiling), the case only compensation renders right (docs/math.md section 4): that
//! `--compensate auto` (the default) compensates it, or with `--compensate off` what that leaves
//! out; nothing where the light leaves into the room or with a count given.

use crate::common::{self, irad, quads::Quads};
use serde_json::json;

/// A room (the cube [-1,1]^3 seen from inside) lit by a 0.4 m square lamp 1 mm under the
/// ceiling, facing the ceiling (`up`) or the room.
fn room(up: bool) -> serde_json::Value {
    let mut q = Quads::default();
    let grey = q.material(0.7, 0.0, true);
    let light = q.material(0.0, 10.0, false);
    q.cube([-1.0; 3], [1.0; 3], grey);
    let (u, v) = if up {
        ([0.0, 0.0, 0.2], [0.2, 0.0, 0.0])
    } else {
        ([0.2, 0.0, 0.0], [0.0, 0.0, 0.2])
    };
    q.quad([0.0, 0.999, 0.0], u, v, light, json!({}));
    q.camera([0.0, 0.0, 0.5], 1.0);
    q.finish()
}

fn render_note(up: bool, extra: &[&str]) -> Option<String> {
    let dir = common::fresh_dir(&format!("near-field-{up}"));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("room.gltf");
    std::fs::write(&scene, room(up).to_string()).unwrap();
    let out = dir.join("out");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--frames",
        "0",
        "--size",
        "16x16",
        "--vpls",
        "64",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let o = irad(&args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
    err.lines()
        .find(|l| l.contains("distance clamp"))
        .map(str::to_owned)
}

#[test]
fn a_lamp_facing_a_ceiling_within_the_clamp_gets_a_note() {
    let note = render_note(true, &[]).expect("no note for a lamp 1 mm under the ceiling");
    assert!(
        note.starts_with("note: scene")
            && note.contains("100%")
            && note.contains("compensating the clamp with 64 paths a pixel"),
        "{note}"
    );
    assert_eq!(render_note(false, &[]), None, "a lamp lighting the room");
    let off = render_note(true, &["--compensate", "off"]).expect("no note with --compensate off");
    assert!(
        off.contains("darkens") && off.contains("--compensate auto"),
        "{off}"
    );
    assert_eq!(
        render_note(true, &["--compensate", "4"]),
        None,
        "--compensate given"
    );
}
