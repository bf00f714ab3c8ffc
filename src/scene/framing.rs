//! A camera for a file that has none: one that sees what the lights light. Points spread
//! over the surfaces by area are lit by a few emitter samples (with shadow rays); eyes around
//! the lit region, outside it and inside it, are scored by the light of the points they see,
//! each weighted by the cosine it is seen at (its share of the image). Views within a few
//! percent of the best are told apart by how many triangles they see: a board lit by a sky
//! on both sides is seen from its front, where its panels are, not from its plain back (the
//! Khronos TextureSettingsTest). An eye inside a closed mesh (most rays from it first meet
//! the inside of a solid) is never chosen.

use super::{Camera, Frame};
use crate::trace::Tracer;
use glam::{Vec2, Vec3};
use rand::Rng;

/// Surface points and emitter samples per point used to find what is lit.
const POINTS: usize = 512;
const LIGHT_SAMPLES: usize = 16;
/// The field of view of the chosen camera (radians, 50 degrees).
const YFOV: f32 = 0.8727;

/// A lit surface point: position, the normal of its lit side, and its irradiance (luminance).
struct Lit {
    x: Vec3,
    n: Vec3,
    e: f32,
    tri: u32,
}

/// Views whose scores are within this fraction of the best are told apart by how many of the
/// model's triangles they see: a score sums the light of at most [`POINTS`] points, too few to
/// rank views this close (a board's front and back score the same lit area).
const NEAR_BEST: f32 = 0.05;

/// The camera that sees the most light among eyes around the lit region, or the camera
/// framing the bounds from +Z when nothing is lit at this frame.
pub fn lit_camera(frame: &Frame) -> Camera {
    let (lo, hi) = frame.bounds();
    let fallback = Camera::framing(lo, hi);
    if frame.tris.is_empty() || frame.emitters.is_empty() {
        return fallback;
    }
    let tracer = Tracer::new(frame);
    let lit = lit_points(frame, &tracer);
    let Some(emax) = lit.iter().map(|l| l.e).reduce(f32::max) else {
        return fallback;
    };
    // The region: points with at least 1% of the brightest's light.
    let bright: Vec<&Lit> = lit.iter().filter(|l| l.e >= 0.01 * emax).collect();
    let (blo, bhi) = super::bounds(bright.iter().map(|l| l.x));
    let center = (blo + bhi) * 0.5;
    let radius = ((bhi - blo).length() * 0.5).max(1e-3);
    let dist = 1.1 * radius / (YFOV * 0.5).sin();
    let solid = solid_triangles(frame);
    let mut views = Vec::new();
    for f in [1.0, 0.6, 0.3] {
        for dir in directions() {
            let eye = center + dir * dist * f;
            if inside_solid(frame, &tracer, &solid, eye) {
                continue;
            }
            let cam = look_from(eye, center);
            let (s, parts) = score(&cam, &lit, &tracer);
            views.push((s, parts, cam));
        }
    }
    // The most light; among views within NEAR_BEST of it, the one that sees the most
    // triangles (a board's front, with its panels, over its plain back), then the most light.
    let top = views.iter().map(|v| v.0).fold(0.0f32, f32::max);
    let mut best: Option<(f32, usize, Camera)> = None;
    for v in views
        .into_iter()
        .filter(|v| v.0 > 0.0 && v.0 >= (1.0 - NEAR_BEST) * top)
    {
        if best
            .as_ref()
            .is_none_or(|b| v.1 > b.1 || (v.1 == b.1 && v.0 > b.0))
        {
            best = Some(v);
        }
    }
    best.map_or(fallback, |b| b.2)
}

/// For each triangle, whether it belongs to a closed mesh.
fn solid_triangles(frame: &Frame) -> Vec<bool> {
    let mut s = vec![false; frame.tris.len()];
    for i in frame.instances.iter().filter(|i| i.closed) {
        for t in i.tris.clone() {
            if let Some(x) = s.get_mut(t as usize) {
                *x = true;
            }
        }
    }
    s
}

/// Whether `eye` lies inside a closed mesh: more than half of the 26 rays from it first meet
/// a closed mesh's triangle from behind (from inside a solid every ray does).
fn inside_solid(frame: &Frame, tracer: &Tracer, solid: &[bool], eye: Vec3) -> bool {
    if !solid.contains(&true) {
        return false;
    }
    let dirs = directions();
    let inside = dirs
        .iter()
        .filter(|&&d| {
            tracer
                .intersect_light(eye, d, f32::INFINITY)
                .is_some_and(|h| {
                    solid[h.tri as usize] && frame.normals[h.tri as usize].dot(d) > 0.0
                })
        })
        .count();
    2 * inside > dirs.len()
}

/// The 26 directions to the corners, edges and faces of a cube, +Z first.
fn directions() -> Vec<Vec3> {
    let mut d = vec![Vec3::Z];
    for i in -1..=1 {
        for j in -1..=1 {
            for k in -1..=1 {
                let v = Vec3::new(i as f32, j as f32, k as f32);
                if v != Vec3::ZERO && v != Vec3::Z {
                    d.push(v.normalize());
                }
            }
        }
    }
    d
}

fn look_from(eye: Vec3, target: Vec3) -> Camera {
    let fwd = (target - eye).normalize();
    let up = if fwd.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    Camera::look_at(eye, target, up, YFOV)
}

/// Points spread over the surfaces by area, with the light they receive.
fn lit_points(frame: &Frame, tracer: &Tracer) -> Vec<Lit> {
    let mut r = crate::math::rng(&[0xf4a3e]);
    let mut cdf = Vec::with_capacity(frame.areas.len());
    let mut acc = 0.0f64;
    for &a in &frame.areas {
        acc += a as f64;
        cdf.push(acc);
    }
    let samples = frame.emitter_samples(7, LIGHT_SAMPLES);
    (0..POINTS)
        .filter_map(|_| {
            let u = r.random::<f64>() * acc;
            let tri = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
            let b = crate::math::triangle_barycentrics(Vec2::new(r.random(), r.random()));
            let x = frame.point(tri, b.x, b.y);
            let single = tracer.single_sided(tri as u32);
            irradiance(frame.normals[tri], x, &samples, tracer, single).map(|(n, e)| Lit {
                x,
                n,
                e,
                tri: tri as u32,
            })
        })
        .collect()
}

/// The light at `x` on whichever side of the surface gets more (the front only where the
/// surface is single-sided: nothing sees its back), with that side's normal, or None if unlit.
fn irradiance(
    n: Vec3,
    x: Vec3,
    samples: &[super::EmitterSample],
    tracer: &Tracer,
    single_sided: bool,
) -> Option<(Vec3, f32)> {
    let mut side = [0.0f32; 2];
    let sides: &[Vec3] = if single_sided { &[n] } else { &[n, -n] };
    for s in samples {
        for (k, &nk) in sides.iter().enumerate() {
            if let Some((e, y, ny)) = s.irradiance_at(x, nk) {
                if !tracer.occluded(x, nk, y, ny) {
                    side[k] += crate::math::luminance(e);
                }
            }
        }
    }
    let (e, n) = if side[0] >= side[1] {
        (side[0], n)
    } else {
        (side[1], -n)
    };
    (e > 0.0 && e.is_finite()).then_some((n, e))
}

/// The light of the lit points that `cam` sees (in its view, facing it, not occluded), each
/// weighted by the cosine it is seen at: the points stand for equal areas of surface, whose
/// image shrinks with that cosine, so a flat board seen edge-on (both of its faces lit by a
/// sky, each facing the eye by a hair) scores next to nothing. And how many distinct
/// triangles those points lie on.
fn score(cam: &Camera, lit: &[Lit], tracer: &Tracer) -> (f32, usize) {
    let half = YFOV * 0.5;
    let mut tris = Vec::new();
    let light = lit
        .iter()
        .filter_map(|l| {
            let v = (cam.position - l.x).normalize();
            let cos = l.n.dot(v);
            (cos > 0.0
                && cam.forward.dot(-v).clamp(-1.0, 1.0).acos() < half
                // Traced from the eye, the receiver (single-sided surfaces are seen from the
                // front only: docs/math.md).
                && !tracer.occluded(cam.position, Vec3::ZERO, l.x, l.n))
            .then(|| {
                tris.push(l.tri);
                l.e * cos
            })
        })
        .sum();
    tris.sort_unstable();
    tris.dedup();
    (light, tris.len())
}
