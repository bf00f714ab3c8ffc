//! Punctual lights (glTF's KHR_lights_punctual): point, spot and directional lights, which
//! have no area. Their units are converted on loading (see [`LUMENS_PER_WATT`]): a point or
//! spot light carries a radiant intensity `I` (W/sr, RGB) and a directional light an
//! irradiance `E` (W/m^2 on a surface facing it, RGB), in the same units as an emissive
//! material's radiance (`emissiveFactor` x strength, W/m^2/sr).
//!
//! Light from a point light at distance `d` and angle `theta` to the receiver's normal gives
//! the irradiance `I cos(theta) / d^2`; a spot light multiplies `I` by glTF's smooth cone
//! falloff ([`LightKind::falloff`]); a directional light gives `E cos(theta)`.

use glam::Vec3;
use std::f32::consts::PI;

/// Luminous efficacy used to turn glTF's photometric units into irad's radiometric ones:
/// `I = candela / 683` (W/sr) and `E = lux / 683` (W/m^2). It is what Blender's glTF exporter
/// multiplies by when it writes a lamp of `P` watts as `P / (4 pi) * 683` candela (a sun of
/// `S` W/m^2 as `S * 683` lux), while it writes an emission strength `S` as
/// `emissive_strength = S`: with this factor a Blender scene lit by both a lamp and an
/// emissive mesh keeps their ratio.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// What kind of punctual light, with a spot light's cone as cosines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Full intensity within `cos_inner`, none beyond `cos_outer` (cosines of the angles
    /// from the axis; `cos_outer < cos_inner`).
    Spot {
        cos_inner: f32,
        cos_outer: f32,
    },
    Directional,
}

impl LightKind {
    /// The fraction of the intensity sent at cosine `c` from the axis: 1 for a point light;
    /// for a spot light glTF's smooth falloff
    /// `clamp((c - cos_outer) / max(cos_inner - cos_outer, 0.001), 0, 1)^2`.
    pub fn falloff(&self, c: f32) -> f32 {
        match *self {
            LightKind::Spot {
                cos_inner,
                cos_outer,
            } => {
                let a = ((c - cos_outer) / (cos_inner - cos_outer).max(1e-3)).clamp(0.0, 1.0);
                a * a
            }
            _ => 1.0,
        }
    }

    /// The solid angle the light's intensity covers, weighted by its falloff:
    /// `power = intensity * this` for point and spot lights (0 for directional).
    /// For a spot, `2 pi [(1 - cos_inner) + (cos_inner - cos_outer) / 3]` (the integral of the
    /// squared linear ramp between the cosines).
    pub fn solid_angle(&self) -> f32 {
        match *self {
            LightKind::Point => 4.0 * PI,
            LightKind::Spot {
                cos_inner,
                cos_outer,
            } => {
                let ramp = cos_inner - cos_outer;
                if ramp < 1e-3 {
                    // The falloff is then a ramp 0.001 wide in cosine ending at cos_inner.
                    2.0 * PI * ((1.0 - cos_outer) - 1e-3 * (1.0 - 1.0 / 3.0)).max(0.0)
                } else {
                    2.0 * PI * ((1.0 - cos_inner) + ramp / 3.0)
                }
            }
            LightKind::Directional => 0.0,
        }
    }

    /// A short name ("point", "spot", "directional").
    pub fn name(&self) -> &'static str {
        match self {
            LightKind::Point => "point",
            LightKind::Spot { .. } => "spot",
            LightKind::Directional => "directional",
        }
    }
}

/// A light as the file defines it (before its node places it).
#[derive(Clone, Debug, PartialEq)]
pub struct LightDef {
    pub name: String,
    pub kind: LightKind,
    /// Radiant intensity (W/sr) for point and spot lights, irradiance (W/m^2) for
    /// directional ones, RGB: glTF's `color * intensity / 683`.
    pub intensity: Vec3,
}

/// A punctual light placed in a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PunctualLight {
    /// Which of the scene's lights ([`crate::scene::Scene::lights`]).
    pub light: usize,
    pub kind: LightKind,
    /// Where it is (a directional light's is unused).
    pub position: Vec3,
    /// Unit direction it shines in (its node's -Z in world space); unused for point lights.
    pub direction: Vec3,
    /// As [`LightDef::intensity`].
    pub intensity: Vec3,
    /// RGB power in watts: `I * solid angle` for point and spot lights, `E * pi R^2` for a
    /// directional light (R: the radius of the sphere around the frame's geometry).
    pub power: Vec3,
}

impl PunctualLight {
    /// The irradiance this light gives at `x` on a surface with unit normal `n` (without
    /// visibility), and the point whose visibility from `x` counts: the light itself, or for a
    /// directional light the point `far` back along its direction. None where it gives none.
    pub fn irradiance_at(&self, x: Vec3, n: Vec3, far: f32) -> Option<(Vec3, Vec3)> {
        match self.kind {
            LightKind::Directional => {
                let cos_x = -n.dot(self.direction);
                (cos_x > 0.0).then(|| (self.intensity * cos_x, x - self.direction * far))
            }
            kind => {
                let d = x - self.position;
                let d2 = d.length_squared();
                if d2 <= 0.0 {
                    return None;
                }
                let w = d / d2.sqrt();
                let cos_x = -n.dot(w);
                let f = kind.falloff(self.direction.dot(w));
                (cos_x > 0.0 && f > 0.0).then(|| (self.intensity * (f * cos_x / d2), self.position))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spot's solid angle is the integral of its falloff over the sphere, here by a
    /// midpoint sum over the cosine (independent of the closed form).
    #[test]
    fn spot_solid_angle_is_the_integral_of_the_falloff() {
        let kind = LightKind::Spot {
            cos_inner: 0.9,
            cos_outer: 0.6,
        };
        let n = 100_000;
        let sum: f64 = (0..n)
            .map(|i| {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                kind.falloff(c as f32) as f64 * 2.0 / n as f64
            })
            .sum::<f64>()
            * 2.0
            * std::f64::consts::PI;
        assert!(
            (sum - kind.solid_angle() as f64).abs() < 1e-4,
            "{sum} vs {}",
            kind.solid_angle()
        );
        // Falloff: 1 inside, 0 outside, (1/2)^2 halfway in cosine.
        assert_eq!(kind.falloff(0.95), 1.0);
        assert_eq!(kind.falloff(0.5), 0.0);
        assert!((kind.falloff(0.75) - 0.25).abs() < 1e-6);
    }
}
