//! Issue 23 item 4, the small parts: EXT_mesh_gpu_instancing draws every instance, an emitter
//! without power gets a warning naming it, and the automatic camera never starts inside
//! closed geometry.

use crate::common::quads::{load, Quads};
use glam::{Quat, Vec3};
use serde_json::json;

/// Three instances of a 1 x 1 quad (facing +y) under a node moved by (0, 0, -5): the first
/// moved by +x 2, the second turned a quarter about z (facing -x) and the third scaled by 3.
#[test]
fn ext_mesh_gpu_instancing_draws_every_instance() {
    let mut q = Quads::default();
    let grey = q.material(0.5, 0.0, true);
    let light = q.material(0.0, 5.0, false);
    let t = q.floats(&[2., 0., 0., 0., 0., 0., 0., 0., 0.], "VEC3");
    let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2).to_array();
    let r = q.floats(
        &[[0., 0., 0., 1.], quarter, [0., 0., 0., 1.]].concat(),
        "VEC4",
    );
    let s = q.floats(&[1., 1., 1., 1., 1., 1., 3., 3., 3.], "VEC3");
    q.quad(
        [0.; 3],
        [0., 0., 0.5],
        [0.5, 0., 0.],
        grey,
        json!({ "translation": [0., 0., -5.], "extensions": { "EXT_mesh_gpu_instancing": {
            "attributes": { "TRANSLATION": t, "ROTATION": r, "SCALE": s } } } }),
    );
    q.quad([0., 4., 0.], [0.5, 0., 0.], [0., 0., 0.5], light, json!({}));
    let scene = load(&q.finish());
    assert!(
        scene
            .warnings
            .iter()
            .all(|w| !w.contains("EXT_mesh_gpu_instancing")),
        "{:?}",
        scene.warnings
    );
    let f = scene.at(0.0);
    let grey_tris: Vec<usize> = (0..f.tris.len())
        .filter(|&i| f.tri_material[i] == grey as u32)
        .collect();
    assert_eq!(grey_tris.len(), 6, "three instances of two triangles");
    let centre = |k: usize| {
        let (a, b) = (grey_tris[2 * k], grey_tris[2 * k + 1]);
        let sum: Vec3 = f.tris[a].iter().chain(&f.tris[b]).copied().sum();
        (sum / 6.0, f.normals[a], f.areas[a] + f.areas[b])
    };
    let expected = [
        (Vec3::new(2., 0., -5.), Vec3::Y, 1.0f32),
        (Vec3::new(0., 0., -5.), Vec3::NEG_X, 1.0),
        (Vec3::new(0., 0., -5.), Vec3::Y, 9.0),
    ];
    for (k, (c, n, area)) in expected.into_iter().enumerate() {
        let (fc, fnorm, fa) = centre(k);
        // The quad's two triangles' corners average off the centre by a sixth of a diagonal.
        assert!(
            (fc - c).length() < 0.5 * area.sqrt()
                && (fnorm - n).length() < 1e-5
                && (fa - area).abs() < 1e-4,
            "instance {k}: centre {fc}, normal {fnorm}, area {fa}; expected {c}, {n}, {area}"
        );
    }
}

/// A floor, a quad light, and the emitter without power `dark` adds: the loader's warnings.
fn warnings_with(dark: impl FnOnce(&mut Quads) -> serde_json::Value) -> Vec<String> {
    let mut q = Quads::default();
    let grey = q.material(0.5, 0.0, true);
    let light = q.material(0.0, 5.0, false);
    q.quad([0.; 3], [0., 0., 2.], [2., 0., 0.], grey, json!({}));
    q.quad([0., 2., 0.], [0.5, 0., 0.], [0., 0., 0.5], light, json!({}));
    let mut doc = dark(&mut q);
    if doc.is_null() {
        doc = q.finish();
    }
    load(&doc).warnings
}

#[test]
fn an_emitter_without_power_is_named_in_a_warning() {
    // A material with emissiveFactor 1 and emissive strength 0 (as WaterBottle's, 0 W).
    let w = warnings_with(|q| {
        let m = q.material(0.5, 1.0, false);
        let mut doc = {
            q.quad([0., 1., 0.], [0.2, 0., 0.], [0., 0., 0.2], m, json!({}));
            std::mem::take(q).finish()
        };
        doc["materials"][m]["name"] = json!("bottle");
        doc["materials"][m]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] =
            json!(0.0);
        doc
    });
    let hits: Vec<&String> = w.iter().filter(|w| w.contains("emits nothing")).collect();
    assert!(
        hits.len() == 1 && hits[0].contains("material 2 ('bottle')"),
        "{w:?}"
    );
    // A point light of intensity 0.
    let w = warnings_with(|q| {
        let mut doc = std::mem::take(q).finish();
        doc["extensionsUsed"] = json!(["KHR_materials_emissive_strength", "KHR_lights_punctual"]);
        doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
            { "type": "point", "name": "bulb", "intensity": 0.0 }] } });
        let n = doc["nodes"].as_array().unwrap().len();
        doc["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "translation": [0., 1., 0.], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
        doc["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(n));
        doc
    });
    let hits: Vec<&String> = w.iter().filter(|w| w.contains("emits nothing")).collect();
    assert!(
        hits.len() == 1 && hits[0].contains("light 0 ('bulb')"),
        "{w:?}"
    );
    // Nothing to say about a scene whose emitters all shine.
    let w = warnings_with(|_| serde_json::Value::Null);
    assert!(w.iter().all(|w| !w.contains("emits nothing")), "{w:?}");
}

/// A lamp inside a closed single-sided box (as a light inside a helmet's shell): what it
/// lights is the box's inside, which the eyes inside the box would see best. The automatic
/// camera stays outside.
#[test]
fn the_automatic_camera_never_starts_inside_closed_geometry() {
    let mut q = Quads::default();
    let shell = q.material(0.8, 0.0, false);
    let grey = q.material(0.5, 0.0, true);
    let light = q.material(0.0, 5.0, false);
    q.cube([-1.; 3], [1.; 3], shell);
    q.quad([0., -1.5, 0.], [0., 0., 4.], [4., 0., 0.], grey, json!({}));
    q.quad(
        [0., 0.5, 0.],
        [0.2, 0., 0.],
        [0., 0., 0.2],
        light,
        json!({}),
    );
    let scene = load(&q.finish());
    let f = scene.at(0.0);
    assert!(f.instances.iter().any(|i| i.closed), "the box is a solid");
    let eye = f.camera.position;
    println!("automatic camera at {eye}");
    assert!(
        eye.abs().max_element() > 1.0,
        "the camera is inside the box at {eye}"
    );
}

/// An emissive texture black wherever its material is used (emissiveFactor 1): the material
/// is named in a warning.
#[test]
fn an_emissive_texture_black_everywhere_is_named_in_a_warning() {
    use base64::Engine;
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([0, 0, 0, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let w = warnings_with(|q| {
        let m = q.material(0.5, 1.0, false);
        q.quad([0., 1., 0.], [0.2, 0., 0.], [0., 0., 0.2], m, json!({}));
        let mut doc = std::mem::take(q).finish();
        doc["materials"][m]["name"] = json!("label");
        doc["materials"][m]["emissiveTexture"] = json!({ "index": 0 });
        doc["textures"] = json!([{ "source": 0 }]);
        doc["images"] = json!([{ "uri": format!("data:image/png;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&png)) }]);
        doc
    });
    let hits: Vec<&String> = w.iter().filter(|w| w.contains("emits nothing")).collect();
    assert!(
        hits.len() == 1 && hits[0].contains("material 2 ('label')") && hits[0].contains("black"),
        "{w:?}"
    );
}
