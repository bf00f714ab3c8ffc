//! Scenes: the built-ins, animation through glTF files, and bad input.

use base64::Engine;
use glam::{Mat4, Vec3, Vec4};
use irad::scene::{builtin, load::load_slice, Scene};
use serde_json::{json, Value};

fn builtin_json(name: &str) -> Value {
    serde_json::from_str(builtin::find(name).unwrap().gltf).unwrap()
}

fn load_json(v: &Value) -> Result<Scene, String> {
    load_slice(v.to_string().as_bytes(), "test.gltf", "test", None).map_err(|e| e.to_string())
}

fn node_index(scene: &Scene, name: &str) -> usize {
    scene.nodes.iter().position(|n| n.name == name).unwrap()
}

#[test]
fn committed_scene_files_are_what_the_generator_makes() {
    for b in builtin::BUILTINS {
        let generated = builtin::generate(b.name).unwrap();
        assert!(
            generated == b.gltf,
            "scenes/{}.gltf differs from the generator: run `irad scenes --generate scenes`",
            b.name
        );
    }
}

#[test]
fn cornell_is_mitsubas_box() {
    let scene = builtin::load("cornell").unwrap().unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let f = scene.at(0.0);
    assert_eq!(f.tris.len(), 36); // 5 walls and the light (2 each), two cubes (12 each)
    let (lo, hi) = f.bounds();
    // Mitsuba's tall box reaches 0.01 below the floor (-0.4 - 0.61).
    assert!(
        (lo - Vec3::new(-1.0, -1.01, -1.0)).length() < 1e-6 && (hi - Vec3::ONE).length() < 1e-6,
        "{lo} {hi}"
    );
    // The light: 0.46 x 0.38 at y = 0.99, facing down, radiance as Mitsuba's.
    assert_eq!(f.emitters.tris.len(), 2);
    let le = Vec3::new(18.387, 13.9873, 6.75357);
    let area = 0.46 * 0.38;
    let power = le * std::f32::consts::PI * area;
    assert!(
        (f.emitters.total_power - power).abs().max_element() < 1e-3,
        "{}",
        f.emitters.total_power
    );
    for &t in &f.emitters.tris {
        assert_eq!(f.normals[t as usize], Vec3::NEG_Y);
        assert!((f.emission(t as usize) - le).abs().max_element() < 1e-4);
        for p in f.tris[t as usize] {
            assert!(
                (p.y - 0.99).abs() < 1e-6
                    && p.x.abs() <= 0.23 + 1e-6
                    && (-0.18 - 1e-6..=0.20 + 1e-6).contains(&p.z)
            );
        }
    }
    // Wall colours and inward normals.
    let wall = |p: Vec3| {
        let tr = irad::trace::Tracer::new(&f);
        let h = tr
            .intersect(
                Vec3::new(0.0, 0.3, 0.9),
                (p - Vec3::new(0.0, 0.3, 0.9)).normalize(),
                10.0,
            )
            .unwrap();
        (f.albedo(h.tri as usize), f.normals[h.tri as usize])
    };
    let (red, n) = wall(Vec3::new(-1.0, 0.3, 0.9));
    assert!((red - Vec3::new(0.570068, 0.0430135, 0.0443706)).length() < 1e-6 && n == Vec3::X);
    let (green, n) = wall(Vec3::new(1.0, 0.3, 0.9));
    assert!((green - Vec3::new(0.105421, 0.37798, 0.076425)).length() < 1e-6 && n == Vec3::NEG_X);
    // The boxes' world matrices are DESIGN.md's.
    let world = scene.world_matrices(0.0);
    let large = Mat4::from_cols_array_2d(&[
        [0.28491, 0.0, -0.0939491, 0.0],
        [0.0, 0.61, 0.0, 0.0],
        [0.0939491, 0.0, 0.28491, 0.0],
        [-0.33, -0.4, -0.28, 1.0],
    ]);
    let small = Mat4::from_cols_array_2d(&[
        [0.286891, 0.0, 0.0877115, 0.0],
        [0.0, 0.3, 0.0, 0.0],
        [-0.0877115, 0.0, 0.286891, 0.0],
        [0.335, -0.7, 0.38, 1.0],
    ]);
    assert!(world[node_index(&scene, "large_box")].abs_diff_eq(large, 1e-5));
    assert!(world[node_index(&scene, "small_box")].abs_diff_eq(small, 1e-5));
    // The camera: at (0,0,3.9), looking down -z, 39.3077 degrees.
    let c = f.camera;
    assert!((c.position - Vec3::new(0.0, 0.0, 3.9)).length() < 1e-6);
    assert!((c.forward - Vec3::NEG_Z).length() < 1e-6 && (c.up - Vec3::Y).length() < 1e-6);
    assert!((c.yfov.to_degrees() - 39.3077).abs() < 1e-3);
}

#[test]
fn every_builtin_loads_and_animates_as_it_says() {
    for b in builtin::BUILTINS {
        let scene = builtin::load(b.name).unwrap().unwrap();
        assert!(
            scene.warnings.is_empty(),
            "{}: {:?}",
            b.name,
            scene.warnings
        );
        let f0 = scene.at(0.0);
        let f1 = scene.at(1.0);
        let animated = scene.duration() > 0.0;
        assert_eq!(
            animated,
            b.name != "cornell" && b.name != "furnace",
            "{}",
            b.name
        );
        assert!(!animated || (2.0..=4.0).contains(&scene.duration()));
        match b.name {
            "cornell-orbit" => {
                assert_eq!(f0.tris, f1.tris);
                assert_ne!(f0.camera, f1.camera);
                // Always at 3.9 from the centre, looking at it.
                for t in [0.3, 0.75, 1.9] {
                    let c = scene.at(t).camera;
                    assert!(
                        (c.position.length() - 3.9).abs() < 0.02,
                        "{t}: {}",
                        c.position
                    );
                    assert!(c.forward.dot(-c.position.normalize()) > 0.999);
                }
            }
            "cornell-light" | "cornell-box" => {
                assert_ne!(f0.tris, f1.tris);
                assert_eq!(f0.camera, f1.camera);
            }
            _ => {}
        }
    }
}

#[test]
fn linear_and_slerp_through_gltf() {
    // cornell-box: small box LINEAR from (0.335,-0.7,0.38) at t=0 to (-0.25,-0.7,0.6) at 1.5,
    // rotation -17 -> 30 degrees about y.
    let scene = builtin::load("cornell-box").unwrap().unwrap();
    let w = scene.world_matrices(0.75)[node_index(&scene, "small_box")];
    let (s, r, t) = w.to_scale_rotation_translation();
    assert!((t - Vec3::new(0.0425, -0.7, 0.49)).length() < 1e-5, "{t}");
    assert!((s - Vec3::splat(0.3)).length() < 1e-5);
    let (axis, angle) = r.to_axis_angle();
    assert!(
        (axis.y.signum() * angle.to_degrees() - 6.5).abs() < 1e-3,
        "{}",
        angle.to_degrees()
    );
}

#[test]
fn cubic_spline_through_gltf() {
    // cornell-light: x keys -0.5, 0.5, -0.5 at 0, 1.5, 3 with zero tangents.
    // At t = 0.375, s = 0.25: h00 = 0.84375, h01 = 0.15625: x = -0.34375.
    let scene = builtin::load("cornell-light").unwrap().unwrap();
    for (t, x) in [
        (0.375, -0.34375),
        (0.75, 0.0),
        (1.5, 0.5),
        (2.625, -0.34375),
    ] {
        let m = scene.world_matrices(t)[node_index(&scene, "light")];
        assert!((m.w_axis.x - x).abs() < 1e-5, "t={t}: {}", m.w_axis.x);
        assert!((m.w_axis.y - 0.99).abs() < 1e-6);
    }
}

#[test]
fn step_through_gltf() {
    let mut v = builtin_json("cornell-box");
    for s in v["animations"][0]["samplers"].as_array_mut().unwrap() {
        s["interpolation"] = json!("STEP");
    }
    let scene = load_json(&v).unwrap();
    let n = node_index(&scene, "small_box");
    assert!(
        (scene.world_matrices(1.49)[n].w_axis.truncate() - Vec3::new(0.335, -0.7, 0.38)).length()
            < 1e-6
    );
    assert!(
        (scene.world_matrices(1.5)[n].w_axis.truncate() - Vec3::new(-0.25, -0.7, 0.6)).length()
            < 1e-6
    );
}

#[test]
fn glb_loads_like_gltf() {
    // Pack cornell as .glb: JSON chunk + BIN chunk with the decoded buffer.
    let mut v = builtin_json("cornell");
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    v["buffers"][0] = json!({ "byteLength": bin.len() });
    let mut js = v.to_string().into_bytes();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let mut b = bin.clone();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + js.len() + 8 + b.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(js.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&js);
    glb.extend_from_slice(&(b.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&b);
    let scene = load_slice(&glb, "cornell.glb", "cornell", None).unwrap();
    let reference = builtin::load("cornell").unwrap().unwrap();
    assert_eq!(scene.at(0.0).tris, reference.at(0.0).tris);
}

// ---- Bad input: one test per case, each checking that the message names the problem. ----

#[test]
fn not_gltf() {
    let e = load_slice(b"P3 hello, not a scene", "bad.gltf", "bad", None)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("bad.gltf: not a glTF 2.0 file"), "{e}");
}

#[test]
fn missing_buffer_file() {
    let mut v = builtin_json("cornell");
    v["buffers"][0]["uri"] = json!("does-not-exist.bin");
    let e = load_json(&v).unwrap_err();
    assert!(
        e.contains("test.gltf") && e.contains("buffer 0") && e.contains("does-not-exist.bin"),
        "{e}"
    );
}

#[test]
fn short_buffer() {
    let mut v = builtin_json("cornell");
    let len = v["buffers"][0]["byteLength"].as_u64().unwrap();
    v["buffers"][0]["byteLength"] = json!(len + 400);
    let e = load_json(&v).unwrap_err();
    assert!(e.contains("buffer 0 is short"), "{e}");
    // A view past the end of its buffer is refused too, without a panic.
    let mut v = builtin_json("cornell");
    v["bufferViews"][0]["byteOffset"] = json!(len - 8);
    let e = load_json(&v).unwrap_err();
    assert!(
        e.contains("bufferView 0") || e.contains("invalid glTF"),
        "{e}"
    );
}

#[test]
fn only_non_triangle_primitives() {
    let mut v = builtin_json("cornell");
    for m in v["meshes"].as_array_mut().unwrap() {
        m["primitives"][0]["mode"] = json!(1);
    }
    let e = load_json(&v).unwrap_err();
    assert!(
        e.contains("no triangle primitives") && e.contains("Lines"),
        "{e}"
    );
}

#[test]
fn no_camera_is_a_warning_and_a_camera_that_sees_the_lit_box() {
    let mut v = builtin_json("cornell");
    for n in v["nodes"].as_array_mut().unwrap() {
        n.as_object_mut().unwrap().remove("camera");
    }
    let scene = load_json(&v).unwrap();
    assert_eq!(scene.warnings.len(), 1);
    assert!(
        scene.warnings[0].contains("no perspective camera")
            && scene.warnings[0].contains("what the lights light"),
        "{:?}",
        scene.warnings
    );
    // Through the open front: the camera is in front of the box (z > 1) and its rays hit the
    // inside of the box, not the outside of a wall or the ceiling.
    let f = scene.at(0.0);
    let c = f.camera;
    assert!(c.position.z > 1.0, "{c:?}");
    let tr = irad::trace::Tracer::new(&f);
    let (mut hit, mut inside) = (0, 0);
    for y in 0..16 {
        for x in 0..16 {
            let d = c.ray_dir(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5), 16, 16);
            if let Some(h) = tr.intersect(c.position, d, 100.0) {
                hit += 1;
                inside += (f.normals[h.tri as usize].dot(d) < 0.0) as usize;
            }
        }
    }
    // Measured: 100 of 256 rays hit the box, all 100 on a front (inner) face.
    assert!(
        hit >= 67 && inside == hit,
        "{inside} of {hit} hits (256 rays) see the box from inside"
    );
}

#[test]
fn no_emitter() {
    let mut v = builtin_json("cornell");
    for m in v["materials"].as_array_mut().unwrap() {
        m.as_object_mut().unwrap().remove("emissiveFactor");
    }
    // Loaded under the default sky, with the reason kept for the note (and for
    // `--environment none`, which refuses it).
    let s = load_json(&v).unwrap();
    let e = s.unlit.clone().unwrap();
    assert!(
        e.contains("no emitter") && e.contains("nothing to light"),
        "{e}"
    );
    assert!(s.environment.as_ref().is_some_and(|e| e.is_uniform()));
    assert!(!s.at(0.0).emitters.is_empty());
}

#[test]
fn nan_and_infinite_positions() {
    for bad in [f32::NAN, f32::INFINITY] {
        let mut v = builtin_json("cornell");
        let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
        let mut bin = base64::engine::general_purpose::STANDARD
            .decode(uri.split_once(',').unwrap().1)
            .unwrap();
        bin[4..8].copy_from_slice(&bad.to_le_bytes()); // y of the floor's first vertex
        v["buffers"][0]["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        ));
        let e = load_json(&v).unwrap_err();
        assert!(
            e.contains("NaN or infinite position") && e.contains("floor"),
            "{e}"
        );
    }
}

#[test]
fn required_extension_it_lacks() {
    let mut v = builtin_json("cornell");
    v["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    v["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = load_json(&v).unwrap_err();
    assert!(
        e.contains("requires the glTF extension KHR_draco_mesh_compression"),
        "{e}"
    );
}

#[test]
fn unused_features_warn_once_per_kind() {
    let mut v = builtin_json("cornell");
    for m in v["materials"].as_array_mut().unwrap() {
        m["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
    }
    v["extensionsUsed"] = json!(["KHR_materials_emissive_strength", "KHR_materials_clearcoat"]);
    let scene = load_json(&v).unwrap();
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
    assert!(scene.warnings.iter().any(|w| w.contains("metallic")));
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("KHR_materials_clearcoat")));
}

#[test]
fn path_errors_name_the_file() {
    let e = builtin::load_any("/nonexistent/scene.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("/nonexistent/scene.gltf") && e.contains("built-in"),
        "{e}"
    );
    let dir = std::env::temp_dir().join(format!("irad-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("broken.glb");
    std::fs::write(&p, b"glTF\x02\x00\x00\x00garbage").unwrap();
    let e = builtin::load_any(p.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("broken.glb") && e.contains("not a glTF"), "{e}");
    let _ = Vec4::ZERO;
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `irad scenes FILE` names the animated nodes, what their channels key and what they move.
#[test]
fn inspection_names_the_animated_nodes() {
    let text = |v: &Value| irad::scene::inspect::inspect(&load_json(v).unwrap()).to_string();
    // cornell-box with its moving block renamed: keyed translation and rotation, moving no
    // camera, light or emitter.
    let mut v = builtin_json("cornell-box");
    let nodes = v["nodes"].as_array_mut().unwrap();
    let k = nodes.iter().position(|n| n["name"] == "small_box").unwrap();
    nodes[k]["name"] = json!("crate");
    let t = text(&v);
    let line = format!("  animated    'crate' (node {k}): translation, rotation\n");
    assert!(t.contains(&line), "'{line}' missing from:\n{t}");
    assert_eq!(t.matches("  animated ").count(), 1, "{t}");
    // Unnamed, it is "node K".
    v["nodes"][k].as_object_mut().unwrap().remove("name");
    let t = text(&v);
    let line = format!("  animated    node {k}: translation, rotation\n");
    assert!(t.contains(&line), "'{line}' missing from:\n{t}");
    // A keyed parent moves the emitting light mesh below it, and the camera below another
    // keyed parent is named as moved.
    let mut v = builtin_json("cornell-light");
    let nodes = v["nodes"].as_array_mut().unwrap();
    let light = nodes.iter().position(|n| n["name"] == "light").unwrap();
    let camera = nodes
        .iter()
        .position(|n| n.get("camera").is_some())
        .unwrap();
    nodes.push(json!({ "name": "rig", "children": [light] }));
    nodes.push(json!({ "name": "dolly", "children": [camera] }));
    let (rig, dolly) = (nodes.len() - 2, nodes.len() - 1);
    let roots = v["scenes"][0]["nodes"].as_array_mut().unwrap();
    roots.retain(|r| *r != json!(light) && *r != json!(camera));
    roots.extend([json!(rig), json!(dolly)]);
    // Both parents keyed by the light's own sampler (a sampler may serve several channels).
    let mut g = v.clone();
    let channels = g["animations"][0]["channels"].as_array_mut().unwrap();
    channels.push(json!({ "sampler": 0, "target": { "node": rig, "path": "translation" } }));
    channels.push(json!({ "sampler": 0, "target": { "node": dolly, "path": "translation" } }));
    let t = text(&g);
    for line in [
        format!("  animated    'light' (node {light}): translation (moves an emitter)\n"),
        format!("  animated    'rig' (node {rig}): translation (moves an emitter)\n"),
        format!("  animated    'dolly' (node {dolly}): translation (moves the camera)\n"),
    ] {
        assert!(t.contains(&line), "'{line}' missing from:\n{t}");
    }
}
