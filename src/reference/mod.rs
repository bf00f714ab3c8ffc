//! The reference: a CPU path tracer with next-event estimation and multiple importance
//! sampling (power heuristic) on the emitter triangles, next-event estimation alone on the
//! punctual lights (all of them at each vertex, or one picked by power when there are many: a
//! delta light cannot be hit by a scattered ray, so it needs no MIS weight), next-event
//! estimation with MIS on the environment (a direction from its distribution, weighed by the
//! power heuristic against the cosine-sampled ray that misses the geometry; a camera ray that
//! misses sees it), Russian roulette, rayon across rows.
//! It is the ground truth every metric is held to.

pub mod twin;

use crate::image::Hdr;
use crate::math::{cosine_hemisphere, rng, triangle_barycentrics};
use crate::scene::Frame;
use crate::trace::{Next, PathRay, Tracer};
use glam::{Vec2, Vec3};
use rand::Rng;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Up to this many punctual lights, every path vertex takes all of them (a shadow ray each).
const ALL_LIGHTS: usize = 8;

/// The most samples per pixel a reference may take.
pub const MAX_SPP: u32 = 1 << 20;
/// The widest and tallest reference image.
pub const MAX_SIZE: u32 = 16384;
/// The latest bounce [`ReferenceSettings::rr_cap_depth`] may be (a path in a closed albedo-1
/// room goes on at weight 1 until it).
pub const MAX_RR_CAP_DEPTH: u32 = 1 << 16;

/// Parameters of one reference image.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    /// The bounce from which Russian roulette's survival probability is capped at
    /// [`ROULETTE_CAP`] ([`RR_CAP_DEPTH`] by default, as Mitsuba 3's path tracer does from its
    /// `rr_depth`). Before it, from bounce [`RR_DEPTH`] on, a path survives with its weight's
    /// largest component (at most 1), so between surfaces of albedo 1 it goes on at weight 1
    /// instead of 1 / 0.95 more each bounce. Light caught in a 1 cm gap between two white
    /// surfaces leaves after 35 bounces (median; 97% within 256, `benches/gap_escape.py`):
    /// with the cap from bounce 3 it arrives on the few paths that survive, weighted up to
    /// thousands-fold (two 8192-spp references of tests/gpu/thin_gap.rs's 1 cm box differ by
    /// relMSE 0.89), with the cap from 256 on the paths that carry it at weight 1 (0.14).
    /// Both are unbiased; docs/math.md, "Light that cannot get out", has why the default stays.
    pub rr_cap_depth: u32,
}

/// How a reference traces each pixel: samples a pixel, and the bounce from which its roulette
/// is capped ([`ReferenceSettings::rr_cap_depth`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    pub spp: u32,
    pub rr_cap_depth: u32,
}

impl Sampling {
    /// `spp` samples a pixel, the cap from the default bounce (what `irad compare` traces).
    pub fn spp(spp: u32) -> Self {
        Sampling {
            spp,
            rr_cap_depth: RR_CAP_DEPTH,
        }
    }
}

/// The first bounce after which a reference path may end by Russian roulette.
pub const RR_DEPTH: u32 = 3;
/// [`ReferenceSettings::rr_cap_depth`]'s default: the cap from the first bounce roulette acts on.
pub const RR_CAP_DEPTH: u32 = RR_DEPTH;
/// The highest survival probability from [`ReferenceSettings::rr_cap_depth`] on (Mitsuba 3's).
pub const ROULETTE_CAP: f32 = 0.95;

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            width: 256,
            height: 256,
            spp: 256,
            seed: 1,
            rr_cap_depth: RR_CAP_DEPTH,
        }
    }
}

impl ReferenceSettings {
    /// Checks the settings, naming the one that is wrong.
    pub fn validate(&self) -> anyhow::Result<()> {
        crate::check::int("`size`", self.width, 1, MAX_SIZE)?;
        crate::check::int("`size`", self.height, 1, MAX_SIZE)?;
        crate::check::int("`spp`", self.spp, 1, MAX_SPP)?;
        crate::check::int(
            "`rr_cap_depth`",
            self.rr_cap_depth,
            RR_DEPTH,
            MAX_RR_CAP_DEPTH,
        )
    }
}

/// Renders one frame. Each pixel is the box-filtered mean radiance over its
/// area; `on_row` is called once per finished row (for progress bars).
pub fn render(
    frame: &Frame,
    tracer: &Tracer,
    s: &ReferenceSettings,
    on_row: &(dyn Fn() + Sync),
) -> Hdr {
    let mut img = Hdr::new(s.width, s.height);
    img.data
        .par_chunks_mut(s.width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                // The same stream for a pixel in every frame: still scenes give still images,
                // and the reference's own noise does not count as flicker.
                let mut r = rng(&[s.seed, (y as u64) << 32 | x as u64, 0x7ef]);
                let mut sum = Vec3::ZERO;
                for _ in 0..s.spp {
                    let p = Vec2::new(x as f32 + r.random::<f32>(), y as f32 + r.random::<f32>());
                    let dir = frame.camera.ray_dir(p, s.width, s.height);
                    sum += radiance_capped_from(
                        frame,
                        tracer,
                        frame.camera.position,
                        dir,
                        s.rr_cap_depth,
                        &mut r,
                    );
                }
                *px = sum / s.spp as f32;
            }
            on_row();
        });
    img
}

/// Solid-angle pdf of sampling point `y` on emitter triangle `tri` from a point at squared
/// distance `d2` with cosine `cos_l` at the emitter. 0 for a triangle next-event estimation
/// never samples: one that emits at some points but not on average (an emissive texture
/// black at every point its mean is taken at), so that it is not in the emitter list; light
/// reaching it by a scattered ray then carries the whole weight.
fn light_pdf(frame: &Frame, tri: usize, d2: f32, cos_l: f32) -> f32 {
    match frame.emitter_of_tri.get(tri) {
        Some(&e) if e != u32::MAX && frame.areas[tri] > 0.0 && cos_l > 0.0 => {
            frame.emitters.prob(e as usize) / frame.areas[tri] * d2 / cos_l
        }
        _ => 0.0,
    }
}

/// The power heuristic's weight of the strategy with pdf `a` against the one with pdf `b`:
/// 0 when neither could have made the sample (or a pdf is not finite), never NaN.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let w = a * a / (a * a + b * b);
    if w.is_finite() {
        w
    } else {
        0.0
    }
}

/// Radiance arriving at `origin` from direction `dir` (unit), with Russian roulette capped
/// from the default bounce ([`RR_CAP_DEPTH`]).
pub fn radiance(frame: &Frame, tracer: &Tracer, origin: Vec3, dir: Vec3, r: &mut impl Rng) -> Vec3 {
    radiance_capped_from(frame, tracer, origin, dir, RR_CAP_DEPTH, r)
}

/// [`radiance`] with roulette's survival probability capped at [`ROULETTE_CAP`] from bounce
/// `cap_depth` on ([`ReferenceSettings::rr_cap_depth`]).
pub fn radiance_capped_from(
    frame: &Frame,
    tracer: &Tracer,
    origin: Vec3,
    dir: Vec3,
    cap_depth: u32,
    r: &mut impl Rng,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut ray = PathRay::free(origin, dir);
    let mut pdf_bsdf = 0.0f32; // pdf of the direction that reached this vertex (0: camera ray)
    let mut depth = 0u32;
    let env = frame.emitters.environment.as_deref();
    loop {
        let d = ray.dir;
        let h = match tracer.follow(&ray, f32::INFINITY) {
            Next::Hit(h) => h,
            // Into a gap thinner than the tracer resolves: its light does not come back.
            Next::Sealed => break,
            Next::Miss => {
                // Out to the environment: all of it for a camera ray, else its MIS weight
                // against the environment's own sampling.
                if let Some(env) = env {
                    let le = env.radiance(d);
                    l += beta
                        * le
                        * if pdf_bsdf == 0.0 {
                            1.0
                        } else {
                            power_heuristic(pdf_bsdf, env.pdf(d))
                        };
                }
                break;
            }
        };
        let tri = h.tri as usize;
        let x = frame.point(tri, h.b1, h.b2);
        let ng = frame.normals[tri];
        let front = ng.dot(d) < 0.0;
        let n = if front { ng } else { -ng };
        let le = frame.emission_at(tri, h.b1, h.b2);
        if front && le.max_element() > 0.0 {
            if pdf_bsdf == 0.0 {
                l += beta * le;
            } else {
                let cos_l = -ng.dot(d);
                let pl = light_pdf(frame, tri, h.t * h.t, cos_l);
                l += beta * le * power_heuristic(pdf_bsdf, pl);
            }
        }
        let rho = frame.albedo_at(tri, h.b1, h.b2);
        if rho.max_element() <= 0.0 {
            break;
        }
        // Next-event estimation: one point on an emitter chosen by power.
        let em = &frame.emitters;
        if !em.tris.is_empty() {
            let (e, _) = em.pick(r.random());
            let lt = em.tris[e] as usize;
            let b = triangle_barycentrics(Vec2::new(r.random(), r.random()));
            let y = frame.point(lt, b.x, b.y);
            let w = y - x;
            let d2 = w.length_squared();
            let wn = w / d2.sqrt();
            let cos_x = n.dot(wn);
            let cos_l = -frame.normals[lt].dot(wn);
            let pl = light_pdf(frame, lt, d2, cos_l);
            if cos_x > 0.0 && pl > 0.0 && !tracer.occluded(x, n, y, frame.normals[lt]) {
                let mis = power_heuristic(pl, cos_x / PI);
                l += beta * rho / PI * frame.emission_at(lt, b.x, b.y) * (cos_x / pl * mis);
            }
        }
        // Next-event estimation on the punctual lights: each of them when there are at most
        // ALL_LIGHTS, else one chosen by power (weight 1 / p).
        let punctual = |i: usize, w: f32| match em.lights[i].irradiance_at(x, n, em.far()) {
            Some((e, y)) if !tracer.occluded(x, n, y, Vec3::ZERO) => beta * rho / PI * e * w,
            _ => Vec3::ZERO,
        };
        if em.lights.len() <= ALL_LIGHTS {
            l += (0..em.lights.len()).map(|i| punctual(i, 1.0)).sum::<Vec3>();
        } else {
            let (i, p) = em.pick_light(r.random());
            l += punctual(i, 1.0 / p);
        }
        // Next-event estimation on the environment: a direction from its distribution, with
        // a shadow ray to past the sphere around the geometry.
        if let Some(env) = env {
            let (wi, le, pe) = env.sample(Vec2::new(r.random(), r.random()));
            let cos_x = n.dot(wi);
            if cos_x > 0.0 && pe > 0.0 && !tracer.occluded(x, n, x + wi * em.far(), Vec3::ZERO) {
                let mis = power_heuristic(pe, cos_x / PI);
                l += beta * rho / PI * le * (cos_x / pe * mis);
            }
        }
        // Continue by cosine sampling: f cos / pdf = rho.
        let d = cosine_hemisphere(n, Vec2::new(r.random(), r.random()));
        pdf_bsdf = n.dot(d).max(1e-8) / PI;
        ray = tracer.leave(x, n, d);
        beta *= rho;
        depth += 1;
        if depth >= RR_DEPTH {
            let cap = if depth >= cap_depth {
                ROULETTE_CAP
            } else {
                1.0
            };
            let q = beta.max_element().min(cap);
            if r.random::<f32>() >= q {
                break;
            }
            beta /= q;
        }
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    #[test]
    fn settings_are_checked_naming_the_setting() {
        assert!(ReferenceSettings::default().validate().is_ok());
        let err = |s: ReferenceSettings| s.validate().unwrap_err().to_string();
        let d = ReferenceSettings::default();
        assert_eq!(
            err(ReferenceSettings { spp: 0, ..d }),
            "`spp` 0 is out of range: it must be 1 to 1048576"
        );
        assert!(err(ReferenceSettings {
            spp: MAX_SPP + 1,
            ..d
        })
        .starts_with("`spp` 1048577"));
        assert!(err(ReferenceSettings { width: 0, ..d }).starts_with("`size` 0 is out of range"));
        assert!(err(ReferenceSettings {
            height: MAX_SIZE + 1,
            ..d
        })
        .starts_with("`size` 16385"));
        assert_eq!(
            err(ReferenceSettings {
                rr_cap_depth: RR_DEPTH - 1,
                ..d
            }),
            "`rr_cap_depth` 2 is out of range: it must be 3 to 65536"
        );
    }

    /// A furnace of albedo 0.99 (radiance 1 / (1 - 0.99) = 100, about a hundred bounces a
    /// path): with roulette capped at 0.95 from bounce 3 (the default), a path that lasts `n`
    /// bounces weighs (0.99 / 0.95)^n and the estimate's variance is infinite: most pixels
    /// come out low and a few far too high. Capped from bounce 4096, a path survives each bounce
    /// with 0.99 at weight 1. Measured over 64 pixels of 256 spp: capped from 3, the mean is
    /// 80.0, the pixels' RMS relative error 0.44 and the worst 2.1; capped from 4096, 100.0,
    /// 0.057 and 0.13.
    #[test]
    fn an_albedo_099_furnace_converges_when_the_cap_comes_late() {
        let scene = builtin::load("furnace").unwrap().unwrap();
        let mut f = scene.at(0.0);
        let mut m = (*f.materials).clone();
        for m in &mut m {
            m.albedo = Vec3::splat(0.99);
        }
        f.materials = std::sync::Arc::new(m);
        let tr = Tracer::new(&f);
        let spread = |rr_cap_depth: u32| {
            let s = ReferenceSettings {
                width: 8,
                height: 8,
                spp: 256,
                seed: 1,
                rr_cap_depth,
            };
            let img = render(&f, &tr, &s, &|| {});
            let rel: Vec<f32> = img.data.iter().map(|p| p.x / 100.0 - 1.0).collect();
            let rms = (rel.iter().map(|e| e * e).sum::<f32>() / rel.len() as f32).sqrt();
            let worst = rel.iter().fold(0.0f32, |a, e| a.max(e.abs()));
            println!(
                "cap from {rr_cap_depth}: mean {}, rms {rms}, worst {worst}",
                img.mean().x
            );
            (img.mean().x, rms, worst)
        };
        let (mean, rms, worst) = spread(MAX_RR_CAP_DEPTH);
        // 64 pixels x 256 paths of about 100 bounces: each pixel's standard error is about 6%.
        assert!((mean / 100.0 - 1.0).abs() < 0.02, "mean {mean}");
        assert!(rms < 0.08 && worst < 0.2, "rms {rms}, worst {worst}");
        let (_, rms3, _) = spread(RR_CAP_DEPTH);
        assert!(rms3 > 4.0 * rms, "capped from bounce 3: rms {rms3}");
    }

    /// White furnace: closed box, albedo 0.5, every wall emits 1: radiance 1/(1-0.5) = 2.
    #[test]
    fn white_furnace_is_two_everywhere() {
        let scene = builtin::load("furnace").unwrap().unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        let s = ReferenceSettings {
            width: 8,
            height: 8,
            spp: 4096,
            seed: 1,
            ..Default::default()
        };
        let img = render(&f, &tr, &s, &|| {});
        let mean = img.mean();
        let worst = img
            .data
            .iter()
            .map(|p| (*p - Vec3::splat(2.0)).abs().max_element() / 2.0)
            .fold(0.0f32, f32::max);
        println!(
            "furnace: mean rel err {}, worst pixel rel err {worst}",
            (mean - Vec3::splat(2.0)).abs().max_element() / 2.0
        );
        // Measured: the mean is off by 0.00061 (relative), the worst pixel by 0.0188.
        assert!(
            (mean - Vec3::splat(2.0)).abs().max_element() < 0.0009 * 2.0,
            "mean {mean}"
        );
        // Every pixel within 2% (4096 spp each: the standard error is about 0.6%).
        for (i, p) in img.data.iter().enumerate() {
            assert!(
                (*p - Vec3::splat(2.0)).abs().max_element() < 0.02 * 2.0,
                "pixel {i}: {p}"
            );
        }
    }

    /// Determinism: the same seed gives a bit-identical image; another seed another one.
    #[test]
    fn same_seed_same_image_other_seed_other_image() {
        let scene = builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        let s = ReferenceSettings {
            width: 8,
            height: 8,
            spp: 4,
            seed: 5,
            ..Default::default()
        };
        let bits = |img: &Hdr| -> Vec<u32> {
            img.data
                .iter()
                .flat_map(|c| c.to_array().map(f32::to_bits))
                .collect()
        };
        let a = render(&f, &tr, &s, &|| {});
        assert_eq!(bits(&a), bits(&render(&f, &tr, &s, &|| {})));
        let other = render(&f, &tr, &ReferenceSettings { seed: 6, ..s }, &|| {});
        let changed = a
            .data
            .iter()
            .zip(&other.data)
            .filter(|(p, q)| p != q)
            .count();
        println!("seed 6 changes {changed} of {} pixels", a.data.len());
        // Measured 63 of 64.
        assert!(changed > 42, "seed 6 changes only {changed} of 64 pixels");
    }
}
