//! The CPU twin of the GPU passes: the same camera points, VPLs and emitter samples, shaded
//! with ray-traced (exact) visibility. It separates the error that ISMs and shadow maps add
//! from the error that sampling adds, and the tests hold the GPU images to it.

use crate::image::Hdr;
use crate::scene::{EmitterSample, Frame};
use crate::trace::Tracer;
use crate::vpl::ShadedVpl;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// A visible surface point of a pixel: position, normal facing the camera, triangle.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub x: Vec3,
    pub n: Vec3,
    pub tri: u32,
    /// Barycentrics of `x` in `tri`.
    pub b: Vec2,
}

/// The surface seen through each pixel centre (None: nothing), row 0 at the top.
pub fn pixel_points(
    frame: &Frame,
    tracer: &Tracer,
    width: u32,
    height: u32,
) -> Vec<Option<SurfacePoint>> {
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            let p = Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            let d = frame.camera.ray_dir(p, width, height);
            tracer
                .intersect(frame.camera.position, d, f32::INFINITY)
                .map(|h| {
                    let ng = frame.normals[h.tri as usize];
                    SurfacePoint {
                        x: frame.point(h.tri as usize, h.b1, h.b2),
                        n: if ng.dot(d) < 0.0 { ng } else { -ng },
                        tri: h.tri,
                        b: Vec2::new(h.b1, h.b2),
                    }
                })
        })
        .collect()
}

fn image(width: u32, height: u32, f: impl Fn(usize) -> Vec3 + Sync + Send) -> Hdr {
    Hdr {
        width,
        height,
        data: (0..(width * height) as usize)
            .into_par_iter()
            .map(f)
            .collect(),
    }
}

/// Indirect light of `vpls` at every pixel, with exact visibility.
pub fn gather(
    frame: &Frame,
    tracer: &Tracer,
    points: &[Option<SurfacePoint>],
    width: u32,
    height: u32,
    vpls: &[ShadedVpl],
    dmin: f32,
) -> Hdr {
    image(width, height, |i| {
        let Some(s) = points[i] else {
            return Vec3::ZERO;
        };
        let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y);
        vpls.iter()
            .map(|v| {
                let c = v.radiance_at(s.x, s.n, rho, dmin);
                if c == Vec3::ZERO || tracer.occluded(s.x, s.n, v.position, v.normal) {
                    Vec3::ZERO
                } else {
                    c
                }
            })
            .sum()
    })
}

/// Direct light of the emitter samples at every pixel, with exact visibility.
pub fn direct(
    frame: &Frame,
    tracer: &Tracer,
    points: &[Option<SurfacePoint>],
    width: u32,
    height: u32,
    samples: &[EmitterSample],
) -> Hdr {
    image(width, height, |i| {
        let Some(s) = points[i] else {
            return Vec3::ZERO;
        };
        let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y);
        samples
            .iter()
            .filter_map(|l| l.irradiance_at(s.x, s.n))
            .filter(|&(_, y, ny)| !tracer.occluded(s.x, s.n, y, ny))
            .map(|(e, _, _)| e * rho / PI)
            .sum()
    })
}

/// Emission seen from the camera (front faces only).
pub fn emission(frame: &Frame, points: &[Option<SurfacePoint>], width: u32, height: u32) -> Hdr {
    image(width, height, |i| match points[i] {
        Some(s) if frame.normals[s.tri as usize].dot(frame.camera.position - s.x) > 0.0 => {
            frame.emission_at(s.tri as usize, s.b.x, s.b.y)
        }
        _ => Vec3::ZERO,
    })
}
