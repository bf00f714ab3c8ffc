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

/// A summary of a loaded scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspection {
    pub name: String,
    /// Triangles at t = 0.
    pub triangles: usize,
    pub emitters: Vec<EmitterInfo>,
    pub lights: Vec<LightInfo>,
    pub cameras: Vec<CameraInfo>,
    /// The camera irad renders from at t = 0.
    pub camera: Camera,
    /// Animation channels and the length of the animation (seconds).
    pub channels: usize,
    pub duration: f32,
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
    Inspection {
        name: scene.name.clone(),
        triangles: f.tris.len(),
        emitters,
        lights,
        cameras,
        camera: f.camera,
        channels: scene.channels.len(),
        duration: scene.duration(),
        bounds: f.bounds(),
        warnings: scene.warnings.clone(),
    }
}

impl fmt::Display for Inspection {
    fn fmt(&self, w: &mut fmt::Formatter) -> fmt::Result {
        let v = |v: Vec3| format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z);
        writeln!(w, "scene {}", self.name)?;
        writeln!(w, "  triangles   {}", self.triangles)?;
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
        for warning in &self.warnings {
            writeln!(w, "  warning     {warning}")?;
        }
        Ok(())
    }
}
