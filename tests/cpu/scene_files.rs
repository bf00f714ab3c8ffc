//! Small glTF files written by the tests: hostile input that once crashed, hung or lied
//! (issue 11 item 5), and geometry as the glTF spec says (item 3).

use base64::Engine;
use glam::Vec3;
use irad::scene::{builtin, load::load_slice, Scene};
use serde_json::{json, Value};
use std::time::{Duration, Instant};

/// A glTF under construction: one embedded buffer, accessors added one by one.
#[derive(Default)]
pub(crate) struct Gltf {
    pub(crate) bin: Vec<u8>,
    pub(crate) views: Vec<Value>,
    pub(crate) accessors: Vec<Value>,
}

impl Gltf {
    pub(crate) fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        ty: &str,
        component: u32,
    ) -> usize {
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        crate::common::gltf::accessor(b, v, a, (bytes, count, ty, component))
    }
    pub(crate) fn floats(&mut self, v: &[f32], ty: &str, per: usize) -> usize {
        self.accessor(bytemuck::cast_slice(v), v.len() / per, ty, 5126)
    }
    pub(crate) fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        crate::common::gltf::positions(b, v, a, p)
    }
    pub(crate) fn indices(&mut self, i: &[u32]) -> usize {
        self.accessor(bytemuck::cast_slice(i), i.len(), "SCALAR", 5125)
    }
    /// The whole file: `doc` plus this buffer, its views and accessors.
    pub(crate) fn finish(self, mut doc: Value) -> Value {
        doc["asset"] = json!({ "version": "2.0" });
        doc["accessors"] = json!(self.accessors);
        doc["bufferViews"] = json!(self.views);
        doc["buffers"] = json!([{
            "byteLength": self.bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(&self.bin)),
        }]);
        doc
    }
}

/// A unit quad in the plane z = `z`, facing +z, as four vertices.
pub(crate) fn quad(z: f32) -> [[f32; 3]; 4] {
    [[0., 0., z], [1., 0., z], [1., 1., z], [0., 1., z]]
}

/// Materials: 0 white, 1 emitting 1 (front only).
pub(crate) fn materials() -> Value {
    json!([
        { "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0 } },
        { "pbrMetallicRoughness": { "metallicFactor": 0.0 }, "emissiveFactor": [1.0, 1.0, 1.0] },
    ])
}

/// A lit scene: a white floor quad (mesh 0) facing a light quad above it (mesh 1) facing
/// down, nodes 0 and 1, and a camera node 2 at z = 3 looking down -z.
pub(crate) fn lit() -> (Gltf, Value) {
    let mut g = Gltf::default();
    let floor = g.positions(&quad(0.0));
    let light = g.positions(&quad(1.0));
    let up = g.indices(&[0, 1, 2, 0, 2, 3]);
    let down = g.indices(&[0, 2, 1, 0, 3, 2]);
    let doc = json!({
        "scene": 0,
        "scenes": [{ "nodes": [0, 1, 2] }],
        "nodes": [
            { "name": "floor", "mesh": 0 },
            { "name": "light", "mesh": 1 },
            { "name": "camera", "camera": 0, "translation": [0.5, 0.5, 3.0] },
        ],
        "cameras": [{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.01 } }],
        "meshes": [
            { "primitives": [{ "attributes": { "POSITION": floor }, "indices": up, "material": 0 }] },
            { "primitives": [{ "attributes": { "POSITION": light }, "indices": down, "material": 1 }] },
        ],
        "materials": materials(),
    });
    (g, doc)
}

/// Loads a document, failing the test if loading takes more than 10 s (a hang).
pub(crate) fn load(doc: &Value) -> Result<Scene, String> {
    load_bytes(doc.to_string().into_bytes(), "test.gltf")
}

pub(crate) fn load_bytes(bytes: Vec<u8>, file: &'static str) -> Result<Scene, String> {
    let start = Instant::now();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let r = load_slice(&bytes, file, "test", None).map_err(|e| e.to_string());
        let _ = tx.send(r);
    });
    let r = rx
        .recv_timeout(Duration::from_secs(10))
        .expect("loading hung (or panicked)");
    assert!(start.elapsed() < Duration::from_secs(10));
    r
}

pub(crate) fn refused(doc: &Value, words: &[&str]) {
    let e = load(doc).expect_err("a hostile file was accepted");
    assert!(e.starts_with("test.gltf: "), "{e}");
    for w in words {
        assert!(e.contains(w), "'{w}' missing from: {e}");
    }
}

#[test]
fn the_lit_quad_loads() {
    // The base of the hostile files below must itself load, or they would test nothing.
    let (g, doc) = lit();
    let s = load(&g.finish(doc)).unwrap();
    let f = s.at(0.0);
    assert_eq!(f.tris.len(), 4);
    assert_eq!(f.emitters.tris.len(), 2);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

// ---- Issue 11 item 5: each fuzz finding as a regression test ----

#[test]
fn float_accessor_as_indices_is_refused() {
    // Panicked inside the gltf crate's index reader.
    let (mut g, mut doc) = lit();
    let f = g.floats(&[0.0, 1.0, 2.0], "SCALAR", 1);
    doc["meshes"][0]["primitives"][0]["indices"] = json!(f);
    refused(&g.finish(doc), &["accessor 4", "indices", "unsigned"]);
}

#[test]
fn vertex_at_3e38_is_refused() {
    // Finite but huge: panicked inside obvhs.
    let (mut g, mut doc) = lit();
    let mut q = quad(0.0);
    q[2] = [3e38, 1.0, 0.0];
    let p = g.positions(&q);
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(p);
    refused(&g.finish(doc), &["mesh 0", "vertex 2", "coordinate limit"]);
}

#[test]
fn vertex_moved_to_3e38_by_its_node_is_refused() {
    let (g, mut doc) = lit();
    doc["nodes"][0]["scale"] = json!([1e30, 1e30, 1.0]);
    refused(&g.finish(doc), &["t = 0 s", "coordinate limit"]);
}

#[test]
fn zero_quaternions_are_refused() {
    // A node's zero rotation made NaN vertices (obvhs panicked).
    let (g, mut doc) = lit();
    doc["nodes"][0]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]);
    refused(&g.finish(doc), &["node 0", "zero quaternion"]);
    // The same as an animation key.
    let (mut g, mut doc) = lit();
    let t = g.floats(&[0.0, 1.0], "SCALAR", 1);
    let r = g.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0], "VEC4", 4);
    doc["animations"] = json!([{
        "samplers": [{ "input": t, "output": r }],
        "channels": [{ "sampler": 0, "target": { "node": 0, "path": "rotation" } }],
    }]);
    refused(&g.finish(doc), &["animation 0", "zero quaternion", "key 1"]);
}

#[test]
fn node_cycle_is_refused_without_hanging() {
    let (g, mut doc) = lit();
    doc["nodes"][0]["children"] = json!([3]);
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({ "name": "loop", "children": [0] }));
    refused(&g.finish(doc), &["node 0", "under a cycle"]);
}

#[test]
fn node_dag_with_2_to_the_40_paths_is_refused_without_hanging() {
    // 40 layers of two nodes, each the parent of both nodes of the next layer: 2^40 paths
    // to the floor mesh at the bottom.
    let (g, mut doc) = lit();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    for layer in 0..40 {
        for _ in 0..2 {
            let next = first + 2 * (layer + 1);
            let children = if layer == 39 {
                json!([0])
            } else {
                json!([next, next + 1])
            };
            nodes.push(json!({ "children": children }));
        }
    }
    doc["scenes"][0]["nodes"] = json!([first, first + 1, 1, 2]);
    refused(&g.finish(doc), &["is a child of node", "trees"]);
}

#[test]
fn emission_1e38_is_refused() {
    // Its power overflowed to infinity and the frame to NaN.
    let (g, mut doc) = lit();
    doc["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    doc["materials"][1]["extensions"] =
        json!({ "KHR_materials_emissive_strength": { "emissiveStrength": 1e38 } });
    refused(&g.finish(doc), &["material 1", "limit"]);
}

#[test]
fn scene_1e6_from_the_origin_is_moved_back_and_keeps_its_shape() {
    // Rendered black with exit 0: at 1e6 an f32 step is 0.0625, a third of a Cornell box wall.
    let mut v: Value = serde_json::from_str(builtin::find("cornell").unwrap().gltf).unwrap();
    let roots = v["scenes"][0]["nodes"].clone();
    let nodes = v["nodes"].as_array_mut().unwrap();
    nodes.push(json!({ "name": "far", "children": roots, "translation": [1e6, -1e6, 1e6] }));
    v["scenes"][0]["nodes"] = json!([nodes.len() - 1]);
    let far = load(&v).unwrap();
    assert!(
        far.warnings
            .iter()
            .any(|w| w.contains("moved to the origin")),
        "{:?}",
        far.warnings
    );
    let near = builtin::load("cornell").unwrap().unwrap();
    let (f, g) = (far.at(0.0), near.at(0.0));
    // Same triangles up to one translation (the far frame's first vertex onto the near one's),
    // within 1e-6 of a 2-unit box; the camera likewise.
    let d = g.tris[0][0] - f.tris[0][0];
    assert!(d.length() < 0.1, "moved to the origin: {d}");
    assert_eq!(f.tris.len(), g.tris.len());
    for (a, b) in f.tris.iter().zip(&g.tris) {
        for k in 0..3 {
            assert!(
                (a[k] + d - b[k]).length() < 1e-6,
                "{} vs {}",
                a[k] + d,
                b[k]
            );
        }
    }
    assert!((f.camera.position + d - g.camera.position).length() < 1e-6);
    assert_eq!(f.camera.forward, g.camera.forward);
}

#[test]
fn field_of_view_0_or_pi_is_refused() {
    for fov in [0.0, std::f32::consts::PI, -0.5] {
        let (g, mut doc) = lit();
        doc["cameras"][0]["perspective"]["yfov"] = json!(fov);
        let e = load(&g.finish(doc)).unwrap_err();
        assert!(
            e.contains("camera 0") && e.contains("field of view") || e.contains("invalid glTF"),
            "{fov}: {e}"
        );
    }
}

#[test]
fn camera_scaled_to_zero_is_refused() {
    let (g, mut doc) = lit();
    doc["nodes"][2]["scale"] = json!([0.0, 0.0, 0.0]);
    refused(&g.finish(doc), &["camera", "node 2", "scaled to zero"]);
    // Scaled to zero by an animation at t = 1 s only.
    let (mut g, mut doc) = lit();
    let t = g.floats(&[0.0, 1.0], "SCALAR", 1);
    let s = g.floats(&[1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "VEC3", 3);
    doc["animations"] = json!([{
        "samplers": [{ "input": t, "output": s }],
        "channels": [{ "sampler": 0, "target": { "node": 2, "path": "scale" } }],
    }]);
    refused(&g.finish(doc), &["t = 1 s", "scaled to zero"]);
}

/// The cornell box as a .glb.
fn cornell_glb() -> Vec<u8> {
    let mut v: Value = serde_json::from_str(builtin::find("cornell").unwrap().gltf).unwrap();
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    v["buffers"][0] = json!({ "byteLength": bin.len() });
    let mut js = v.to_string().into_bytes();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin.len();
    let mut glb = Vec::new();
    for w in [
        0x4654_6c67u32,
        2,
        total as u32,
        js.len() as u32,
        0x4e4f_534a,
    ] {
        glb.extend_from_slice(&w.to_le_bytes());
    }
    glb.extend_from_slice(&js);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    glb
}

#[test]
fn truncated_glb_says_truncated() {
    let glb = cornell_glb();
    assert!(load_bytes(glb.clone(), "cornell.glb").is_ok());
    for cut in [10, 16, glb.len() / 2, glb.len() - 1] {
        let e = load_bytes(glb[..cut].to_vec(), "cornell.glb").unwrap_err();
        assert!(
            e.starts_with("cornell.glb: not a glTF 2.0 file: the .glb is truncated"),
            "{cut}: {e}"
        );
    }
}

// ---- Issue 11 item 3: geometry as the spec says ----

#[test]
fn mirrored_emitter_still_faces_down() {
    // A mirroring node (negative determinant) flips the winding back (glTF 2.0 3.7.4).
    let (g, mut doc) = lit();
    doc["nodes"][1]["scale"] = json!([-1.0, 1.0, 1.0]);
    doc["nodes"][1]["translation"] = json!([1.0, 0.0, 0.0]);
    let s = load(&g.finish(doc)).unwrap();
    let f = s.at(0.0);
    assert_eq!(f.emitters.tris.len(), 2);
    for &t in &f.emitters.tris {
        assert_eq!(f.normals[t as usize], Vec3::NEG_Z);
    }
    // The mirrored light covers the same square.
    let (lo, hi) = f.bounds();
    assert_eq!((lo, hi), (Vec3::ZERO, Vec3::ONE));
}

/// A scene of one emitting primitive in `mode` over the vertices of `quad(0)` in `order`.
fn one_primitive(mode: u32, order: &[u32]) -> Scene {
    let mut g = Gltf::default();
    let p = g.positions(&quad(0.0));
    let i = g.indices(order);
    let doc = json!({
        "scenes": [{ "nodes": [0] }], "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": p }, "indices": i, "material": 1, "mode": mode }] }],
        "materials": materials(),
    });
    load(&g.finish(doc)).unwrap()
}

#[test]
fn strips_and_fans_are_triangles() {
    // The unit quad as a strip (0,1,3,2) and as a fan around 0 (0,1,2,3): two triangles of
    // area 1/2 facing +z each; a strip's odd triangles swap two vertices (glTF 2.0 3.7.2.1).
    for (mode, order) in [(5, [0, 1, 3, 2]), (6, [0, 1, 2, 3])] {
        let f = one_primitive(mode, &order).at(0.0);
        assert_eq!(f.tris.len(), 2, "mode {mode}");
        for t in 0..2 {
            assert_eq!(f.normals[t], Vec3::Z, "mode {mode}: {:?}", f.tris[t]);
            assert!((f.areas[t] - 0.5).abs() < 1e-7);
        }
    }
    // A strip of five vertices has three triangles.
    let mut g = Gltf::default();
    let p = g.positions(&[
        [0., 0., 0.],
        [1., 0., 0.],
        [0., 1., 0.],
        [1., 1., 0.],
        [0., 2., 0.],
    ]);
    let doc = json!({
        "scenes": [{ "nodes": [0] }], "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": p }, "material": 1, "mode": 5 }] }],
        "materials": materials(),
    });
    let f = load(&g.finish(doc)).unwrap().at(0.0);
    assert_eq!(f.tris.len(), 3);
    assert!(f.normals.iter().all(|&n| n == Vec3::Z), "{:?}", f.normals);
}

#[test]
fn sparse_accessors_are_read() {
    // The light's vertex 2 moved from (1,1,1) to (2,3,1) by a sparse substitution.
    let (mut g, mut doc) = lit();
    let at = g.indices(&[2]);
    let vals = g.floats(&[2.0, 3.0, 1.0], "VEC3", 3);
    let view = |g: &Gltf, acc: usize| g.accessors[acc]["bufferView"].clone();
    let (iv, vv) = (view(&g, at), view(&g, vals));
    g.accessors[1]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": iv, "componentType": 5125 },
        "values": { "bufferView": vv },
    });
    g.accessors[1]["max"] = json!([2.0, 3.0, 1.0]);
    let f = load(&g.finish(doc.clone())).unwrap().at(0.0);
    assert_eq!(
        f.tris[2],
        [Vec3::Z, Vec3::new(2.0, 3.0, 1.0), Vec3::X + Vec3::Z]
    );
    // Out-of-order sparse indices are refused, not silently dropped.
    let (mut g, _) = lit();
    let at = g.indices(&[2, 1]);
    let vals = g.floats(&[2.0, 3.0, 1.0, 0.0, 0.0, 1.0], "VEC3", 3);
    let (iv, vv) = (view(&g, at), view(&g, vals));
    g.accessors[1]["sparse"] = json!({
        "count": 2,
        "indices": { "bufferView": iv, "componentType": 5125 },
        "values": { "bufferView": vv },
    });
    doc["asset"] = json!({ "version": "2.0" });
    refused(&g.finish(doc), &["accessor 1", "sparse indices"]);
}

#[test]
fn percent_encoded_uris_are_decoded() {
    let dir = std::env::temp_dir().join(format!("irad-uri-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (g, doc) = lit();
    let mut doc = g.finish(doc);
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let bin = base64::engine::general_purpose::STANDARD
        .decode(uri.split_once(',').unwrap().1)
        .unwrap();
    std::fs::write(dir.join("my scene ü.bin"), &bin).unwrap();
    doc["buffers"][0]["uri"] = json!("my%20scene%20%C3%BC.bin");
    let path = dir.join("scene.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let s = irad::scene::load::load_path(&path);
    // Invalid UTF-8 after decoding is a message, not a panic inside the gltf crate.
    doc["buffers"][0]["uri"] = json!("bad%FF.bin");
    std::fs::write(&path, doc.to_string()).unwrap();
    let bad = irad::scene::load::load_path(&path).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(s.unwrap().at(0.0).tris.len(), 4);
    assert!(bad.contains("bad%FF.bin") && bad.contains("UTF-8"), "{bad}");
}

#[test]
fn quantized_positions_are_read() {
    // KHR_mesh_quantization: the floor as normalized i16, scaled by its node to 2 x 2.
    let (mut g, mut doc) = lit();
    let q: [i16; 12] = [0, 0, 0, 32767, 0, 0, 32767, 32767, 0, 0, 32767, 0];
    let p = g.accessor(bytemuck::cast_slice(&q), 4, "VEC3", 5122);
    g.accessors[p]["normalized"] = json!(true);
    g.accessors[p]["min"] = json!([0, 0, 0]);
    g.accessors[p]["max"] = json!([32767, 32767, 0]);
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(p);
    doc["nodes"][0]["scale"] = json!([2.0, 2.0, 1.0]);
    doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let s = load(&g.finish(doc)).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let f = s.at(0.0);
    assert_eq!(
        f.tris[0],
        [Vec3::ZERO, Vec3::X * 2.0, Vec3::new(2.0, 2.0, 0.0)]
    );
}

#[test]
fn double_sided_emitters_emit_from_both_sides() {
    let (g, mut doc) = lit();
    let single = load(&g.finish(doc.clone())).unwrap().at(0.0);
    let (g, _) = lit();
    doc["materials"][1]["doubleSided"] = json!(true);
    let f = load(&g.finish(doc)).unwrap().at(0.0);
    // Two more emitting triangles, facing up, 1e-4 of the scene's size above the light.
    assert_eq!(f.tris.len(), 6);
    assert_eq!(f.emitters.tris.len(), 4);
    assert_eq!(f.tris[..4], single.tris[..]);
    for t in 4..6 {
        assert_eq!(f.normals[t], Vec3::Z);
        assert!(f.tris[t].iter().all(|p| (p.z - 1.0001).abs() < 1e-6));
    }
    assert!((f.emitters.total_power - 2.0 * single.emitters.total_power).length() < 1e-5);
}

#[test]
fn ignored_vertex_data_warns_once_saying_what_it_changes() {
    let (mut g, mut doc) = lit();
    // COLOR_0 is used (tests/gpu/textures.rs); a second colour set is not.
    let c = g.floats(&[1.0; 16], "VEC4", 4);
    for m in [0, 1] {
        doc["meshes"][m]["primitives"][0]["attributes"]["COLOR_0"] = json!(c);
        doc["meshes"][m]["primitives"][0]["attributes"]["COLOR_1"] = json!(c);
    }
    let s = load(&g.finish(doc)).unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(
        s.warnings[0].contains("vertex colours beyond COLOR_0"),
        "{:?}",
        s.warnings
    );
}

// ---- Issue 11 item 4: a useful camera, and inspection ----

/// The fraction of a 32 x 32 grid of camera rays that hit the lit (front) face of the floor.
fn floor_seen(s: &Scene) -> f32 {
    let f = s.at(0.0);
    let c = f.camera;
    let tr = irad::trace::Tracer::new(&f);
    let mut hits = 0;
    for y in 0..32 {
        for x in 0..32 {
            let d = c.ray_dir(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5), 32, 32);
            if let Some(h) = tr.intersect(c.position, d, 1e3) {
                let t = h.tri as usize;
                hits += (t < 2 && f.normals[t].dot(d) < 0.0) as usize;
            }
        }
    }
    hits as f32 / 1024.0
}

#[test]
fn a_file_without_a_camera_looks_at_the_lit_floor() {
    // A 4 x 4 floor in the xz plane facing +y, lit by a quad 1 above it: the old default
    // (framing the bounds from +z) saw it edge-on.
    let mut g = Gltf::default();
    let floor = g.positions(&[[-2., 0., 2.], [2., 0., 2.], [2., 0., -2.], [-2., 0., -2.]]);
    let light = g.positions(&[
        [-0.5, 1., 0.5],
        [0.5, 1., 0.5],
        [0.5, 1., -0.5],
        [-0.5, 1., -0.5],
    ]);
    let up = g.indices(&[0, 1, 2, 0, 2, 3]);
    let down = g.indices(&[0, 2, 1, 0, 3, 2]);
    let doc = json!({
        "scenes": [{ "nodes": [0, 1] }],
        "nodes": [{ "mesh": 0 }, { "mesh": 1 }],
        "meshes": [
            { "primitives": [{ "attributes": { "POSITION": floor }, "indices": up, "material": 0 }] },
            { "primitives": [{ "attributes": { "POSITION": light }, "indices": down, "material": 1 }] },
        ],
        "materials": materials(),
    });
    let mut s = load(&g.finish(doc)).unwrap();
    let seen = floor_seen(&s);
    // The old camera (framing the bounds from +z), for comparison.
    let (lo, hi) = s.at(0.0).bounds();
    let old = irad::scene::Camera::framing(lo, hi);
    s.set_camera(old.position, old.position + old.forward, old.yfov)
        .unwrap();
    let before = floor_seen(&s);
    // Measured: 0.316 of the rays land on the floor's lit face with the new camera (0.207
    // before the views were weighted by the cosine they see the points at), 0.020 with the
    // old one.
    assert!(
        seen > 0.25 && seen > 5.0 * before,
        "new {seen}, old {before}"
    );
}

/// A flat board with no lamp (so a sky lights both of its sides), as the Khronos boards
/// (TextureSettingsTest) are: single-sided panels facing its front at z = 0, before a
/// background of two single-sided quads, one facing front at z = 0.1 and one facing back at
/// z = 0.15. Turned to face each of the six axis directions, the automatic camera looks at its
/// front, face-on. Before: it looked along the board's plane (TextureSettingsTest, seen
/// edge-on from (0, -19.3, 0)), where lit points of both faces faced the eye by a hair.
#[test]
fn a_board_without_lights_is_framed_from_its_front() {
    let rotations = [
        glam::Quat::IDENTITY,
        glam::Quat::from_rotation_y(std::f32::consts::PI),
        glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
        glam::Quat::from_rotation_y(-std::f32::consts::FRAC_PI_2),
        glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
    ];
    for q in rotations {
        let mut g = Gltf::default();
        let square = |h: f32, z: f32| [[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]];
        let front = g.indices(&[0, 2, 1, 0, 3, 2]);
        let back = g.indices(&[0, 1, 2, 0, 2, 3]);
        let prim = |p: usize, i: usize| json!({ "attributes": { "POSITION": p }, "indices": i, "material": 0 });
        let panels: Vec<Value> = [(-1.2, 0.6), (1.2, 0.6), (-1.2, -0.6), (1.2, -0.6)]
            .iter()
            .map(|&(x, y): &(f32, f32)| {
                let p = square(0.4, 0.0).map(|v| [v[0] + x, v[1] + y, v[2]]);
                prim(g.positions(&p), front)
            })
            .collect();
        let bg_front = prim(g.positions(&square(2.0, 0.1)), front);
        let bg_back = prim(g.positions(&square(2.0, 0.15)), back);
        let mut all = panels;
        all.extend([bg_front, bg_back]);
        let r = q.to_array();
        let doc = json!({
            "scenes": [{ "nodes": [0] }],
            "nodes": [{ "mesh": 0, "rotation": r }],
            "meshes": [{ "primitives": all }],
            "materials": materials(),
        });
        let s = load(&g.finish(doc)).unwrap();
        let f = s.at(0.0);
        let facing = q * glam::Vec3::NEG_Z;
        let cos = -f.camera.forward.dot(facing);
        println!(
            "board facing {facing}: camera at {}, cos {cos}",
            f.camera.position
        );
        // Measured: 1.0 for every side (the eye straight in front).
        assert!(
            cos > 0.95,
            "board facing {facing}: camera forward {}",
            f.camera.forward
        );
    }
}

#[test]
fn set_camera_validates_and_overrides() {
    let (g, doc) = lit();
    let mut s = load(&g.finish(doc)).unwrap();
    let bad = [
        (Vec3::NAN, Vec3::ZERO, 0.8, "eye"),
        (Vec3::ZERO, Vec3::splat(1e30), 0.8, "target"),
        (Vec3::ONE, Vec3::ONE, 0.8, "same point"),
        (Vec3::Z, Vec3::ZERO, 0.0, "field of view"),
        (Vec3::Z, Vec3::ZERO, std::f32::consts::PI, "field of view"),
    ];
    for (eye, target, fov, word) in bad {
        let e = s.set_camera(eye, target, fov).unwrap_err();
        assert!(e.contains(word), "{word}: {e}");
    }
    s.set_camera(Vec3::new(0.5, -3.0, 0.5), Vec3::new(0.5, 0.0, 0.5), 0.5)
        .unwrap();
    let c = s.at(0.0).camera;
    assert_eq!(c.position, Vec3::new(0.5, -3.0, 0.5));
    assert_eq!(c.forward, Vec3::Y);
    assert_eq!(c.up, Vec3::Z);
    assert_eq!(c.yfov, 0.5);
}

#[test]
fn inspection_reports_what_the_file_holds() {
    let (mut g, mut doc) = lit();
    let t = g.floats(&[0.0, 2.5], "SCALAR", 1);
    let v = g.floats(&[0.0, 0.0, 0.0, 0.0, 0.0, 1.0], "VEC3", 3);
    doc["animations"] = json!([{
        "samplers": [{ "input": t, "output": v }],
        "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }],
    }]);
    doc["materials"][1]["name"] = json!("lamp");
    doc["materials"][1]["emissiveFactor"] = json!([1.0, 0.5, 0.25]);
    let c = g.floats(&[1.0; 16], "VEC4", 4);
    doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_1"] = json!(c);
    let s = load(&g.finish(doc)).unwrap();
    let i = irad::scene::inspect::inspect(&s);
    assert_eq!(i.triangles, 4);
    assert_eq!(i.emitters.len(), 1);
    // Le * pi * area (1 m^2), by hand.
    let pi = std::f32::consts::PI;
    assert!((i.emitters[0].power - Vec3::new(pi, pi / 2.0, pi / 4.0)).length() < 1e-5);
    assert_eq!(
        (i.emitters[0].material.as_str(), i.emitters[0].triangles),
        ("lamp", 2)
    );
    assert_eq!(i.cameras.len(), 1);
    assert!(i.cameras[0].in_use && (i.cameras[0].yfov_deg - 45.8366).abs() < 1e-3);
    assert_eq!((i.channels, i.duration), (1, 2.5));
    assert_eq!(i.bounds, (Vec3::ZERO, Vec3::ONE));
    let text = i.to_string();
    for line in [
        "triangles   4",
        "bounds      (0.0000, 0.0000, 0.0000) to (1.0000, 1.0000, 1.0000)",
        "emitter     'lamp': 2 triangles, power (3.1416, 1.5708, 0.7854) W",
        "camera      node 2 'camera', yfov 45.84 deg (in use)",
        "animation   1 channels over 2.500 s",
        "warning     test.gltf: vertex colours",
    ] {
        assert!(text.contains(line), "'{line}' missing from:\n{text}");
    }
}

#[test]
fn punctual_lights_light_a_scene_without_emitters() {
    // Issue 11 item 1: KHR_lights_punctual lights are used (no warning) and light a file
    // that has no emissive material (tests/gpu/punctual.rs holds their light to analytic values).
    let lights = json!({ "lights": [
        { "type": "point", "intensity": 10.0 },
        { "type": "point", "intensity": 5.0 },
        { "type": "spot", "spot": {} },
    ] });
    let (g, mut doc) = lit();
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({ "KHR_lights_punctual": lights });
    doc["nodes"][0]["extensions"] = json!({ "KHR_lights_punctual": { "light": 2 } });
    doc["materials"][1]
        .as_object_mut()
        .unwrap()
        .remove("emissiveFactor");
    let s = load(&g.finish(doc)).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.lights.len(), 3);
    let f = s.at(0.0);
    assert!(f.emitters.tris.is_empty());
    // Only the spot is on a node.
    assert_eq!(f.emitters.lights.len(), 1);
}
