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

/// A camera point: position, normal facing the camera, albedo, and the index of its stratum
/// in the grid (row-major; strata whose ray hits nothing give no point, so a point's index in
/// the list may change from frame to frame where its stratum's does not).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPoint {
    pub x: Vec3,
    pub n: Vec3,
    pub albedo: Vec3,
    pub stratum: u32,
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
                stratum: s as u32,
            })
        })
        .collect()
}

/// `I(v)`: the VPL's clamped, unweighted contribution summed over the camera points, with
/// visibility (no floor).
pub fn importance(v: &Vpl, points: &[CameraPoint], tracer: &Tracer, clamp: f32) -> f32 {
    importance_sampled(v, points, tracer, clamp, 1)
}

/// `I(v)` estimated from the camera points of every `stride`-th stratum, from an offset
/// `o < stride` of the VPL's own (a hash of its path and depth, so the same in every frame),
/// times `stride`: `stride * sum_{k: stratum_k = o mod stride} lum(C_v(x_k))`, whose mean
/// over the offsets is `I(v)` exactly. `stride` 1 is `I(v)`. By stratum, not by place in the
/// list: as the camera moves, strata that start or stop seeing geometry would otherwise shift
/// every later point into another subset, and a kept VPL's sampled importance would jump
/// (on `cornell-orbit` the pool's change then drove `mh`'s rate to 1 in most frames). An odd
/// stride on a grid of even width (16 strata a row at 256 points on a square image) takes
/// strata that run diagonally across the grid rather than down a few columns.
pub fn importance_sampled(
    v: &Vpl,
    points: &[CameraPoint],
    tracer: &Tracer,
    clamp: f32,
    stride: usize,
) -> f32 {
    let stride = stride.max(1);
    let o = if stride == 1 {
        0
    } else {
        (crate::math::stream_seed(&[v.path, v.depth as u64, 0x5b1d]) % stride as u64) as usize
    };
    importance_at_offset(v, points, tracer, clamp, (stride, o))
}

/// `stride * sum_{k: stratum_k = o mod stride} lum(C_v(x_k))` ([`importance_sampled`] at
/// offset `o`).
fn importance_at_offset(
    v: &Vpl,
    points: &[CameraPoint],
    tracer: &Tracer,
    clamp: f32,
    (stride, o): (usize, usize),
) -> f32 {
    let s = ShadedVpl::new(v, 1.0);
    let sum: f32 = points
        .iter()
        .filter(|p| stride == 1 || p.stratum as usize % stride == o)
        .map(|p| {
            let c = s.radiance_at(p.x, p.n, p.albedo, clamp);
            if c == Vec3::ZERO || tracer.occluded(p.x, p.n, v.position, v.normal) {
                0.0
            } else {
                luminance(c)
            }
        })
        .sum();
    sum * stride as f32
}

/// Importance of many VPLs in parallel.
pub fn importance_all(
    vpls: &[Vpl],
    points: &[CameraPoint],
    tracer: &Tracer,
    clamp: f32,
) -> Vec<f32> {
    importance_all_sampled(vpls, points, tracer, clamp, 1)
}

/// [`importance_sampled`] of many VPLs in parallel.
pub fn importance_all_sampled(
    vpls: &[Vpl],
    points: &[CameraPoint],
    tracer: &Tracer,
    clamp: f32,
    stride: usize,
) -> Vec<f32> {
    vpls.par_iter()
        .map(|v| importance_sampled(v, points, tracer, clamp, stride))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use crate::vpl::trace_paths;

    /// The sampled importance's mean over its offsets is the full sum, VPL by VPL, and stride 1
    /// is the full sum itself (the pool of `mh` relies on both: its b stays unbiased).
    #[test]
    fn sampled_importance_averages_to_the_full_sum_over_the_offsets() {
        let scene = builtin::load("cornell-orbit").unwrap().unwrap();
        let f = scene.at(0.3);
        let tr = Tracer::new(&f);
        let points = camera_points(&f, &tr, 64, 64, 256, 3);
        assert!(points.len() > 200, "{} camera points", points.len());
        let vpls = trace_paths(&f, &tr, 3, 0, 16);
        let mut checked = 0;
        for v in &vpls {
            let full = importance(v, &points, &tr, 0.1);
            assert_eq!(importance_sampled(v, &points, &tr, 0.1, 1), full);
            for stride in [3usize, 5, 17] {
                let mean = (0..stride)
                    .map(|o| importance_at_offset(v, &points, &tr, 0.1, (stride, o)) as f64)
                    .sum::<f64>()
                    / stride as f64;
                assert!(
                    (mean - full as f64).abs() <= 1e-4 * full as f64 + 1e-9,
                    "stride {stride}: mean {mean} against {full}"
                );
                // And one offset alone differs (else the test shows nothing).
                let one = importance_sampled(v, &points, &tr, 0.1, stride);
                checked += usize::from(full > 0.0 && one != full);
            }
        }
        assert!(
            checked > 20,
            "only {checked} sampled sums differ from the full one"
        );
    }
}
