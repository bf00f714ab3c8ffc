//! Stages 3 and 5: camera points and the importance of a VPL.
//!
//! Camera points are K surface points seen through jittered, stratified pixels of the frame's
//! camera (a low-resolution G-buffer on the CPU), deterministic for (seed, frame). The jitter
//! is the same in every frame: in a still view a kept VPL's importance does not change, and in
//! a moving one the points move with the camera, so importance changes only as the view does
//! (fresh jitter each frame would make every kept VPL's weight wobble). A VPL's
//! importance is its clamped contribution's luminance summed over them, with ray-traced
//! visibility: `I(v) = sum_k lum(C_v(x_k))`. Samplers add the defensive floor `eps * mean(I)`.

use super::{ShadedVpl, Vpl};
use crate::math::{luminance, rng};
use crate::scene::Frame;
use crate::trace::Tracer;
use glam::{Vec2, Vec3};
use rand::Rng;
use rayon::prelude::*;

/// A camera point: position, normal facing the camera, albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPoint {
    pub x: Vec3,
    pub n: Vec3,
    pub albedo: Vec3,
}

/// Up to `k` camera points through a jittered grid of strata over a `width` x `height` image
/// (strata whose ray hits nothing give no point).
pub fn camera_points(
    frame: &Frame,
    tracer: &Tracer,
    width: u32,
    height: u32,
    k: usize,
    seed: u64,
) -> Vec<CameraPoint> {
    let aspect = width as f32 / height as f32;
    let gx = ((k as f32 * aspect).sqrt().round() as usize).max(1);
    let gy = k.div_ceil(gx).max(1);
    let mut r = rng(&[seed, 0xca3e]);
    let jitter: Vec<Vec2> = (0..gx * gy)
        .map(|_| Vec2::new(r.random(), r.random()))
        .collect();
    (0..gx * gy)
        .into_par_iter()
        .filter_map(|s| {
            let (i, j) = (s % gx, s / gx);
            let p = Vec2::new(
                (i as f32 + jitter[s].x) / gx as f32 * width as f32,
                (j as f32 + jitter[s].y) / gy as f32 * height as f32,
            );
            let d = frame.camera.ray_dir(p, width, height);
            let h = tracer.intersect(frame.camera.position, d, f32::INFINITY)?;
            let ng = frame.normals[h.tri as usize];
            Some(CameraPoint {
                x: frame.point(h.tri as usize, h.b1, h.b2),
                n: if ng.dot(d) < 0.0 { ng } else { -ng },
                albedo: frame.albedo_at(h.tri as usize, h.b1, h.b2),
            })
        })
        .collect()
}

/// `I(v)`: the VPL's clamped, unweighted contribution summed over the camera points, with
/// visibility (no floor).
pub fn importance(v: &Vpl, points: &[CameraPoint], tracer: &Tracer, clamp: f32) -> f32 {
    let s = ShadedVpl::new(v, 1.0);
    points
        .iter()
        .map(|p| {
            let c = s.radiance_at(p.x, p.n, p.albedo, clamp);
            if c == Vec3::ZERO || tracer.occluded(p.x, p.n, v.position, v.normal) {
                0.0
            } else {
                luminance(c)
            }
        })
        .sum()
}

/// Importance of many VPLs in parallel.
pub fn importance_all(
    vpls: &[Vpl],
    points: &[CameraPoint],
    tracer: &Tracer,
    clamp: f32,
) -> Vec<f32> {
    vpls.par_iter()
        .map(|v| importance(v, points, tracer, clamp))
        .collect()
}
