//! Clamping-bias compensation, on the CPU after the GPU passes (`--compensate K`, off by
//! default): the light that the distance clamp of the gather leaves out, added back by short
//! rays, after Kollig & Keller (2004). docs/math.md section 4 has the derivation.
//!
//! The gather divides by `max(d^2, clamp^2)` instead of `d^2`, so a VPL at `y` closer than
//! `clamp` to the receiver `x` gives `1 - d^2 / clamp^2` less than it should. Summed over the
//! VPLs and written over the directions from `x`, what is missing is
//!
//! `L_c(x) = rho_x / pi * integral of L_r(y(w)) * max(0, 1 - d^2 / clamp^2) cos(theta_x) dw`,
//!
//! with `y(w)` the first surface along `w` at distance `d` and `L_r(y)` the light reflected
//! there (direct and indirect, no emission: that is what the VPLs stand for). With `K`
//! cosine-distributed rays of length `clamp` from the pixel's surface point, the estimate is
//! `rho_x / K * sum of L_r(y_k) (1 - d_k^2 / clamp^2)`. `L_r(y)` is the frame's own estimate at
//! `y` with exact visibility: its emitter samples, and a stratified subset of its VPLs
//! (each weighted by the share it stands for), clamped as the gather is. The part of `L_r`
//! that the clamp takes from `y` itself is not added back (a second-order term, left out).
//!
//! Rays exist only where surfaces meet within `clamp` (creases, corners, contacts); the random
//! numbers of a pixel are the same every frame, so a still view's compensation is still.

use crate::math::{cosine_hemisphere, rng};
use crate::reference::twin::SurfacePoint;
use crate::scene::{EmitterSample, Frame};
use crate::trace::Tracer;
use crate::vpl::ShadedVpl;
use glam::{Vec2, Vec3};
use rand::Rng;
use rayon::prelude::*;
use std::f32::consts::PI;

/// VPLs (at most) whose light at a ray's hit point is evaluated, as a stratified subset.
pub const VPLS_AT_HIT: usize = 32;

/// What the compensation reads: the frame's light, as the GPU's passes had it.
pub struct Light<'a> {
    pub samples: &'a [EmitterSample],
    pub vpls: &'a [ShadedVpl],
    pub clamp: f32,
}

/// The light the clamp left out at each pixel whose surface has another within `clamp`:
/// (pixel index, radiance to add), from `rays` rays a pixel (0: none); `points` are the
/// pixels' surface points (`reference::twin::pixel_points`).
pub fn compensate(
    frame: &Frame,
    tracer: &Tracer,
    points: &[Option<SurfacePoint>],
    light: &Light,
    rays: u32,
    seed: u64,
) -> Vec<(usize, Vec3)> {
    if rays == 0 || light.clamp <= 0.0 || light.vpls.is_empty() && light.samples.is_empty() {
        return Vec::new();
    }
    points
        .par_iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let s = (*p)?;
            let l = at_point(frame, tracer, &s, light, rays, &[seed, i as u64, 0xc1a3]);
            (l != Vec3::ZERO).then_some((i, l))
        })
        .collect()
}

/// `L_c` at surface point `s` from `rays` stratified rays drawn from the stream `stream`.
pub fn at_point(
    frame: &Frame,
    tracer: &Tracer,
    s: &SurfacePoint,
    light: &Light,
    rays: u32,
    stream: &[u64],
) -> Vec3 {
    let mut r = rng(stream);
    let clamp = light.clamp;
    let mut sum = Vec3::ZERO;
    for k in 0..rays {
        let u = Vec2::new((k as f32 + r.random::<f32>()) / rays as f32, r.random());
        let w = cosine_hemisphere(s.n, u);
        let Some(h) = tracer.intersect(tracer.offset(s.x, s.n, w), w, clamp) else {
            continue;
        };
        let weight = 1.0 - (h.t / clamp).powi(2);
        if weight <= 0.0 {
            continue;
        }
        let ng = frame.normals[h.tri as usize];
        let y = SurfacePoint {
            x: frame.point(h.tri as usize, h.b1, h.b2),
            n: if ng.dot(w) < 0.0 { ng } else { -ng },
            tri: h.tri,
            b: Vec2::new(h.b1, h.b2),
        };
        sum += reflected(frame, tracer, &y, light, r.random()) * weight;
    }
    let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y);
    rho * sum / rays as f32
}

/// The light reflected at `y` (direct from the emitter samples, indirect from a stratified
/// subset of the VPLs starting at fraction `u` of them, clamped), with exact visibility.
fn reflected(frame: &Frame, tracer: &Tracer, y: &SurfacePoint, light: &Light, u: f32) -> Vec3 {
    let rho = frame.albedo_at(y.tri as usize, y.b.x, y.b.y);
    let direct: Vec3 = light
        .samples
        .iter()
        .filter_map(|l| l.irradiance_at(y.x, y.n))
        .filter(|&(_, p, np)| !tracer.occluded(y.x, y.n, p, np))
        .map(|(e, _, _)| e * rho / PI)
        .sum();
    let n = light.vpls.len();
    let m = n.min(VPLS_AT_HIT);
    if m == 0 {
        return direct;
    }
    let first = ((u * n as f32) as usize).min(n - 1);
    let indirect: Vec3 = (0..m)
        .map(|j| &light.vpls[(first + j * n / m) % n])
        .map(|v| {
            let c = v.radiance_at(y.x, y.n, rho, light.clamp);
            if c == Vec3::ZERO || tracer.occluded(y.x, y.n, v.position, v.normal) {
                Vec3::ZERO
            } else {
                c
            }
        })
        .sum();
    direct + indirect * (n as f32 / m as f32)
}
