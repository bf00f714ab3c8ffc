//! Hostile files and what the loader and the path tracer do with them (issue 24): an emitter
//! the emitter list misses, special files, files outside the scene's folder.

use crate::scene_files::{lit, load};
use base64::Engine;
use irad::reference::{self, ReferenceSettings};
use irad::trace::Tracer;
use serde_json::json;

/// A PNG of `w x h` RGBA texels (row 0 at the top).
fn png(w: u32, h: u32, texels: &[[u8; 4]]) -> Vec<u8> {
    let img = image::RgbaImage::from_raw(w, h, texels.concat()).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// The lit quad seen from inside (camera at z = 0.9, under the light), its floor emitting
/// through a 2 x 2 nearest-filtered checker (white on the diagonal) repeated 32 times: every
/// point of the 32 x 32 lattice the mean emission is taken at lands on a black texel, so the
/// floor emits at three points in four but is not in the emitter list.
fn floor_emits_where_its_mean_does_not() -> serde_json::Value {
    let (mut g, mut doc) = lit();
    let uv = g.floats(&[0., 0., 32., 0., 32., 32., 0., 32.], "VEC2", 2);
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    doc["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    doc["materials"][0]["emissiveTexture"] = json!({ "index": 0 });
    let (w, b) = ([255, 255, 255, 255], [0, 0, 0, 255]);
    let image = base64::engine::general_purpose::STANDARD.encode(png(2, 2, &[w, b, b, w]));
    doc["images"] = json!([{ "uri": format!("data:image/png;base64,{image}") }]);
    doc["samplers"] = json!([{ "magFilter": 9728 }]);
    doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
    doc["nodes"][2]["translation"] = json!([0.5, 0.5, 0.9]);
    g.finish(doc)
}

/// Issue 24 item 1: a path that scatters onto an emitting point of a triangle outside the
/// emitter list panicked in `light_pdf` (index u32::MAX). It now counts with MIS weight 1.
#[test]
fn an_emitter_the_emitter_list_misses_does_not_panic_the_reference() {
    let scene = load(&floor_emits_where_its_mean_does_not()).unwrap();
    let f = scene.at(0.0);
    // What makes the case: the floor (triangles 0 and 1) emits at some points, not on average.
    assert_eq!(f.emitters.tris, vec![2, 3], "only the light quad is listed");
    let emitting = (0..64)
        .filter(|k| {
            f.emission_at(0, (*k as f32 + 0.25) / 128.0, 0.3)
                .max_element()
                > 0.0
        })
        .count();
    assert!(emitting > 16, "the floor emits at {emitting} of 64 points");
    let tracer = Tracer::new(&f);
    let s = ReferenceSettings {
        width: 16,
        height: 16,
        spp: 16,
        seed: 3,
    };
    let img = reference::render(&f, &tracer, &s, &|| {});
    let bad = img.data.iter().filter(|p| !p.is_finite()).count();
    assert_eq!(bad, 0, "{bad} pixels not finite");
    // The camera sees the floor's white texels (emission 1) plus light reflected off them.
    let brightest = img.data.iter().map(|p| p.min_element()).fold(0.0, f32::max);
    assert!(brightest > 1.0, "brightest pixel {brightest}");
}
