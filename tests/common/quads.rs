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
    cameras: Vec<Value>,
}

impl Quads {
    fn accessor(&mut self, bytes: &[u8], count: usize, ty: &str, component: u32) -> usize {
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        crate::common::gltf::accessor(b, v, a, (bytes, count, ty, component))
    }

    /// An accessor of floats (`ty`: "VEC3", "VEC4", ...).
    pub fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let per = match ty {
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 1,
        };
        self.accessor(bytemuck::cast_slice(data), data.len() / per, ty, 5126)
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
        let (b, v, a) = (&mut self.bin, &mut self.views, &mut self.accessors);
        let acc = crate::common::gltf::positions(b, v, a, &p);
        let idx: [u32; 6] = [0, 1, 2, 0, 2, 3];
        let ind = self.accessor(bytemuck::cast_slice(&idx), 6, "SCALAR", 5125);
        self.meshes.push(json!({ "primitives": [
            { "attributes": { "POSITION": acc }, "indices": ind, "material": material }] }));
        let mut n = node;
        n["mesh"] = json!(self.meshes.len() - 1);
        self.nodes.push(n);
        self.nodes.len() - 1
    }

    /// A perspective camera (vertical field of view `yfov` radians) at `at` looking down -z.
    pub fn camera(&mut self, at: [f32; 3], yfov: f32) -> usize {
        self.cameras.push(
            json!({ "type": "perspective", "perspective": { "yfov": yfov, "znear": 0.001 } }),
        );
        self.nodes
            .push(json!({ "camera": self.cameras.len() - 1, "translation": at }));
        self.nodes.len() - 1
    }

    /// A closed box from `lo` to `hi` (one mesh, 8 shared corners), faces out; returns its
    /// node.
    pub fn cube(&mut self, lo: [f32; 3], hi: [f32; 3], material: usize) -> usize {
        let p: Vec<[f32; 3]> = (0..8)
            .map(|k| [0, 1, 2].map(|a| if k >> a & 1 == 1 { hi[a] } else { lo[a] }))
            .collect();
        let acc = self.accessor(bytemuck::cast_slice(p.as_flattened()), 8, "VEC3", 5126);
        self.accessors[acc]["min"] = json!(lo);
        self.accessors[acc]["max"] = json!(hi);
        let mut idx: Vec<u32> = Vec::new();
        // Each face by its corners, counter-clockwise seen from outside.
        for f in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            idx.extend([f[0], f[1], f[2], f[0], f[2], f[3]]);
        }
        let ind = self.accessor(bytemuck::cast_slice(&idx), 36, "SCALAR", 5125);
        self.meshes.push(json!({ "primitives": [
            { "attributes": { "POSITION": acc }, "indices": ind, "material": material }] }));
        self.nodes.push(json!({ "mesh": self.meshes.len() - 1 }));
        self.nodes.len() - 1
    }

    /// The glTF document: every node a root.
    pub fn finish(self) -> Value {
        let roots: Vec<usize> = (0..self.nodes.len()).collect();
        self.document(roots)
    }

    /// The glTF document with every node a child of one root node with the properties
    /// `parent` (a JSON object: "scale", "translation", ...).
    pub fn finish_under(mut self, parent: Value) -> Value {
        let children: Vec<usize> = (0..self.nodes.len()).collect();
        let mut p = parent;
        p["children"] = json!(children);
        self.nodes.push(p);
        let root = self.nodes.len() - 1;
        self.document(vec![root])
    }

    fn document(self, roots: Vec<usize>) -> Value {
        let mut d = json!({
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
        });
        if !self.cameras.is_empty() {
            d["cameras"] = json!(self.cameras);
        }
        d
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

/// A small Cornell-like box ([-1,1]^3 open at +z; white, red and green double-sided walls, a
/// 0.6 x 0.6 light facing down 0.02 under the ceiling, a 0.6 cube on the floor) scaled by
/// `scale` and moved by `offset` (one root node), seen from (0, 0, 3.5) scaled and moved
/// alike (a camera node under the root), 0.75 rad. Returns the document.
pub fn cornell_like(scale: f32, offset: [f32; 3]) -> Value {
    let scale = [scale; 3];
    cornell_like_quads()
        .0
        .finish_under(json!({ "scale": scale, "translation": offset }))
}

/// [`cornell_like`]'s box (scale 1, in the origin) and, far from it, a white cube of side 0.2
/// centred at `at`, which makes the scene's bounding box that much larger. Returns the
/// document.
pub fn cornell_like_and_far_cube(at: [f32; 3]) -> Value {
    let (mut q, white) = cornell_like_quads();
    q.cube(at.map(|a| a - 0.1), at.map(|a| a + 0.1), white);
    q.finish()
}

/// [`cornell_like`]'s box at scale 1 in the origin, not yet finished (to add more to it), and
/// its white material.
pub fn cornell_like_quads() -> (Quads, usize) {
    let mut q = Quads::default();
    let white = q.material(0.7, 0.0, true);
    let red = q.material(0.6, 0.0, true);
    let green = q.material(0.3, 0.0, true);
    let light = q.material(0.0, 12.0, false);
    let (x, y, z) = ([1., 0., 0.], [0., 1., 0.], [0., 0., 1.]);
    let n = |v: [f32; 3]| v.map(|a| -a);
    let walls = [
        ([0., -1., 0.], z, x, white),
        ([0., 1., 0.], x, z, white),
        ([0., 0., -1.], x, y, white),
        ([-1., 0., 0.], y, z, red),
        ([1., 0., 0.], z, y, green),
    ];
    for (c, u, v, m) in walls {
        q.quad(c, u, v, m, json!({}));
    }
    q.quad(
        [0., 0.98, 0.],
        [0.3, 0., 0.],
        [0., 0., 0.3],
        light,
        json!({}),
    );
    // The cube: centre (0.3, -0.7, 0.2), half-size 0.3, faces out.
    let h = 0.3;
    let c = [0.3, -0.7, 0.2];
    let at = |d: [f32; 3]| [0, 1, 2].map(|i| c[i] + h * d[i]);
    let s = |v: [f32; 3]| v.map(|a| a * h);
    for (d, u, v) in [
        (y, z, x),
        (n(y), x, z),
        (x, y, z),
        (n(x), z, y),
        (z, x, y),
        (n(z), y, x),
    ] {
        q.quad(at(d), s(u), s(v), white, json!({}));
    }
    q.camera([0., 0., 3.5], 0.75);
    (q, white)
}

/// A model without any light, as most downloaded models: a grey floor (4 x 4 at y = 0,
/// double-sided, albedo 0.6), a white cube (0.8) and a taller dark box (0.4) on it, and a
/// panel (0.7) leaning over them; the camera at (0, 1, 4) looking down -z, so that the top
/// of the frame sees the sky. Returns the document.
pub fn lightless_model() -> Value {
    let mut q = Quads::default();
    let floor = q.material(0.6, 0.0, true);
    let white = q.material(0.8, 0.0, false);
    let dark = q.material(0.4, 0.0, false);
    let panel = q.material(0.7, 0.0, true);
    q.quad(
        [0.; 3],
        [0., 0., 2.],
        [2., 0., 0.],
        floor,
        json!({ "name": "floor" }),
    );
    q.cube([-1.0, 0.0, -0.6], [-0.2, 0.8, 0.2], white);
    q.cube([0.3, 0.0, -1.2], [0.9, 1.6, -0.6], dark);
    q.quad(
        [0.2, 1.2, -0.2],
        [0.6, 0.0, 0.0],
        [0.0, 0.3, -0.4],
        panel,
        json!({ "name": "panel" }),
    );
    q.camera([0.0, 1.0, 4.0], 0.8);
    q.finish()
}
