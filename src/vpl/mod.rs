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
}

impl ShadedVpl {
    pub fn new(v: &Vpl, weight: f32) -> Self {
        ShadedVpl {
            position: v.position,
            normal: v.normal,
            flux: v.power * v.albedo * weight,
            near: v.near,
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
        let cos_y = -self.normal.dot(w);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            return Vec3::ZERO;
        }
        self.flux * rho_x * (cos_x * cos_y / (std::f32::consts::PI.powi(2) * d2.max(clamp * clamp)))
    }
}
