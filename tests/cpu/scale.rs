//! Issue 23 item 2: where 32-bit floats cannot resolve a scene's shape, a clear error
//! instead of a black frame; where the placement alone is far (a node's translation), the
//! scene loads and keeps its shape.

use crate::common::quads::{cornell_like, Quads};
use irad::scene::load::load_slice;
use serde_json::json;

fn load(doc: &serde_json::Value) -> Result<irad::scene::Scene, String> {
    let bytes = serde_json::to_vec(doc).unwrap();
    load_slice(&bytes, "far.gltf", "far", None).map_err(|e| e.to_string())
}

/// A 20 cm panel and a light whose vertices themselves lie 1e6 from the origin: floats there
/// are 0.0625 apart, the panel's shape is gone. The message names the file and the mesh.
#[test]
fn vertices_too_far_for_their_shape_are_an_error() {
    for at in [1e6f32, 1e5] {
        let mut q = Quads::default();
        let grey = q.material(0.5, 0.0, true);
        let light = q.material(0.0, 10.0, false);
        q.quad([at, 0., at], [0.1, 0., 0.], [0., 0., 0.1], grey, json!({}));
        q.quad([at, 1., at], [0.1, 0., 0.], [0., 0., 0.1], light, json!({}));
        let r = load(&q.finish());
        println!("panel at {at:e}: {:?}", r.as_ref().map(|_| ()));
        if at == 1e6 {
            let e = r.expect_err("an error");
            assert!(
                e.starts_with("far.gltf: mesh ")
                    && e.contains("as the file stores it")
                    && e.contains("0.0625 apart")
                    && e.contains("25.0% of its median edge"),
                "{e}"
            );
        } else {
            // 1e5: floats 0.0078 apart, 3.9% of the 0.2 edges... still too coarse.
            assert!(r.is_err());
        }
    }
    // The same panel 1e3 away (floats 6e-5 apart, 0.03% of an edge) loads.
    let mut q = Quads::default();
    let grey = q.material(0.5, 0.0, true);
    let light = q.material(0.0, 10.0, false);
    q.quad(
        [1e3, 0., 1e3],
        [0.1, 0., 0.],
        [0., 0., 0.1],
        grey,
        json!({}),
    );
    q.quad(
        [1e3, 1., 1e3],
        [0.1, 0., 0.],
        [0., 0., 0.1],
        light,
        json!({}),
    );
    assert!(load(&q.finish()).is_ok());
}

/// Placed 1e6 away by a node's translation, a 2 mm box keeps its shape (the loader moves the
/// scene to the origin, composing the matrices exactly): no error, and its light's gap to the
/// ceiling (0.02 of the box) is still there.
#[test]
fn a_tiny_box_placed_far_by_its_node_loads_whole() {
    let s = load(&cornell_like(1e-3, [1e6, 5e5, -2.5e5])).unwrap();
    let f = s.at(0.0);
    let light = f.emitters.tris[0] as usize;
    let y_light = f.tris[light][0].y;
    let (lo, hi) = f.bounds();
    let gap = (hi.y - y_light) / (hi.y - lo.y);
    assert!((gap - 0.01).abs() < 1e-4, "gap {gap} of the box's height");
}
