//! What a scene holds, for `irad scenes FILE`: triangles, emitters and punctual lights and
//! their power, cameras, animations, bounds and the loader's warnings.

use super::{Camera, LightKind, Scene};
use glam::Vec3;
use std::fmt;

/// One emitting material: its triangles and their power at t = 0.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterInfo {
    pub material: String,
    pub triangles: usize,
    /// RGB power in watts (`Le * pi * area`, summed).
    pub power: Vec3,
}

/// One punctual light placed at t = 0.
#[derive(Clone, Debug, PartialEq)]
pub struct LightInfo {
    pub name: String,
    pub kind: LightKind,
    pub position: Vec3,
    pub direction: Vec3,
    /// W/sr (point, spot) or W/m^2 (directional), RGB.
    pub intensity: Vec3,
    /// RGB watts (a directional light's through the sphere around the geometry).
    pub power: Vec3,
}

/// One perspective camera node.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfo {
    pub node: usize,
    pub name: String,
    /// Vertical field of view in degrees.
    pub yfov_deg: f32,
    /// Whether it is the camera irad renders from.
    pub in_use: bool,
}

/// One animated node: what its channels key, and what it moves (itself and its subtree).
#[derive(Clone, Debug, PartialEq)]
pub struct AnimatedNode {
    pub node: usize,
    /// The node's name, or "node N" when it has none.
    pub name: String,
    /// The keyed properties, in the order translation, rotation, scale (morph-target weights
    /// are not loaded: the loader warns about them).
    pub properties: Vec<&'static str>,
    /// Whether the node or one of its descendants carries the camera in use, a punctual
    /// light, an emitting mesh.
    pub moves_camera: bool,
    pub moves_light: bool,
    pub moves_emitter: bool,
}

/// A summary of a loaded scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspection {
    pub name: String,
    /// Triangles at t = 0.
    pub triangles: usize,
    /// Mesh instances at t = 0, and those of closed meshes with their triangles (see
    /// [`super::culling`]).
    pub instances: (usize, usize, usize),
    pub emitters: Vec<EmitterInfo>,
    pub lights: Vec<LightInfo>,
    /// The environment (its name, `sky` or a map's path, and its RGB power through the
    /// sphere around the geometry, W), and whether the loader gave it because nothing in
    /// the file lights the scene.
    pub environment: Option<(String, Vec3, bool)>,
    pub cameras: Vec<CameraInfo>,
    /// The camera irad renders from at t = 0.
    pub camera: Camera,
    /// Animation channels and the length of the animation (seconds).
    pub channels: usize,
    pub duration: f32,
    /// The animated nodes, in node order.
    pub animated: Vec<AnimatedNode>,
    /// Axis-aligned bounds at t = 0.
    pub bounds: (Vec3, Vec3),
    pub warnings: Vec<String>,
}

/// Inspects a scene at t = 0 (emitters, triangles, bounds) and as a whole (cameras, animation).
pub fn inspect(scene: &Scene) -> Inspection {
    let f = scene.at(0.0);
    let mut emitters: Vec<EmitterInfo> = Vec::new();
    for (k, &t) in f.emitters.tris.iter().enumerate() {
        let m = &f.materials[f.tri_material[t as usize] as usize];
        match emitters.iter_mut().find(|e| e.material == m.name) {
            Some(e) => {
                e.triangles += 1;
                e.power += f.emitters.power[k];
            }
            None => emitters.push(EmitterInfo {
                material: m.name.clone(),
                triangles: 1,
                power: f.emitters.power[k],
            }),
        }
    }
    let lights = f
        .emitters
        .lights
        .iter()
        .map(|l| LightInfo {
            name: scene.lights[l.light].name.clone(),
            kind: l.kind,
            position: l.position,
            direction: l.direction,
            intensity: l.intensity,
            power: l.power,
        })
        .collect();
    let cameras = (0..scene.nodes.len())
        .filter_map(|i| {
            let c = scene.nodes[i].camera?;
            Some(CameraInfo {
                node: i,
                name: scene.nodes[i].name.clone(),
                yfov_deg: c.yfov.to_degrees(),
                in_use: scene.camera_node == Some(i),
            })
        })
        .collect();
    let animated = animated_nodes(scene);
    Inspection {
        name: scene.name.clone(),
        triangles: f.tris.len(),
        instances: (
            f.instances.len(),
            f.instances.iter().filter(|i| i.closed).count(),
            f.instances
                .iter()
                .filter(|i| i.closed)
                .map(|i| i.tris.len())
                .sum(),
        ),
        emitters,
        lights,
        environment: f
            .emitters
            .environment
            .as_ref()
            .map(|e| (e.name.clone(), f.emitters.env_power, scene.unlit.is_some())),
        cameras,
        camera: f.camera,
        channels: scene.channels.len(),
        duration: scene.duration(),
        animated,
        bounds: f.bounds(),
        warnings: scene.warnings.clone(),
    }
}

/// Every node that a channel keys, with what it moves.
fn animated_nodes(scene: &Scene) -> Vec<AnimatedNode> {
    use super::anim::Property;
    let mut nodes: Vec<usize> = scene.channels.iter().map(|c| c.node).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let emits = |mesh: usize| {
        scene.meshes[mesh]
            .iter()
            .any(|p| scene.materials[p.material].emission.max_element() > 0.0)
    };
    nodes
        .into_iter()
        .filter(|&n| n < scene.nodes.len())
        .map(|n| {
            let properties = [
                (Property::Translation, "translation"),
                (Property::Rotation, "rotation"),
                (Property::Scale, "scale"),
            ]
            .into_iter()
            .filter(|(p, _)| {
                scene
                    .channels
                    .iter()
                    .any(|c| c.node == n && c.property == *p)
            })
            .map(|(_, name)| name)
            .collect();
            // The subtree (the loader refuses cycles; `seen` keeps a shared child once).
            let (mut stack, mut seen) = (vec![n], vec![false; scene.nodes.len()]);
            let (mut camera, mut light, mut emitter) = (false, false, false);
            while let Some(i) = stack.pop() {
                if std::mem::replace(&mut seen[i], true) {
                    continue;
                }
                let node = &scene.nodes[i];
                camera |= scene.camera_node == Some(i);
                light |= node.light.is_some();
                emitter |= node.mesh.is_some_and(emits);
                stack.extend(node.children.iter().copied().filter(|&c| c < seen.len()));
            }
            let name = &scene.nodes[n].name;
            AnimatedNode {
                node: n,
                name: if name.is_empty() {
                    format!("node {n}")
                } else {
                    name.clone()
                },
                properties,
                moves_camera: camera,
                moves_light: light,
                moves_emitter: emitter,
            }
        })
        .collect()
}

impl fmt::Display for Inspection {
    fn fmt(&self, w: &mut fmt::Formatter) -> fmt::Result {
        let v = |v: Vec3| format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z);
        writeln!(w, "scene {}", self.name)?;
        writeln!(w, "  triangles   {}", self.triangles)?;
        writeln!(
            w,
            "  instances   {} meshes placed, {} closed ({} triangles: back faces skipped from outside)",
            self.instances.0, self.instances.1, self.instances.2
        )?;
        let (lo, hi) = self.bounds;
        writeln!(w, "  bounds      {} to {}", v(lo), v(hi))?;
        for e in &self.emitters {
            writeln!(
                w,
                "  emitter     '{}': {} triangles, power {} W",
                e.material,
                e.triangles,
                v(e.power)
            )?;
        }
        for l in &self.lights {
            let (what, unit) = match l.kind {
                LightKind::Point => ("point".to_string(), "W/sr"),
                LightKind::Spot {
                    cos_inner,
                    cos_outer,
                } => (
                    format!(
                        "spot (cone {:.1} to {:.1} deg)",
                        cos_inner.acos().to_degrees(),
                        cos_outer.acos().to_degrees()
                    ),
                    "W/sr",
                ),
                LightKind::Directional => ("directional".to_string(), "W/m^2"),
            };
            let place = match l.kind {
                LightKind::Point => format!("at {}", v(l.position)),
                LightKind::Spot { .. } => format!("at {} toward {}", v(l.position), v(l.direction)),
                LightKind::Directional => format!("toward {}", v(l.direction)),
            };
            writeln!(
                w,
                "  light       '{}': {what} {place}, intensity {} {unit}, power {} W",
                l.name,
                v(l.intensity),
                v(l.power)
            )?;
        }
        if let Some((name, power, default)) = &self.environment {
            let why = if *default {
                " (the default: nothing in the file lights the scene)"
            } else {
                ""
            };
            writeln!(w, "  environment {name}{why}, power {} W", v(*power))?;
        }
        for c in &self.cameras {
            let used = if c.in_use { " (in use)" } else { "" };
            writeln!(
                w,
                "  camera      node {} '{}', yfov {:.2} deg{used}",
                c.node, c.name, c.yfov_deg
            )?;
        }
        let c = &self.camera;
        writeln!(
            w,
            "  view        from {} toward {}, yfov {:.2} deg",
            v(c.position),
            v(c.forward),
            c.yfov.to_degrees()
        )?;
        if self.channels > 0 {
            writeln!(
                w,
                "  animation   {} channels over {:.3} s",
                self.channels, self.duration
            )?;
        } else {
            writeln!(w, "  animation   none (still)")?;
        }
        for a in &self.animated {
            let moves: Vec<&str> = [
                (a.moves_camera, "the camera"),
                (a.moves_light, "a light"),
                (a.moves_emitter, "an emitter"),
            ]
            .into_iter()
            .filter_map(|(m, what)| m.then_some(what))
            .collect();
            let moves = if moves.is_empty() {
                String::new()
            } else {
                format!(" (moves {})", moves.join(", "))
            };
            let name = if a.name == format!("node {}", a.node) {
                a.name.clone()
            } else {
                format!("'{}' (node {})", a.name, a.node)
            };
            writeln!(
                w,
                "  animated    {name}: {}{moves}",
                a.properties.join(", ")
            )?;
        }
        for warning in &self.warnings {
            writeln!(w, "  warning     {warning}")?;
        }
        Ok(())
    }
}
