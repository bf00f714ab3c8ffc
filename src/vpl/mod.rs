//! Stages 4-6: virtual point lights. Light paths leave VPLs on diffuse surfaces; a sampler
//! picks the frame's VPLs and their weights.

pub mod crevice;
pub mod environment;
pub mod gradient;
pub mod importance;
pub mod ism_points;
pub mod paths;
pub mod sampler;

use glam::Vec3;
pub use paths::{trace_path, trace_paths, Vpl};

/// A VPL as the gather sees it: position, normal, and weighted flux
/// `power * albedo_y * weight` (RGB), so that its outgoing radiance at a receiver x is
/// `flux * rho_x * cos_x cos_y / (pi^2 max(d^2, clamp^2))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadedVpl {
    pub position: Vec3,
    pub normal: Vec3,
    pub flux: Vec3,
    /// Read by the compensation alone, within this distance of a pixel's point ([`Vpl::near`]).
    pub near: Option<f32>,
    /// A VPL on the way out of a crevice ([`Vpl::fan`]): its light leaves in a fan.
    pub fan: Option<Vec3>,
}

impl ShadedVpl {
    pub fn new(v: &Vpl, weight: f32) -> Self {
        ShadedVpl {
            position: v.position,
            normal: v.normal,
            flux: v.power * v.albedo * weight,
            near: v.near,
            fan: v.fan,
        }
    }

    /// How the VPL's light falls off toward the unit direction `w` it leaves along: `cos` to
    /// its normal, or for a VPL on the way out of a crevice `pi` times its fan's density
    /// ([`fan_lobe`]). A VPL's radiant intensity along `w` is `flux * lobe(w) / pi`.
    pub fn lobe(&self, w: Vec3) -> f32 {
        match self.fan {
            None => self.normal.dot(w),
            Some(nf) => std::f32::consts::PI * fan_lobe(self.normal, nf, w),
        }
    }

    /// Outgoing radiance at `x` (unit normal `nx` facing the viewer, albedo `rho_x`),
    /// without visibility.
    pub fn radiance_at(&self, x: Vec3, nx: Vec3, rho_x: Vec3, clamp: f32) -> Vec3 {
        let d = self.position - x;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return Vec3::ZERO;
        }
        let w = d / d2.sqrt();
        let cos_x = nx.dot(w);
        let cos_y = self.lobe(-w);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            return Vec3::ZERO;
        }
        self.flux * rho_x * (cos_x * cos_y / (std::f32::consts::PI.powi(2) * d2.max(clamp * clamp)))
    }
}

/// The density (per steradian) of the directions `w` in which the light of a VPL on the way out
/// of a crevice leaves ([`Vpl::fan`]): the path left along `d`, from a vertex with normal `nf`
/// (facing into the crevice, so `d . nf > 0`), at the elevation `e_d = asin(d . nf)` above the
/// crevice's plane. Light gets out of a thin crevice only close to its plane (within `gap /
/// depth` radians), so the density spreads the path's one direction evenly over the elevations
/// within `h = min(e_d, pi/2 - e_d)` of `e_d` (from the plane to `2 e_d` for a direction less
/// steep than 45 degrees) and over the azimuth as a cosine about `d`'s: `cos(phi) / (4 h
/// cos(e))`, which integrates to 1 over the sphere (docs/math.md, "Out of a 1 mm gap, in a
/// fan"). 0 outside the fan, and for `d` in the plane or along its normal.
pub fn fan_lobe(d: Vec3, nf: Vec3, w: Vec3) -> f32 {
    let sd = d.dot(nf);
    let sw = w.dot(nf);
    if sd <= 0.0 || sw <= 0.0 {
        return 0.0;
    }
    let ed = sd.min(1.0).asin();
    let h = ed.min(std::f32::consts::FRAC_PI_2 - ed);
    if h <= 0.0 || (sw.min(1.0).asin() - ed).abs() >= h {
        return 0.0;
    }
    // In-plane parts: |a| = cos e_d, |b| = cos e.
    let a = d - nf * sd;
    let b = w - nf * sw;
    let (la, lb2) = (a.length(), b.length_squared());
    let ab = a.dot(b);
    if ab <= 0.0 || la <= 0.0 || lb2 <= 0.0 {
        return 0.0;
    }
    // cos(phi) / cos(e) = (a . b) / (|a| |b|^2).
    ab / (la * lb2) / (4.0 * h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    /// The fan's density integrates to 1 over the sphere (so a VPL on the way out of a crevice
    /// sends out the power its path carried), its elevations lie within `min(e_d, pi/2 - e_d)`
    /// of `e_d` on the side of `nf` (mean `e_d`), and its azimuths within 90 degrees of `d`'s
    /// with mean cosine `pi / 4` (a cosine's). A midpoint rule over elevation and azimuth, for
    /// `e_d` from a hundredth of a radian to 1.2 and a plane normal off every axis.
    #[test]
    fn a_fans_density_integrates_to_one_about_its_direction() {
        let nf = Vec3::new(0.3, -0.8, 0.2).normalize();
        let (t, b) = crate::math::basis(nf);
        for ed in [0.01f32, 0.1, 0.4, 1.2] {
            let az = 0.7f32;
            let inplane = t * az.cos() + b * az.sin();
            let d = inplane * ed.cos() + nf * ed.sin();
            let (ne, na) = (16000, 360);
            let (mut total, mut mean_e, mut mean_cos, mut outside) = (0.0f64, 0.0f64, 0.0f64, 0.0);
            for i in 0..ne {
                // Elevation over the whole sphere, -pi/2..pi/2.
                let e = -PI / 2.0 + PI * (i as f32 + 0.5) / ne as f32;
                for j in 0..na {
                    let phi = 2.0 * PI * (j as f32 + 0.5) / na as f32;
                    let w = (t * (az + phi).cos() + b * (az + phi).sin()) * e.cos() + nf * e.sin();
                    let f = fan_lobe(d, nf, w);
                    assert!(f >= 0.0 && f.is_finite());
                    let dw = (e.cos() * (PI / ne as f32) * (2.0 * PI / na as f32)) as f64;
                    total += f as f64 * dw;
                    mean_e += (f * e) as f64 * dw;
                    mean_cos += (f * w.dot(inplane).max(0.0) / e.cos()) as f64 * dw;
                    let h = ed.min(PI / 2.0 - ed);
                    if f > 0.0 && ((e - ed).abs() >= h + 1e-3 || w.dot(inplane) <= 0.0) {
                        outside += 1.0;
                    }
                }
            }
            assert!(
                (total - 1.0).abs() < 0.01,
                "e_d {ed}: the fan integrates to {total}"
            );
            assert!(
                ((mean_e / total) as f32 - ed).abs() < 0.01 * ed.max(0.1),
                "e_d {ed}: mean elevation {mean_e}"
            );
            assert!(
                ((mean_cos / total) as f32 - PI / 4.0).abs() < 0.01,
                "e_d {ed}: {mean_cos}"
            );
            assert_eq!(outside, 0.0, "e_d {ed}: light outside the fan");
        }
        // A direction in the plane, or on the other side of it, has no fan.
        assert_eq!(fan_lobe(t, nf, (t + nf * 0.01).normalize()), 0.0);
        assert_eq!(fan_lobe(-nf, nf, (t - nf * 0.01).normalize()), 0.0);
    }

    /// A VPL without a fan is the cosine lobe the gather has always read, and one with a fan
    /// reads it: `radiance_at` is `flux rho cos_x lobe / (pi^2 d^2)`.
    #[test]
    fn a_vpls_radiance_follows_its_lobe() {
        let nf = -Vec3::Y;
        let d = (Vec3::Z * 0.2f32.cos() + nf * 0.2f32.sin()).normalize();
        let v = ShadedVpl {
            position: Vec3::ZERO,
            normal: d,
            flux: Vec3::ONE,
            near: None,
            fan: Some(nf),
        };
        // A receiver at elevation 0.1 under the plane, straight ahead, facing the VPL.
        let w = (Vec3::Z * 0.1f32.cos() + nf * 0.1f32.sin()).normalize();
        let x = w * 2.0;
        let got = v.radiance_at(x, -w, Vec3::ONE, 0.0).x;
        let want = PI * fan_lobe(d, nf, w) / (PI * PI * 4.0);
        assert!((got - want).abs() < 1e-6 * want, "{got} {want}");
        // Beyond the fan (elevation 0.5 > 2 e_d): nothing; as a cosine lobe, something.
        let w2 = (Vec3::Z * 0.5f32.cos() + nf * 0.5f32.sin()).normalize();
        assert_eq!(v.radiance_at(w2 * 2.0, -w2, Vec3::ONE, 0.0), Vec3::ZERO);
        let c = ShadedVpl { fan: None, ..v };
        let cos = c.radiance_at(w2 * 2.0, -w2, Vec3::ONE, 0.0).x;
        assert!((cos - d.dot(w2) / (PI * PI * 4.0)).abs() < 1e-6, "{cos}");
    }
}
