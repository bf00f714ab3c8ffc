//! Motion-compensated (warped) flicker: the previous frame's error reprojected to each pixel
//! with the scene's exact motion. Each pixel centre's primary ray is cast on the CPU in both
//! frames; the surface point a pixel sees at t (triangle and barycentrics, which name the same
//! surface point in every frame) is placed where the triangle was at t-1 and projected with
//! the camera at t-1. The pixel of t-1 that holds that position must see the same surface
//! there (the same triangle, or a point of the same plane within 1.5 pixel footprints), else
//! the point was hidden (disoccluded) at t-1 or off screen, and the pixel is left out.
//! Pixels that see nothing (the background, at infinity) are reprojected by direction.
//! The previous error is read bilinearly between those of the four pixel centres around the
//! reprojected position that see the same surface (weights renormalized), so an error that
//! varies smoothly over a surface warps to second order and edges never blend two surfaces.

use super::error_image;
use crate::image::Hdr;
use crate::scene::Frame;
use crate::trace::Tracer;
use anyhow::{bail, Result};
use glam::Vec2;
use rayon::prelude::*;
use serde::Serialize;

/// What a pixel centre sees: a triangle and its barycentrics, or nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelHit {
    pub tri: u32,
    pub b1: f32,
    pub b2: f32,
}

/// The primary hit of every pixel centre, row 0 at the top.
pub fn pixel_hits(
    frame: &Frame,
    tracer: &Tracer,
    width: u32,
    height: u32,
) -> Vec<Option<PixelHit>> {
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            let p = Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            let d = frame.camera.ray_dir(p, width, height);
            tracer
                .intersect(frame.camera.position, d, f32::INFINITY)
                .map(|h| PixelHit {
                    tri: h.tri,
                    b1: h.b1,
                    b2: h.b2,
                })
        })
        .collect()
}

/// For each pixel of frame `cur`, where the surface it sees was in frame `prev`'s image
/// and which pixels around that position see it too, or None when it was off screen or
/// hidden.
pub fn reproject(
    prev: (&Frame, &[Option<PixelHit>]),
    cur: (&Frame, &[Option<PixelHit>]),
    width: u32,
    height: u32,
) -> Vec<Option<Warp>> {
    let (pf, ph) = prev;
    let (cf, ch) = cur;
    let tan = (pf.camera.yfov * 0.5).tan();
    (0..(width * height) as usize)
        .into_par_iter()
        .map(|i| {
            let q = match ch[i] {
                Some(h) => {
                    let x = pf.point(h.tri as usize, h.b1, h.b2);
                    pf.camera.project(x, width, height)?
                }
                None => {
                    let p = Vec2::new(
                        (i as u32 % width) as f32 + 0.5,
                        (i as u32 / width) as f32 + 0.5,
                    );
                    pf.camera
                        .project_dir(cf.camera.ray_dir(p, width, height), width, height)?
                }
            };
            if q.x < 0.0 || q.y < 0.0 || q.x >= width as f32 || q.y >= height as f32 {
                return None;
            }
            // Whether pixel k of t-1 sees the surface pixel i sees at t.
            let same = |k: usize| match (ch[i], ph[k]) {
                (None, None) => true,
                (Some(a), Some(b)) if a.tri == b.tri => true,
                (Some(a), Some(b)) => {
                    // A neighbouring triangle of the same plane (a wall of two triangles).
                    let (xa, xb) = (
                        pf.point(a.tri as usize, a.b1, a.b2),
                        pf.point(b.tri as usize, b.b1, b.b2),
                    );
                    let na = pf.normals[a.tri as usize];
                    let footprint = (xa - pf.camera.position).dot(pf.camera.forward) * 2.0 * tan
                        / height as f32;
                    na.dot(pf.normals[b.tri as usize]) > 0.999
                        && (xa - xb).length() < 1.5 * footprint
                        && (xa - xb).dot(na).abs() < 0.01 * footprint
                }
                _ => false,
            };
            let (x, y) = (q.x as u32, q.y as u32);
            if !same((y * width + x) as usize) {
                return None;
            }
            // A still view reprojects to the pixel centres, up to rounding: read them as
            // they are.
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let q = if (q - centre).abs().max_element() < 1e-3 {
                centre
            } else {
                q
            };
            // Which of the four pixel centres around q see the same surface.
            let (x0, y0) = ((q.x - 0.5).floor() as i64, (q.y - 0.5).floor() as i64);
            let mut around = [false; 4];
            for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let (xk, yk) = (x0 + dx, y0 + dy);
                around[k] = xk >= 0
                    && yk >= 0
                    && xk < width as i64
                    && yk < height as i64
                    && same((yk * width as i64 + xk) as usize);
            }
            Some(Warp { q, around })
        })
        .collect()
}

/// Where a pixel's surface was in the previous frame's image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warp {
    /// Continuous pixel position (pixel centres at k + 0.5, x right, y down).
    pub q: Vec2,
    /// Which of the four pixel centres around `q` (x0y0, x1y0, x0y1, x1y1, with
    /// x0 = floor(q.x - 0.5)) see the same surface; the pixel holding `q` always does.
    pub around: [bool; 4],
}

impl Warp {
    /// `e` (row-major, `width` wide) at `q`: bilinear between the centres around it that see
    /// the same surface (weights renormalized; edges never blend two surfaces), written as
    /// the nearest pixel's value plus weighted differences so that it is exactly that value
    /// where the four agree and at a pixel centre.
    pub fn read(&self, e: &[f64], width: u32) -> f64 {
        let w = width as i64;
        let q = self.q;
        let near = e[(q.y as i64 * w + q.x as i64) as usize];
        let (x, y) = (q.x as f64 - 0.5, q.y as f64 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let weights = [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ];
        let (mut sum, mut total) = (0.0, 0.0);
        for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
            if self.around[k] && weights[k] > 0.0 {
                let i = ((y0 as i64 + dy) * w + x0 as i64 + dx) as usize;
                sum += weights[k] * (e[i] - near);
                total += weights[k];
            }
        }
        if total > 0.0 {
            near + sum / total
        } else {
            near
        }
    }
}

/// Warped flicker of a sequence.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WarpedFlicker {
    /// Mean over frame pairs of `mean_p |e_t(p) - e_(t-1)(warp(p))|` over the pixels kept.
    pub f1: f64,
    /// Fraction of pixels kept (not disoccluded or off screen), over all frame pairs.
    pub kept: f64,
    /// Per frame pair (frames 1..): F1 and the fraction kept.
    pub frames: Vec<(f64, f64)>,
}

/// Per-pixel flicker of every frame pair (frames 1..): `|e_t(p) - e_(t-1)(warp(p))|` with the
/// previous error read at the reprojected position ([`Warp::read`]), the quantity whose mean
/// over the kept pixels is a frame's warped F1; None where the warp left the pixel out
/// (hidden or off screen at t-1). For a still camera and still objects the warp reads the
/// same pixel, and this is the plain per-pixel flicker `|e_t(p) - e_(t-1)(p)|`. `motion` is
/// as for [`warped_f1`].
pub fn flicker_maps(
    test: &[Hdr],
    reference: &[Hdr],
    motion: &[Vec<Option<Warp>>],
) -> Result<Vec<Vec<Option<f64>>>> {
    if test.len() != reference.len() || test.len() != motion.len() || test.is_empty() {
        bail!(
            "sequences differ in length: {} test frames, {} reference frames, {} motion fields",
            test.len(),
            reference.len(),
            motion.len()
        );
    }
    let (w, h) = (test[0].width, test[0].height);
    let mut maps = Vec::new();
    let mut prev: Option<Vec<f64>> = None;
    for ((t, r), m) in test.iter().zip(reference).zip(motion) {
        if (t.width, t.height) != (w, h)
            || (r.width, r.height) != (w, h)
            || m.len() != (w * h) as usize
        {
            bail!(
                "frame sizes differ: {}x{}, reference {}x{}, motion {} pixels against {w}x{h}",
                t.width,
                t.height,
                r.width,
                r.height,
                m.len()
            );
        }
        let e = error_image(t, r);
        if let Some(p) = &prev {
            maps.push(
                m.iter()
                    .enumerate()
                    .map(|(i, q)| q.map(|q| (e[i] - q.read(p, w)).abs()))
                    .collect(),
            );
        }
        prev = Some(e);
    }
    Ok(maps)
}

/// Warped F1 of `test` against `reference` given each frame's reprojection (`motion[t]` for
/// t >= 1, from [`reproject`]; `motion[0]` is not used): the mean of [`flicker_maps`] over
/// the kept pixels of each frame pair.
pub fn warped_f1(
    test: &[Hdr],
    reference: &[Hdr],
    motion: &[Vec<Option<Warp>>],
) -> Result<WarpedFlicker> {
    Ok(summarize(&flicker_maps(test, reference, motion)?))
}

/// Warped F1 from per-pixel flicker maps (see [`flicker_maps`]).
pub fn summarize(maps: &[Vec<Option<f64>>]) -> WarpedFlicker {
    let mut out = WarpedFlicker::default();
    let (mut kept_all, mut total) = (0usize, 0usize);
    for m in maps {
        let (mut sum, mut kept) = (0.0, 0usize);
        for v in m.iter().flatten() {
            sum += v;
            kept += 1;
        }
        out.frames
            .push((sum / kept.max(1) as f64, kept as f64 / m.len() as f64));
        kept_all += kept;
        total += m.len();
    }
    if !out.frames.is_empty() {
        out.f1 = out.frames.iter().map(|f| f.0).sum::<f64>() / out.frames.len() as f64;
        out.kept = kept_all as f64 / total.max(1) as f64;
    }
    out
}

/// The reprojection of every frame of `frames` (frame t from t-1) at `width` x `height`.
pub fn motion(frames: &[Frame], width: u32, height: u32) -> Vec<Vec<Option<Warp>>> {
    let hits: Vec<Vec<Option<PixelHit>>> = frames
        .iter()
        .map(|f| pixel_hits(f, &Tracer::new(f), width, height))
        .collect();
    (0..frames.len())
        .map(|t| {
            if t == 0 {
                vec![None; (width * height) as usize]
            } else {
                reproject(
                    (&frames[t - 1], &hits[t - 1]),
                    (&frames[t], &hits[t]),
                    width,
                    height,
                )
            }
        })
        .collect()
}

/// Warped F1 of frames `numbers` (frame f at time f / fps) of `scene`.
pub fn for_scene(
    scene: &crate::scene::Scene,
    fps: f32,
    numbers: &[u32],
    test: &[Hdr],
    reference: &[Hdr],
) -> Result<WarpedFlicker> {
    crate::check::float("`fps`", fps, 0.0, true, 1000.0)?;
    if numbers.windows(2).any(|w| w[1] != w[0] + 1) {
        bail!("warped flicker needs consecutive frame numbers");
    }
    let Some(first) = test.first() else {
        bail!("no frames");
    };
    let frames: Vec<Frame> = numbers.iter().map(|&f| scene.at(f as f32 / fps)).collect();
    warped_f1(test, reference, &motion(&frames, first.width, first.height))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use glam::Vec3;

    const W: u32 = 64;
    const H: u32 = 64;

    /// An error pattern fixed to the surfaces: one value per plane of frame 0's geometry (a
    /// wall's two triangles share it), looked up through each pixel's triangle, so it moves
    /// with the camera and with the objects.
    fn surface_pattern(frames: &[Frame]) -> (Vec<Hdr>, Vec<Hdr>) {
        let f0 = &frames[0];
        let value = |tri: usize| {
            let n = f0.normals[tri];
            let d = n.dot(f0.tris[tri][0]);
            let k = (n * 7.0).round().dot(Vec3::new(1.0, 13.0, 171.0)) + (d * 50.0).round() * 0.37;
            0.1 + 0.05 * (k * 0.731).sin()
        };
        let mut test = Vec::new();
        let mut reference = Vec::new();
        for f in frames {
            let hits = pixel_hits(f, &Tracer::new(f), W, H);
            let data: Vec<Vec3> = hits
                .iter()
                .map(|h| Vec3::splat(h.map_or(0.0, |h| value(h.tri as usize))))
                .collect();
            test.push(Hdr {
                width: W,
                height: H,
                data,
            });
            reference.push(Hdr {
                width: W,
                height: H,
                data: vec![Vec3::ZERO; (W * H) as usize],
            });
        }
        (test, reference)
    }

    fn frames(name: &str, times: &[f32]) -> Vec<Frame> {
        let scene = builtin::load(name).unwrap().unwrap();
        times.iter().map(|&t| scene.at(t)).collect()
    }

    #[test]
    fn warped_f1_is_zero_for_errors_fixed_to_surfaces() {
        // Measured: orbit kept 0.946, plain F1 0.00166; box kept 0.994, plain F1 0.00014.
        for (name, kept, min_plain) in [
            ("cornell-orbit", 0.90..0.99, 1.1e-3),
            ("cornell-box", 0.98..1.0, 1e-4),
        ] {
            let fr = frames(name, &[0.0, 1.0 / 24.0, 2.0 / 24.0]);
            let (test, reference) = surface_pattern(&fr);
            let m = motion(&fr, W, H);
            let warped = warped_f1(&test, &reference, &m).unwrap();
            let plain = crate::metrics::sequence(&[0, 1, 2], &test, &reference).unwrap();
            println!(
                "{name}: warped {} (kept {}), plain {}",
                warped.f1, warped.kept, plain.flicker_f1
            );
            assert_eq!(warped.f1, 0.0, "{name}");
            assert!(kept.contains(&warped.kept), "{name}: kept {}", warped.kept);
            // The plain F1 sees the pattern move.
            assert!(
                plain.flicker_f1 > min_plain,
                "{name}: plain {}",
                plain.flicker_f1
            );
        }
    }

    /// An error that varies smoothly over the surfaces (a function of frame 0's surface
    /// point) warps to second order: reading the previous error bilinearly (between the
    /// centres on the same surface) leaves a small fraction of what reading the nearest pixel
    /// does, which sees the pattern shift by up to half a pixel.
    #[test]
    fn smooth_errors_fixed_to_surfaces_warp_to_almost_nothing() {
        for name in ["cornell-orbit", "cornell-box"] {
            let fr = frames(name, &[0.0, 1.0 / 24.0, 2.0 / 24.0]);
            let f0 = &fr[0];
            let (lo, hi) = f0.bounds();
            let value = |h: PixelHit| {
                // About a third of a period across the box.
                let u = (f0.point(h.tri as usize, h.b1, h.b2) - lo) / (hi - lo);
                0.1 + 0.05 * (2.0 * u.x).sin() + 0.05 * (2.0 * u.y + 1.5 * u.z).cos()
            };
            let mut test = Vec::new();
            for f in &fr {
                let hits = pixel_hits(f, &Tracer::new(f), W, H);
                let data = hits
                    .iter()
                    .map(|h| Vec3::splat(h.map_or(0.0, value)))
                    .collect();
                test.push(Hdr {
                    width: W,
                    height: H,
                    data,
                });
            }
            let zero = Hdr {
                width: W,
                height: H,
                data: vec![Vec3::ZERO; (W * H) as usize],
            };
            let reference = vec![zero; 3];
            let m = motion(&fr, W, H);
            let nearest: Vec<Vec<Option<Warp>>> = m
                .iter()
                .map(|f| {
                    f.iter()
                        .map(|q| {
                            q.map(|q| Warp {
                                around: [false; 4],
                                ..q
                            })
                        })
                        .collect()
                })
                .collect();
            let warped = warped_f1(&test, &reference, &m).unwrap().f1;
            let near = warped_f1(&test, &reference, &nearest).unwrap().f1;
            println!("{name}: bilinear {warped:.3e}, nearest {near:.3e}");
            assert!(near > 0.0, "{name}: the pattern did move on screen");
            // Measured: orbit 8.6e-5 against 4.8e-4 (0.18x: what is left is mostly pixels
            // next to an edge, read from fewer centres); box 2.1e-5 against 3.2e-5 (the small
            // moving box is mostly edge pixels at 64x64).
            let bound = if name == "cornell-orbit" { 0.27 } else { 0.95 };
            assert!(warped < bound * near, "{name}: {warped} vs nearest {near}");
        }
    }

    #[test]
    fn warped_f1_equals_plain_f1_for_a_still_camera() {
        let fr = frames("cornell", &[0.0, 0.5, 1.0]);
        let m = motion(&fr, W, H);
        let noise = |s: u64| Hdr {
            width: W,
            height: H,
            data: (0..W * H)
                .map(|i| Vec3::splat(((i as u64 * 2654435761 + s * 97) % 1000) as f32 / 1000.0))
                .collect(),
        };
        let test = vec![noise(1), noise(2), noise(3)];
        let reference = vec![noise(9); 3];
        let warped = warped_f1(&test, &reference, &m).unwrap();
        let plain = crate::metrics::sequence(&[0, 1, 2], &test, &reference).unwrap();
        assert_eq!(warped.kept, 1.0);
        assert!(
            (warped.f1 - plain.flicker_f1).abs() < 1e-12,
            "{} vs {}",
            warped.f1,
            plain.flicker_f1
        );
    }

    /// A camera moved sideways by `dx` in front of the Cornell box's back wall: a pixel that
    /// sees the wall at depth z came from `dx / z * (W / 2) / (tan * aspect)` pixels to the
    /// right (the wall is perpendicular to the view).
    #[test]
    fn warp_matches_an_analytic_reprojection() {
        let f0 = builtin::load("cornell").unwrap().unwrap().at(0.0);
        let dx = 0.05;
        let mut f1 = f0.clone();
        f1.camera.position += f1.camera.right * dx;
        let tracer = Tracer::new(&f0);
        let (h0, h1) = (
            pixel_hits(&f0, &tracer, W, H),
            pixel_hits(&f1, &tracer, W, H),
        );
        let q = reproject((&f0, &h0), (&f1, &h1), W, H);
        let tan = (f0.camera.yfov * 0.5).tan();
        let mut checked = 0;
        for i in 0..(W * H) as usize {
            let Some(h) = h1[i] else { continue };
            let n = f0.normals[h.tri as usize];
            if n.dot(f0.camera.forward).abs() < 0.9999 {
                continue;
            }
            let p = Vec2::new((i as u32 % W) as f32 + 0.5, (i as u32 / W) as f32 + 0.5);
            let z =
                (f0.point(h.tri as usize, h.b1, h.b2) - f1.camera.position).dot(f1.camera.forward);
            let expect = p + Vec2::new(dx / z * (W as f32 / 2.0) / tan, 0.0);
            if let Some(q) = q[i] {
                assert!(
                    (q.q - expect).length() < 1e-3,
                    "pixel {i}: {} vs {expect}",
                    q.q
                );
                checked += 1;
            }
        }
        assert!(checked > 500, "{checked} back-wall pixels");
    }
}
