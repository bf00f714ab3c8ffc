//! KHR_lights_punctual: the file's lights in irad's units (see [`crate::scene::lights`]), and
//! the light each node carries. Read from the typed JSON (the gltf crate's own accessors
//! unwrap what a hostile file may leave out).

use super::{Ctx, LoadError};
use crate::scene::lights::{LightDef, LightKind, LUMENS_PER_WATT};
use glam::Vec3;
use gltf::json::extensions::scene::khr_lights_punctual::{Light, Type};
use gltf::json::validation::Checked;
use std::f32::consts::FRAC_PI_2;

/// The largest intensity (W/sr) or irradiance (W/m^2) irad accepts after conversion: the
/// power of such a light still sums in 32-bit floats.
const MAX_INTENSITY: f32 = 1e10;

/// The file's lights, in the order of its `lights` array.
pub(super) fn read(cx: &mut Ctx, doc: &gltf::Document) -> Result<Vec<LightDef>, LoadError> {
    let lights = doc
        .as_json()
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map_or(&[][..], |k| k.lights.as_slice());
    lights
        .iter()
        .enumerate()
        .map(|(i, l)| one(cx, i, l))
        .collect()
}

fn one(cx: &mut Ctx, i: usize, l: &Light) -> Result<LightDef, LoadError> {
    let name = l.name.clone().unwrap_or_default();
    let what = format!("KHR_lights_punctual light {i} ('{name}')");
    let kind = match &l.type_ {
        Checked::Valid(Type::Point) => LightKind::Point,
        Checked::Valid(Type::Directional) => LightKind::Directional,
        Checked::Valid(Type::Spot) => spot(cx, &what, l)?,
        Checked::Invalid => {
            return Err(cx.err(format!(
                "{what} has an unknown type (glTF's are point, spot and directional)"
            )))
        }
    };
    let color = Vec3::from(l.color);
    if !color.is_finite() || color.min_element() < 0.0 {
        return Err(cx.err(format!(
            "{what} has the colour {color}, not a finite colour >= 0"
        )));
    }
    if !l.intensity.is_finite() || l.intensity < 0.0 {
        return Err(cx.err(format!(
            "{what} has the intensity {}, not a finite number >= 0",
            l.intensity
        )));
    }
    let intensity = color * (l.intensity / LUMENS_PER_WATT);
    if intensity.max_element() <= 0.0 {
        cx.warn(format!(
            "{what} emits nothing (intensity {} x colour {color}): it lights nothing",
            l.intensity
        ));
    }
    if intensity.max_element() > MAX_INTENSITY {
        return Err(cx.err(format!(
            "{what} has the intensity {} {} ({} in irad's units), above irad's limit of {MAX_INTENSITY:e} (light is summed in 32-bit floats)",
            l.intensity,
            if kind == LightKind::Directional { "lux" } else { "candela" },
            intensity
        )));
    }
    if l.range.is_some() {
        cx.warn("KHR_lights_punctual range is ignored: light falls off with the inverse square of distance to any distance");
    }
    Ok(LightDef {
        name,
        kind,
        intensity,
    })
}

/// A spot's cone; angles outside glTF's `0 <= inner < outer <= pi/2` are clamped there.
fn spot(cx: &mut Ctx, what: &str, l: &Light) -> Result<LightKind, LoadError> {
    let Some(s) = l.spot.as_ref() else {
        return Err(cx.err(format!("{what} is a spot light without its 'spot' cone")));
    };
    let (inner, outer) = (s.inner_cone_angle, s.outer_cone_angle);
    if !(inner.is_finite() && outer.is_finite()) {
        return Err(cx.err(format!(
            "{what} has the cone angles {inner} and {outer}, not finite numbers"
        )));
    }
    let outer_c = outer.clamp(1e-4, FRAC_PI_2);
    let inner_c = inner.clamp(0.0, outer_c);
    if (inner_c, outer_c) != (inner, outer) || inner >= outer {
        cx.warn(format!(
            "{what}: spot cone angles inner {inner} and outer {outer} are outside glTF's 0 <= inner < outer <= pi/2, so they are clamped to {inner_c} and {outer_c}"
        ));
    }
    Ok(LightKind::Spot {
        cos_inner: inner_c.cos(),
        cos_outer: outer_c.cos(),
    })
}

/// The light node `n` carries, if any.
pub(super) fn of_node(
    cx: &Ctx,
    doc: &gltf::Document,
    n: usize,
    count: usize,
) -> Result<Option<usize>, LoadError> {
    let light = doc.as_json().nodes[n]
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map(|k| k.light.value());
    match light {
        Some(l) if l >= count => Err(cx.err(format!(
            "invalid glTF: node {n} carries KHR_lights_punctual light {l}, but there are {count}"
        ))),
        l => Ok(l),
    }
}
