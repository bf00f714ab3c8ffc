//! Display of a solution: element radiance interpolated to vertices (Gouraud) and, on the
//! CPU, the image a camera sees of it ([`render_cpu`], the twin of the GPU radiosity pass
//! and what the tests measure against the path-traced reference).

use super::{Part, Solution};
use crate::image::Hdr;
use crate::math::rng;
use crate::scene::{EmitterSample, Frame};
use crate::trace::Tracer;
use glam::{Vec2, Vec3};
use rand::Rng;
use rayon::prelude::*;
use std::f32::consts::PI;

/// A solution ready to show: Gouraud values at each element's corners and the elements
/// as a frame with its own BVH (a hit's triangle is the element).
pub struct Shaded {
    pub part: Part,
    pub corners: Vec<[Vec3; 3]>,
    pub elements: Frame,
    pub tracer: Tracer,
}

impl<'a> From<&'a Shaded> for crate::gpu::radiosity::Gouraud<'a> {
    fn from(s: &'a Shaded) -> Self {
        crate::gpu::radiosity::Gouraud {
            elements: &s.elements,
            corners: &s.corners,
        }
    }
}

impl Shaded {
    pub fn new(frame: &Frame, sol: &Solution, part: Part) -> Shaded {
        let corners = sol.corner_values(frame, part);
        let elements = sol.mesh.as_frame(frame);
        let tracer = Tracer::new(&elements);
        Shaded {
            part,
            corners,
            elements,
            tracer,
        }
    }

    /// Interpolated reflected radiance on element `e` at barycentrics (b1, b2).
    pub fn at(&self, e: usize, b1: f32, b2: f32) -> Vec3 {
        let c = &self.corners[e];
        c[0] * (1.0 - b1 - b2) + c[1] * b1 + c[2] * b2
    }
}

/// Direct light at `x` (normal `n`, albedo `rho`) from emitter samples, with shadow rays.
pub fn direct_at(tracer: &Tracer, lights: &[EmitterSample], x: Vec3, n: Vec3, rho: Vec3) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for l in lights {
        if let Some((e, y, ny)) = l.irradiance_at(x, n) {
            if !tracer.occluded(x, n, y, ny) {
                sum += e;
            }
        }
    }
    rho / PI * sum
}

/// Image size and sampling of [`render_cpu`].
#[derive(Clone, Copy, Debug)]
pub struct DisplayView {
    pub width: u32,
    pub height: u32,
    /// Jittered camera rays per pixel; 0: one ray through each pixel's centre (what the
    /// GPU pass rasterizes).
    pub spp: u32,
    /// Emitter samples for direct light ([`Part::Indirect`] only).
    pub light_samples: usize,
    pub seed: u64,
}

/// The camera's image of a solution: `spp` jittered rays per pixel (box filter, like the
/// reference), emission on front faces, the interpolated radiance, and with
/// [`Part::Indirect`] direct light from `light_samples` emitter samples traced in `scene`.
pub fn render_cpu(frame: &Frame, scene: &Tracer, shaded: &Shaded, v: &DisplayView) -> Hdr {
    let DisplayView {
        width,
        height,
        spp,
        light_samples,
        seed,
    } = *v;
    let lights = if shaded.part == Part::Indirect {
        frame.emitter_samples(seed, light_samples)
    } else {
        Vec::new()
    };
    let mut img = Hdr::new(width, height);
    img.data
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let mut r = rng(&[seed, (y as u64) << 32 | x as u64, 0x7ad]);
                let mut sum = Vec3::ZERO;
                for _ in 0..spp.max(1) {
                    let p = if spp == 0 {
                        Vec2::new(x as f32 + 0.5, y as f32 + 0.5)
                    } else {
                        Vec2::new(x as f32 + r.random::<f32>(), y as f32 + r.random::<f32>())
                    };
                    let dir = frame.camera.ray_dir(p, width, height);
                    let Some(h) =
                        shaded
                            .tracer
                            .intersect(frame.camera.position, dir, f32::INFINITY)
                    else {
                        continue;
                    };
                    let e = h.tri as usize;
                    let n = shaded.elements.normals[e];
                    if n.dot(dir) >= 0.0 {
                        continue; // the back of a one-sided element
                    }
                    sum += shaded.elements.emission(e) + shaded.at(e, h.b1, h.b2);
                    if !lights.is_empty() {
                        let xp = shaded.elements.point(e, h.b1, h.b2);
                        sum += direct_at(scene, &lights, xp, n, shaded.elements.albedo(e));
                    }
                }
                *px = sum / spp.max(1) as f32;
            }
        });
    img
}
