//! The built-in scenes. Each is a glTF file in `scenes/`, embedded in the binary, and produced
//! by the generator in this file (`irad scenes --generate scenes/` writes them again; a test
//! checks that the committed files are exactly what the generator makes).

pub mod atrium;

use super::{load, Scene};
use base64::Engine;
use glam::{Quat, Vec3};
use serde_json::{json, Value};

/// A built-in scene: its name, what it stresses, and its glTF text.
pub struct Builtin {
    pub name: &'static str,
    pub stresses: &'static str,
    pub gltf: &'static str,
}

pub const BUILTINS: &[Builtin] = &[
    Builtin {
        name: "cornell",
        stresses: "the classic Cornell box (Mitsuba 3's), still: the baseline every metric is held to",
        gltf: include_str!("../../../scenes/cornell.gltf"),
    },
    Builtin {
        name: "cornell-orbit",
        stresses: "the camera swings 12 degrees either side of the box over 3 s: importance changes with the view, so CDF sampling re-maps its VPLs",
        gltf: include_str!("../../../scenes/cornell-orbit.gltf"),
    },
    Builtin {
        name: "cornell-light",
        stresses: "the light slides across the ceiling over 3 s (cubic spline): every light path moves, chains must follow",
        gltf: include_str!("../../../scenes/cornell-light.gltf"),
    },
    Builtin {
        name: "cornell-box",
        stresses: "the small box slides and turns across the floor over 3 s: moving occluder, BVH rebuilds and moving ISM points",
        gltf: include_str!("../../../scenes/cornell-box.gltf"),
    },
    Builtin {
        name: "two-rooms",
        stresses: "importance decides: the light is in one room, the camera walks through the door into the other over 3 s; most plain VPLs land where the camera cannot see",
        gltf: include_str!("../../../scenes/two-rooms.gltf"),
    },
    Builtin {
        name: "furnace",
        stresses: "white furnace: a closed box, albedo 0.5, every wall emits 1: radiance is exactly 2 everywhere",
        gltf: include_str!("../../../scenes/furnace.gltf"),
    },
    Builtin {
        name: "atrium",
        stresses: "Sponza-class: a 30 x 14 m court with two storeys of arcades (about 130k triangles), lit by a sun high above the open roof that slides across the sky over 4 s and a spot light on a column whose beam sweeps the floor: scale, deep occlusion, light mostly arriving by bounces",
        gltf: include_str!("../../../scenes/atrium.gltf"),
    },
];

/// Looks a built-in scene up by name.
pub fn find(name: &str) -> Option<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name)
}

/// Loads a built-in scene.
pub fn load(name: &str) -> Option<Result<Scene, load::LoadError>> {
    find(name).map(|b| load::load_slice(b.gltf.as_bytes(), &format!("builtin:{name}"), name, None))
}

/// Loads a scene given as a built-in name or a path, with the default options.
pub fn load_any(spec: &str) -> anyhow::Result<Scene> {
    load_any_with(spec, &load::LoadOptions::default())
}

/// Loads a scene given as a built-in name or a path.
pub fn load_any_with(spec: &str, options: &load::LoadOptions) -> anyhow::Result<Scene> {
    if let Some(s) = load(spec) {
        return Ok(s?);
    }
    let path = std::path::Path::new(spec);
    if !path.exists() {
        // A name a letter or two from a built-in's is most likely that one, misspelled.
        let near = BUILTINS
            .iter()
            .map(|b| (edit_distance(spec, b.name), b.name))
            .filter(|&(d, _)| d <= 2)
            .min();
        let hint = near.map_or(String::new(), |(_, n)| format!("did you mean '{n}'? "));
        anyhow::bail!(
            "{spec}: no such file, and not a built-in scene ({hint}built-ins: {})",
            BUILTINS
                .iter()
                .map(|b| b.name)
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(load::load_path_with(path, options)?)
}

/// Levenshtein distance between two names (characters inserted, deleted or replaced).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + (ca != cb) as usize).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// Generates the glTF text of a built-in scene.
pub fn generate(name: &str) -> Option<String> {
    let mut b = GltfBuilder::default();
    match name {
        "cornell" => {
            cornell(&mut b);
        }
        "cornell-orbit" => cornell_orbit(&mut b),
        "cornell-light" => cornell_light(&mut b),
        "cornell-box" => cornell_box(&mut b),
        "two-rooms" => two_rooms(&mut b),
        "atrium" => atrium::atrium(&mut b),
        "furnace" => furnace(&mut b),
        _ => return None,
    }
    Some(b.finish(name))
}

/// The Cornell box with the camera swinging 12 degrees either side over 3 s.
fn cornell_orbit(b: &mut GltfBuilder) {
    let n = cornell(b);
    let times: Vec<f32> = (0..=12).map(|i| i as f32 * 0.25).collect();
    let angle = |t: f32| 12f32.to_radians() * (std::f32::consts::TAU * t / 3.0).sin();
    let pos: Vec<f32> = times
        .iter()
        .flat_map(|&t| [3.9 * angle(t).sin(), 0.0, 3.9 * angle(t).cos()])
        .collect();
    let rot: Vec<f32> = times
        .iter()
        .flat_map(|&t| Quat::from_rotation_y(angle(t)).to_array())
        .collect();
    b.animate("orbit", n.camera, "translation", "LINEAR", &times, &pos);
    b.animate("orbit", n.camera, "rotation", "LINEAR", &times, &rot);
}

/// The Cornell box with the light sliding across the ceiling (cubic spline).
fn cornell_light(b: &mut GltfBuilder) {
    let n = cornell(b);
    // CUBICSPLINE keys (in-tangent, value, out-tangent): ease from x=-0.5 to 0.5 and back.
    let times = [0.0, 1.5, 3.0];
    let key = |x: f32| [0.0, 0.0, 0.0, x, 0.99, 0.01, 0.0, 0.0, 0.0];
    let values: Vec<f32> = [-0.5, 0.5, -0.5].iter().flat_map(|&x| key(x)).collect();
    b.animate(
        "slide",
        n.light,
        "translation",
        "CUBICSPLINE",
        &times,
        &values,
    );
}

/// The Cornell box with the small box sliding and turning across the floor.
fn cornell_box(b: &mut GltfBuilder) {
    let n = cornell(b);
    let times = [0.0, 1.5, 3.0];
    let pos = [0.335, -0.7, 0.38, -0.25, -0.7, 0.6, 0.335, -0.7, 0.38];
    let rot: Vec<f32> = [-17.0f32, 30.0, -17.0]
        .iter()
        .flat_map(|a| Quat::from_rotation_y(a.to_radians()).to_array())
        .collect();
    b.animate("slide", n.small_box, "translation", "LINEAR", &times, &pos);
    b.animate("slide", n.small_box, "rotation", "LINEAR", &times, &rot);
}

/// White furnace: a closed box of albedo 0.5 whose walls all emit 1.
fn furnace(b: &mut GltfBuilder) {
    let m = b.material("furnace", [0.5; 3], [1.0; 3]);
    let mut nodes = Vec::new();
    for (c, u, v) in cube_faces() {
        // Inward-facing walls: swap u and v to flip the winding.
        let mesh = b.quad_mesh("wall", c, v, u, m);
        nodes.push(b.node(json!({ "name": "wall", "mesh": mesh })));
    }
    let cam = b.camera_node([0.0, 0.0, 0.5], Quat::IDENTITY, 60.0);
    nodes.push(cam);
    b.roots = nodes;
}

/// The six faces of the cube [-1,1]^3 as (center, u, v) with outward normal u x v.
fn cube_faces() -> [(Vec3, Vec3, Vec3); 6] {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    [
        (x, y, z),
        (-x, z, y),
        (y, z, x),
        (-y, x, z),
        (z, x, y),
        (-z, y, x),
    ]
}

/// Two rooms, x in [-4,0] (lit) and [0,4], joined by a door in the wall at x = 0.
fn two_rooms(b: &mut GltfBuilder) {
    let white = b.material("white", [0.8, 0.8, 0.8], [0.0; 3]);
    let grey = b.material("floor", [0.55, 0.55, 0.5], [0.0; 3]);
    let blue = b.material("blue", [0.2, 0.3, 0.75], [0.0; 3]);
    let orange = b.material("orange", [0.8, 0.5, 0.2], [0.0; 3]);
    let light = b.material("light", [0.8, 0.8, 0.8], [40.0, 38.0, 34.0]);
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let h = 1.25;
    let quads = [
        ("floor", Vec3::new(0.0, 0.0, 0.0), z * 2.0, x * 4.0, grey),
        ("ceiling", Vec3::new(0.0, 2.5, 0.0), x * 4.0, z * 2.0, white),
        ("back", Vec3::new(0.0, h, -2.0), x * 4.0, y * h, white),
        ("front", Vec3::new(0.0, h, 2.0), y * h, x * 4.0, white),
        ("end_a", Vec3::new(-4.0, h, 0.0), y * h, z * 2.0, orange),
        ("end_b", Vec3::new(4.0, h, 0.0), z * 2.0, y * h, blue),
        // The dividing wall at x = 0 with a door z in [-0.5, 0.5], y in [0, 2].
        (
            "wall_left",
            Vec3::new(0.0, h, -1.25),
            z * 0.75,
            y * h,
            white,
        ),
        (
            "wall_right",
            Vec3::new(0.0, h, 1.25),
            z * 0.75,
            y * h,
            white,
        ),
        (
            "lintel",
            Vec3::new(0.0, 2.25, 0.0),
            z * 0.5,
            y * 0.25,
            white,
        ),
        ("light", Vec3::new(-2.5, 2.49, 0.0), x * 0.5, z * 0.5, light),
    ];
    let mut roots = Vec::new();
    for (name, c, u, v, m) in quads {
        let mesh = b.quad_mesh(name, c, u, v, m);
        roots.push(b.node(json!({ "name": name, "mesh": mesh })));
    }
    let cube = b.cube_mesh("box", white);
    roots.push(b.node(json!({
        "name": "box", "mesh": cube,
        "translation": [2.2, 0.5, -0.8],
        "rotation": Quat::from_rotation_y(20f32.to_radians()).to_array(),
        "scale": [0.5, 0.5, 0.5],
    })));
    let look_x = Quat::from_rotation_y(-90f32.to_radians());
    let cam = b.camera_node([-1.5, 1.3, 0.2], look_x, 60.0);
    roots.push(cam);
    b.roots = roots;
    walk(b, cam);
}

/// The two-rooms camera walks through the door over 3 s, turning toward the box.
fn walk(b: &mut GltfBuilder, cam: usize) {
    let times = [0.0, 3.0];
    b.animate(
        "walk",
        cam,
        "translation",
        "LINEAR",
        &times,
        &[-1.5, 1.3, 0.2, 0.9, 1.3, 0.8],
    );
    let turn: Vec<f32> = [-90.0f32, -45.0]
        .iter()
        .flat_map(|a| Quat::from_rotation_y(a.to_radians()).to_array())
        .collect();
    b.animate("walk", cam, "rotation", "LINEAR", &times, &turn);
}

struct CornellNodes {
    light: usize,
    small_box: usize,
    camera: usize,
}

/// The Cornell box exactly as Mitsuba 3 defines it (DESIGN.md).
fn cornell(b: &mut GltfBuilder) -> CornellNodes {
    let white = b.material("white", [0.885809, 0.698859, 0.666422], [0.0; 3]);
    let red = b.material("red", [0.570068, 0.0430135, 0.0443706], [0.0; 3]);
    let green = b.material("green", [0.105421, 0.37798, 0.076425], [0.0; 3]);
    let light = b.material(
        "light",
        [0.885809, 0.698859, 0.666422],
        [18.387, 13.9873, 6.75357],
    );
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let walls = [
        ("floor", -y, z, x, white),
        ("ceiling", y, x, z, white),
        ("back", -z, x, y, white),
        ("left", -x, y, z, red),
        ("right", x, z, y, green),
    ];
    let mut roots = Vec::new();
    for (name, c, u, v, m) in walls {
        let mesh = b.quad_mesh(name, c, u, v, m);
        roots.push(b.node(json!({ "name": name, "mesh": mesh })));
    }
    // Light: 0.46 x 0.38 centred at (0, 0.99, 0.01), facing down.
    let lmesh = b.quad_mesh("light", Vec3::ZERO, x * 0.23, z * 0.19, light);
    let light_node =
        b.node(json!({ "name": "light", "mesh": lmesh, "translation": [0.0, 0.99, 0.01] }));
    roots.push(light_node);
    let cube = b.cube_mesh("box", white);
    let large = b.node(json!({
        "name": "large_box", "mesh": cube,
        "translation": [-0.33, -0.4, -0.28],
        "rotation": Quat::from_rotation_y(18.25f32.to_radians()).to_array(),
        "scale": [0.3, 0.61, 0.3],
    }));
    let small = b.node(json!({
        "name": "small_box", "mesh": cube,
        "translation": [0.335, -0.7, 0.38],
        "rotation": Quat::from_rotation_y(-17f32.to_radians()).to_array(),
        "scale": [0.3, 0.3, 0.3],
    }));
    let camera = b.camera_node([0.0, 0.0, 3.9], Quat::IDENTITY, 39.3077);
    roots.extend([large, small, camera]);
    b.roots = roots;
    CornellNodes {
        light: light_node,
        small_box: small,
        camera,
    }
}

/// A minimal glTF 2.0 writer: one embedded buffer, meshes, materials, nodes, animations.
#[derive(Default)]
struct GltfBuilder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    nodes: Vec<Value>,
    cameras: Vec<Value>,
    channels: Vec<(String, Value, Value)>,
    roots: Vec<usize>,
    /// KHR_lights_punctual lights.
    lights: Vec<Value>,
}

impl GltfBuilder {
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        ty: &str,
        component: u32,
        extra: Value,
    ) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views
            .push(json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }));
        self.bin.extend_from_slice(bytes);
        let mut a = json!({ "bufferView": self.views.len() - 1, "count": count, "type": ty, "componentType": component });
        if let (Value::Object(a), Value::Object(e)) = (&mut a, extra) {
            a.extend(e);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(&mut self, data: &[f32], ty: &str, per: usize, extra: Value) -> usize {
        self.accessor(
            bytemuck::cast_slice(data),
            data.len() / per,
            ty,
            5126,
            extra,
        )
    }

    fn material(&mut self, name: &str, albedo: [f32; 3], emission: [f32; 3]) -> usize {
        let strength = emission.iter().copied().fold(0.0, f32::max);
        let mut m = json!({
            "name": name,
            "pbrMetallicRoughness": { "baseColorFactor": [albedo[0], albedo[1], albedo[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0 },
        });
        if strength == 0.0 {
            // Walls are seen, lit and cast shadows from both sides (the scenes' cameras and
            // lights may be on either); emitters emit from their fronts only.
            m["doubleSided"] = json!(true);
        } else {
            m["emissiveFactor"] = json!(emission.map(|e| e / strength));
            if strength != 1.0 {
                m["extensions"] =
                    json!({ "KHR_materials_emissive_strength": { "emissiveStrength": strength } });
            }
        }
        self.materials.push(m);
        self.materials.len() - 1
    }

    fn mesh(&mut self, name: &str, positions: &[Vec3], indices: &[u32], material: usize) -> usize {
        let flat: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
        let (lo, hi) = super::bounds(positions.iter().copied());
        let pos = self.floats(
            &flat,
            "VEC3",
            3,
            json!({ "min": lo.to_array(), "max": hi.to_array() }),
        );
        let idx = self.accessor(
            bytemuck::cast_slice(indices),
            indices.len(),
            "SCALAR",
            5125,
            json!({}),
        );
        self.meshes.push(json!({
            "name": name,
            "primitives": [{ "attributes": { "POSITION": pos }, "indices": idx, "material": material, "mode": 4 }],
        }));
        self.meshes.len() - 1
    }

    /// A quad centred at `c` with half-edges `u` and `v`; its front face points along u x v.
    fn quad_mesh(&mut self, name: &str, c: Vec3, u: Vec3, v: Vec3, material: usize) -> usize {
        let p = [c - u - v, c + u - v, c + u + v, c - u + v];
        self.mesh(name, &p, &[0, 1, 2, 0, 2, 3], material)
    }

    /// The cube [-1,1]^3 with outward faces.
    fn cube_mesh(&mut self, name: &str, material: usize) -> usize {
        let mut p = Vec::new();
        let mut idx = Vec::new();
        for (c, u, v) in cube_faces() {
            let base = p.len() as u32;
            p.extend([c - u - v, c + u - v, c + u + v, c - u + v]);
            idx.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
        }
        self.mesh(name, &p, &idx, material)
    }

    fn node(&mut self, n: Value) -> usize {
        self.nodes.push(n);
        self.nodes.len() - 1
    }

    fn camera_node(&mut self, at: [f32; 3], rotation: Quat, yfov_deg: f32) -> usize {
        self.cameras.push(json!({
            "type": "perspective",
            "perspective": { "yfov": yfov_deg.to_radians(), "aspectRatio": 1.0, "znear": 0.01 },
        }));
        self.node(json!({ "name": "camera", "camera": self.cameras.len() - 1, "translation": at, "rotation": rotation.to_array() }))
    }

    /// A node carrying a KHR_lights_punctual spot light of `candela` (white) with cone half
    /// angles `inner` and `outer` (degrees), at `at`, shining along its rotated -Z.
    fn spot_node(
        &mut self,
        name: &str,
        at: Vec3,
        rotation: Quat,
        candela: f32,
        cone_deg: [f32; 2],
    ) -> usize {
        self.lights.push(json!({
            "name": name, "type": "spot", "color": [1.0, 1.0, 1.0], "intensity": candela,
            "spot": { "innerConeAngle": cone_deg[0].to_radians(), "outerConeAngle": cone_deg[1].to_radians() },
        }));
        self.node(json!({
            "name": name, "translation": at.to_array(), "rotation": rotation.to_array(),
            "extensions": { "KHR_lights_punctual": { "light": self.lights.len() - 1 } },
        }))
    }

    fn animate(
        &mut self,
        anim: &str,
        node: usize,
        path: &str,
        interpolation: &str,
        times: &[f32],
        values: &[f32],
    ) {
        let (lo, hi) = (times[0], times[times.len() - 1]);
        let input = self.floats(times, "SCALAR", 1, json!({ "min": [lo], "max": [hi] }));
        let (ty, per) = if path == "rotation" {
            ("VEC4", 4)
        } else {
            ("VEC3", 3)
        };
        let output = self.floats(values, ty, per, json!({}));
        self.channels.push((
            anim.to_string(),
            json!({ "input": input, "output": output, "interpolation": interpolation }),
            json!({ "node": node, "path": path }),
        ));
    }

    fn finish(self, name: &str) -> String {
        let mut animations: Vec<(String, Vec<Value>, Vec<Value>)> = Vec::new();
        for (anim, sampler, target) in self.channels {
            if animations.last().map(|a| &a.0) != Some(&anim) {
                animations.push((anim.clone(), Vec::new(), Vec::new()));
            }
            let a = animations.last_mut().unwrap();
            a.2.push(json!({ "sampler": a.1.len(), "target": target }));
            a.1.push(sampler);
        }
        let uses_strength = self.materials.iter().any(|m| m.get("extensions").is_some());
        let mut root = json!({
            "asset": { "version": "2.0", "generator": "irad scene generator" },
            "scene": 0,
            "scenes": [{ "name": name, "nodes": self.roots }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "cameras": self.cameras,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{
                "byteLength": self.bin.len(),
                "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&self.bin)),
            }],
        });
        let mut used = Vec::new();
        if uses_strength {
            used.push("KHR_materials_emissive_strength");
        }
        if !self.lights.is_empty() {
            used.push("KHR_lights_punctual");
            root["extensions"] = json!({ "KHR_lights_punctual": { "lights": self.lights } });
        }
        if !used.is_empty() {
            root["extensionsUsed"] = json!(used);
        }
        if !animations.is_empty() {
            root["animations"] = Value::Array(
                animations
                    .into_iter()
                    .map(|(n, s, c)| json!({ "name": n, "samplers": s, "channels": c }))
                    .collect(),
            );
        }
        let mut s = serde_json::to_string_pretty(&root).expect("JSON of plain values");
        s.push('\n');
        s
    }
}
