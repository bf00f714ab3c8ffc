//! Small glTF documents written by tests: quads, each with its own node, and materials.

use base64::Engine;
use irad::scene::{load::load_slice, Scene};
use serde_json::{json, Value};

/// One embedded buffer; every quad a mesh of its own under a node of its own.
#[derive(Default)]
pub struct Quads {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    materials: Vec<Value>,
}

impl Quads {
    fn accessor(&mut self, bytes: &[u8], count: usize, ty: &str, component: u32) -> usize {
        self.views
            .push(json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }));
        self.bin.extend_from_slice(bytes);
        self.accessors.push(json!({
            "bufferView": self.views.len() - 1, "count": count, "type": ty, "componentType": component,
        }));
        self.accessors.len() - 1
    }

    /// A grey (`albedo`) material emitting `emission` (white), single- or double-sided.
    pub fn material(&mut self, albedo: f32, emission: f32, double_sided: bool) -> usize {
        let mut m = json!({
            "pbrMetallicRoughness": { "baseColorFactor": [albedo, albedo, albedo, 1.0], "metallicFactor": 0.0 },
            "doubleSided": double_sided,
        });
        if emission > 0.0 {
            m["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
            m["extensions"] =
                json!({ "KHR_materials_emissive_strength": { "emissiveStrength": emission } });
        }
        self.materials.push(m);
        self.materials.len() - 1
    }

    /// The quad `c +- u +- v` (its front faces `u x v`) under a node with the properties
    /// `node` (a JSON object: "scale", "translation", ...); returns the node.
    pub fn quad(
        &mut self,
        c: [f32; 3],
        u: [f32; 3],
        v: [f32; 3],
        material: usize,
        node: Value,
    ) -> usize {
        let at = |a: f32, b: f32| [0, 1, 2].map(|i| c[i] + a * u[i] + b * v[i]);
        let p = [at(-1., -1.), at(1., -1.), at(1., 1.), at(-1., 1.)];
        let acc = self.accessor(bytemuck::cast_slice(p.as_flattened()), 4, "VEC3", 5126);
        let lo = p
            .iter()
            .fold([f32::MAX; 3], |a, v| [0, 1, 2].map(|i| a[i].min(v[i])));
        let hi = p
            .iter()
            .fold([f32::MIN; 3], |a, v| [0, 1, 2].map(|i| a[i].max(v[i])));
        self.accessors[acc]["min"] = json!(lo);
        self.accessors[acc]["max"] = json!(hi);
        let idx: [u32; 6] = [0, 1, 2, 0, 2, 3];
        let ind = self.accessor(bytemuck::cast_slice(&idx), 6, "SCALAR", 5125);
        self.meshes.push(json!({ "primitives": [
            { "attributes": { "POSITION": acc }, "indices": ind, "material": material }] }));
        let mut n = node;
        n["mesh"] = json!(self.meshes.len() - 1);
        self.nodes.push(n);
        self.nodes.len() - 1
    }

    /// The glTF document: every node a root.
    pub fn finish(self) -> Value {
        let roots: Vec<usize> = (0..self.nodes.len()).collect();
        json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": roots }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "extensionsUsed": ["KHR_materials_emissive_strength"],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{
                "byteLength": self.bin.len(),
                "uri": format!("data:application/octet-stream;base64,{}",
                    base64::engine::general_purpose::STANDARD.encode(&self.bin)),
            }],
        })
    }
}

/// Loads a document written here.
pub fn load(doc: &Value) -> Scene {
    let bytes = serde_json::to_vec(doc).unwrap();
    load_slice(&bytes, "test.gltf", "test", None).unwrap()
}

/// How the test quad of [`quad_under_light`] is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Panel {
    /// None at all.
    Absent,
    /// Facing up (toward the light), single- or double-sided.
    Up { double: bool },
    /// Facing down (toward the floor and the camera), single- or double-sided.
    Down { double: bool },
}

/// A grey floor (double-sided, albedo 0.5, 6 x 6 at y = 0), a 1 x 1 light facing down at
/// y = 3 (radiance 10, single-sided, black), and between them the 1.2 x 1.2 grey panel at
/// y = 1.5 as `panel` says; the camera sits below the panel's plane, looking at the floor
/// under it (so it sees the panel's underside).
pub fn quad_under_light(panel: Panel) -> Scene {
    let mut q = Quads::default();
    let floor = q.material(0.5, 0.0, true);
    let light = q.material(0.0, 10.0, false);
    q.quad(
        [0.; 3],
        [0., 0., 3.],
        [3., 0., 0.],
        floor,
        json!({ "name": "floor" }),
    );
    q.quad(
        [0., 3., 0.],
        [0.5, 0., 0.],
        [0., 0., 0.5],
        light,
        json!({ "name": "light" }),
    );
    let (x, z) = ([0.6, 0., 0.], [0., 0., 0.6]);
    let c = [0., 1.5, 0.];
    match panel {
        Panel::Absent => {}
        Panel::Up { double } => {
            let m = q.material(0.5, 0.0, double);
            q.quad(c, z, x, m, json!({ "name": "panel" }));
        }
        Panel::Down { double } => {
            let m = q.material(0.5, 0.0, double);
            q.quad(c, x, z, m, json!({ "name": "panel" }));
        }
    }
    let mut s = load(&q.finish());
    s.set_camera(
        glam::Vec3::new(0.0, 0.8, 4.5),
        glam::Vec3::new(0.0, 0.4, 0.0),
        0.9,
    )
    .unwrap();
    s
}
