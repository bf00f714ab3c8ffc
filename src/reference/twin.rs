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

impl SurfacePoint {
    /// Where a ray along `d` hits (`h`), on the side of the triangle the ray meets.
    pub fn seen(frame: &Frame, h: &crate::trace::Hit, d: Vec3) -> SurfacePoint {
        let ng = frame.normals[h.tri as usize];
        SurfacePoint {
            x: frame.point(h.tri as usize, h.b1, h.b2),
            n: if ng.dot(d) < 0.0 { ng } else { -ng },
            tri: h.tri,
            b: Vec2::new(h.b1, h.b2),
        }
    }
}

/// The mean luminance of `img` over the pixels whose centre sees a surface (`points` from
/// [`pixel_points`]); 0 when none does.
pub fn mean_over_surfaces(img: &Hdr, points: &[Option<SurfacePoint>]) -> f32 {
    let (n, sum) = img
        .data
        .iter()
        .zip(points)
        .filter(|(_, p)| p.is_some())
        .fold((0usize, 0.0f32), |(n, s), (c, _)| {
            (n + 1, s + crate::math::luminance(*c))
        });
    sum / n.max(1) as f32
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
                .map(|h| SurfacePoint::seen(frame, &h, d))
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
    clamp: f32,
) -> Hdr {
    image(width, height, |i| {
        let Some(s) = points[i] else {
            return Vec3::ZERO;
        };
        let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y);
        vpls.iter()
            .map(|v| {
                let c = v.radiance_at(s.x, s.n, rho, clamp);
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

/// How noisy an estimate of the direct light with N area samples is over what the camera
/// sees, for each N of `counts`: at the surface points `points`, the variance of the
/// N-sample estimator of
/// the light the area emitters reflect there (luminance of irradiance times albedo, exact
/// visibility; punctual lights' samples are exact and count only in the mean), summed over the points, over the sum of the squared
/// mean irradiance: the expected relative squared error of a direct image of N samples.
/// `samples` must be one call of [`Frame::emitter_samples`], whose m area samples are
/// stratified in the emitter pick: for N samples, stratum g holds the consecutive samples
/// from floor(g m / N) on, and the variance within it is that stratum's (so the estimate
/// follows the stratification the renderer's N samples get, not independent draws). Each
/// stratum needs two samples or more: m >= 2N (a count with fewer gives no variance).
pub fn direct_relative_error(
    frame: &Frame,
    tracer: &Tracer,
    points: &[Option<SurfacePoint>],
    samples: &[EmitterSample],
    counts: &[u32],
) -> Vec<f32> {
    let lum = |l: &EmitterSample, s: &SurfacePoint, rho: Vec3| match l.irradiance_at(s.x, s.n) {
        Some((e, y, ny)) if !tracer.occluded(s.x, s.n, y, ny) => {
            crate::math::luminance(e * rho) as f64
        }
        _ => 0.0,
    };
    let area: Vec<&EmitterSample> = samples.iter().filter(|l| l.kind.is_sampled()).collect();
    let m = area.len();
    let zero = || (vec![0.0f64; counts.len()], 0.0f64);
    let (var, mean2) = points
        .par_iter()
        .flatten()
        .map(|s| {
            let rho = frame.albedo_at(s.tri as usize, s.b.x, s.b.y);
            let exact: f64 = samples
                .iter()
                .filter(|l| !l.kind.is_sampled())
                .map(|l| lum(l, s, rho))
                .sum();
            // Each area sample's one-sample estimate of the area emitters' reflected light.
            let v: Vec<f64> = area.iter().map(|l| lum(l, s, rho) * m as f64).collect();
            let mean = if m > 0 {
                v.iter().sum::<f64>() / m as f64
            } else {
                0.0
            };
            let var = counts
                .iter()
                .map(|&n| {
                    let n = n.max(1) as usize;
                    // Stratum g of N holds the samples j with j * N / m = g.
                    (0..n)
                        .map(|g| {
                            let run = &v[g * m / n..((g + 1) * m / n).max(g * m / n)];
                            if run.len() < 2 {
                                return 0.0;
                            }
                            let k = run.len() as f64;
                            let mu = run.iter().sum::<f64>() / k;
                            run.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (k - 1.0)
                        })
                        .sum::<f64>()
                        / (n * n) as f64
                })
                .collect();
            (var, (mean + exact).powi(2))
        })
        .reduce(zero, |mut a, b| {
            a.0.iter_mut().zip(&b.0).for_each(|(x, y)| *x += y);
            (a.0, a.1 + b.1)
        });
    var.iter()
        .map(|&v| if mean2 > 0.0 { (v / mean2) as f32 } else { 0.0 })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// `direct_relative_error` is what it claims: the relative squared error of an N-sample
    /// direct image against a 4096-sample one, measured with the twin's own direct light
    /// (exact visibility) over 24 seeds, independently of the statistic's code path: 1.01x,
    /// 1.06x and 1.23x measured (the atrium's heavier tail: a few points see the sun at a
    /// grazing angle).
    #[test]
    fn the_direct_error_is_predicted() {
        for (name, n) in [("cornell", 8), ("cornell-light", 8), ("atrium", 8)] {
            let scene = builtin::load(name).unwrap().unwrap();
            let f = scene.at(0.0);
            let tr = Tracer::new(&f);
            let (w, h) = (24, 24);
            let points = pixel_points(&f, &tr, w, h);
            let samples = f.emitter_samples(99, 256);
            let predicted = direct_relative_error(&f, &tr, &points, &samples, &[n])[0] as f64;
            let truth = direct(&f, &tr, &points, w, h, &f.emitter_samples(7, 4096));
            let lum = crate::math::luminance;
            let t2: f64 = truth.data.iter().map(|&c| (lum(c) as f64).powi(2)).sum();
            let seeds = 24;
            let err: f64 = (0..seeds)
                .map(|s| {
                    let img = direct(
                        &f,
                        &tr,
                        &points,
                        w,
                        h,
                        &f.emitter_samples(1000 + s, n as usize),
                    );
                    img.data
                        .iter()
                        .zip(&truth.data)
                        .map(|(&a, &b)| ((lum(a) - lum(b)) as f64).powi(2))
                        .sum::<f64>()
                        / t2
                })
                .sum::<f64>()
                / seeds as f64;
            let ratio = err / predicted;
            println!(
                "{name}: {n} samples: error {err:.5}, predicted {predicted:.5}, ratio {ratio:.3}"
            );
            assert!(
                (0.75..=1.33).contains(&ratio),
                "{name}: measured {err} against {predicted} predicted"
            );
        }
    }
}
