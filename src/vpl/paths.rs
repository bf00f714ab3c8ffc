//! Light paths: an emitter point chosen in proportion to power, a cosine-weighted direction,
//! and Russian roulette on albedo at every bounce. Each vertex after the emitter is a VPL.
//! A path starts on an emitter triangle or at a punctual light in proportion to their
//! luminance power: a point light sends it in a uniform direction, a spot light in a
//! uniform direction within its outer cone (weighted by the falloff), a directional light
//! along its direction from a uniform point of the disk that covers the sphere around the
//! geometry, behind it.
//!
//! A path is a pure function of (seed, path id, the frame's scene): its random numbers come
//! from a stream seeded by (seed, path id) alone, so a path kept by a sampler can be traced
//! again in the next frame and lands where the moved scene sends it.

use crate::math::{basis, cosine_hemisphere, rng, triangle_barycentrics};
use crate::scene::{Frame, LightKind, PunctualLight};
use crate::trace::{Next, PathRay, Tracer};
use glam::{Vec2, Vec3};
use rand::Rng;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Paths stop after this many bounces whatever Russian roulette says: far more than a light
/// path needs in an open room, because light caught between two close white surfaces (a lamp
/// just under the ceiling) takes about a hundred bounces to get out of a 1 cm gap and thousands
/// out of a 1 mm one (98.5% of it within 16384, `benches/gap_escape.py`), and cutting it off
/// darkens the room (0.58 of the reference in tests/gpu/thin_gap.rs at 16; at 1024 the 1 mm
/// gap's room was 25-28% under the true image, docs/math.md, "Out of a 1 mm gap").
pub const MAX_DEPTH: u32 = 16384;

/// From this bounce on, a path in a crevice tosses the crevice coin (`vpl::crevice`, 16 rays)
/// only at every [`THIN`]-th vertex, at the first after a hop longer than the reach and where
/// a ray along the vertex's normal runs a reach free, and leaves no VPL at the others: deep in
/// a 1 mm gap a path bounces thousands of times, and the coin at each bounce cost 17 rays where
/// the bounce now costs two. The VPLs of such a stretch are the compensation's (the crevice's
/// inside), a sixteenth of them kept at their own power: the light they would add inside the
/// gap past this bounce is left out (docs/math.md, "Out of a 1 mm gap"). What a skipped vertex
/// sends out of the crevice is not: a hop out from it leaves a VPL on its way out ([`EXIT`]).
pub const DEEP: u32 = 256;

/// The stride of the coin deep in a crevice ([`DEEP`]).
pub const THIN: u32 = 16;

/// Added to the bounce count of a VPL on a path's way out of a crevice (`Vpl::depth`), so that
/// it and the VPL of the vertex the path reaches have different identities (path, depth).
pub const EXIT: u32 = 1 << 31;

/// A virtual point light: a light-path vertex on a diffuse surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    pub position: Vec3,
    /// Unit surface normal, facing the side the light arrived from.
    pub normal: Vec3,
    pub albedo: Vec3,
    /// Photon power arriving at the vertex (RGB watts) for a one-path estimate; a frame with
    /// N paths scales it by 1/N. The VPL re-emits `power * albedo` with a cosine lobe.
    pub power: Vec3,
    /// Bounce count: 1 for the first surface hit after the emitter; plus [`EXIT`] for a VPL on
    /// the way out of a crevice, whose count is that of the vertex the path reaches.
    pub depth: u32,
    pub path: u64,
    pub tri: u32,
    /// A crevice vertex's VPL whose light stays in its neighbourhood (`vpl::crevice`): only
    /// the compensation, with exact visibility, reads it (at the point a pixel sees, within
    /// this distance); the GPU's gather does not.
    pub near: Option<f32>,
    /// A VPL on the way out of a crevice ([`EXIT`]): the normal of the crevice's vertex the
    /// path left from, facing into the crevice; its light leaves in a fan about the crevice's
    /// plane, on this side of it ([`crate::vpl::fan_lobe`]), not in a cosine lobe about
    /// [`Vpl::normal`] (the direction the path left along).
    pub fan: Option<Vec3>,
}

/// Traces light path `path` of stream `seed` in `frame`, returning its VPLs (possibly none).
pub fn trace_path(frame: &Frame, tracer: &Tracer, seed: u64, path: u64) -> Vec<Vpl> {
    let mut out = Vec::new();
    let em = &frame.emitters;
    if em.is_empty() {
        return out;
    }
    let mut r = rng(&[seed, path, 0x11a7]);
    let u: f32 = r.random();
    // From the environment first, in proportion to its power (`vpl::environment`).
    let env = em.environment_share();
    let u = if env > 0.0 && u < env {
        -1.0
    } else {
        (u - env) / (1.0 - env)
    };
    let share = em.area_share();
    let (mut ray, mut power) = if u < 0.0 {
        let (o, d, power) = super::environment::emit(em, &mut r);
        (PathRay::free(o, d), power / env)
    } else if u < share {
        let (e, p_e) = em.pick(u / share);
        let tri = em.tris[e] as usize;
        // The inside of a closed lamp: its light reaches nothing outside (trace::solids).
        if tracer.emits_inside_solid(tri as u32) {
            return out;
        }
        let b = triangle_barycentrics(Vec2::new(r.random(), r.random()));
        let n = frame.normals[tri];
        let x = frame.point(tri, b.x, b.y);
        let dir = cosine_hemisphere(n, Vec2::new(r.random(), r.random()));
        // Le * cos / (p_e / A * cos / pi)
        let power = frame.emission_at(tri, b.x, b.y)
            * (std::f32::consts::PI * frame.areas[tri] / (p_e * share * (1.0 - env)));
        (tracer.leave(x, n, dir), power)
    } else {
        let v = ((u - share) / (1.0 - share)).min(1.0 - 1e-7);
        let (i, p) = em.pick_light(v);
        let (o, d, power) = emit(&em.lights[i], em.sphere, &mut r);
        (
            PathRay::free(o, d),
            power / (p * (1.0 - share) * (1.0 - env)),
        )
    };
    if power == Vec3::ZERO {
        return out;
    }
    let reach = super::crevice::REACH * tracer.size();
    // The last vertex was in a crevice (by its coin, or its coin skipped deep in one).
    let mut in_crevice = false;
    // The normal of the path's last vertex (facing the side the light arrived from), and
    // whether its own coin found it sealed (None: its coin was not tossed).
    let mut last: Option<(Vec3, Option<bool>)> = None;
    for depth in 1..=MAX_DEPTH {
        let (origin, dir) = (ray.origin, ray.dir);
        let h = match tracer.follow_light(&ray, f32::INFINITY) {
            Next::Hit(h) => h,
            // Into a gap thinner than the tracer resolves: its light does not come back.
            Next::Sealed | Next::Miss => break,
        };
        let tri = h.tri as usize;
        let x = frame.point(tri, h.b1, h.b2);
        let ng = frame.normals[tri];
        // The back of a single-sided surface: those beyond it see its front, not this light,
        // and nobody sees its back (docs/math.md, "Single-sided surfaces").
        if ng.dot(dir) > 0.0 && tracer.single_sided(h.tri) {
            break;
        }
        // Inside a closed mesh the camera is outside of: its light never gets out
        // (trace::solids).
        if tracer.struck_inside_solid(h.tri, ng, dir) {
            break;
        }
        let nf = if ng.dot(dir) < 0.0 { ng } else { -ng };
        let albedo = frame.albedo_at(tri, h.b1, h.b2);
        // A vertex in a crevice is kept by a coin (vpl::crevice); the path goes on either way.
        // Deep in a crevice, at every THIN-th vertex only (DEEP).
        let hop_out = h.t > reach;
        // Skipped only where a ray along the normal meets a surface within the reach: a
        // path that walks out of the crevice in short hops (onto the lamp's side, the ceiling
        // beyond its edge) has its coin and its VPLs again at once.
        let skipped = in_crevice
            && depth > DEEP
            && depth % THIN != 0
            && !hop_out
            && tracer
                .intersect_light(tracer.offset(x, nf, nf), nf, reach)
                .is_some();
        let coin = (!skipped).then(|| super::crevice::coin(tracer, x, nf, (seed, path, depth)));
        let crevice = coin.is_none_or(|c| c.crevice);
        // Out of a crevice from a vertex sealed in it (none of its coin's rays got out), or
        // from one deep in it whose coin was skipped (it left no VPL): the light of that
        // vertex lit what the path now reaches through the crevice's mouth, which the GPU
        // cannot resolve, and no VPL of the GPU's carries it. So the light it sends out is a
        // VPL of its own where the hop is out of the crevice, with the path's direction and
        // that vertex's normal: its light leaves in a fan about the crevice's plane
        // (`vpl::fan_lobe`; docs/math.md, "Out of a 1 mm gap").
        let exit = match last {
            Some((n, was_sealed)) if in_crevice && hop_out && !crevice => {
                // Sealed by its coin, or skipped (None): its light reaches the room this way
                // alone. One with a ray out has its own VPL, for the GPU (or no VPL, by its coin).
                was_sealed
                    .unwrap_or(true)
                    .then(|| way_out(tracer, (origin, dir, h.t), n, reach))
                    .flatten()
                    .map(|m| (m, n))
            }
            _ => None,
        };
        if let Some((position, n)) = exit {
            out.push(Vpl {
                position,
                normal: dir,
                albedo: Vec3::ONE,
                power,
                depth: depth + EXIT,
                path,
                tri: h.tri,
                near: None,
                fan: Some(n),
            });
        }
        in_crevice = crevice;
        last = Some((nf, coin.map(|c| c.sealed)));
        if let Some((p, near)) = coin.and_then(|c| c.kept) {
            out.push(Vpl {
                position: x,
                normal: nf,
                albedo,
                power: power / p,
                depth,
                path,
                tri: h.tri,
                near,
                fan: None,
            });
        }
        // Russian roulette on albedo, at most 0.99 but in a crevice: the light there has no
        // way but out through the crevice's mouth, and albedo-1 walls absorb none of it on
        // the way, so a path goes on at its power. Ended there at 0.99 a bounce, the light that
        // gets out came on the few paths that lived, each weighted 1/0.99 a bounce (up to
        // hundreds-fold out of a 1 mm gap), and a frame's VPLs had blotches of them.
        let q = albedo.max_element().min(if crevice { 1.0 } else { 0.99 });
        if q <= 0.0 || r.random::<f32>() >= q {
            break;
        }
        power *= albedo / q;
        let dir = cosine_hemisphere(nf, Vec2::new(r.random(), r.random()));
        ray = tracer.leave(x, nf, dir);
    }
    out
}

/// Where a hop of length `t` from `o` along `d`, out of a crevice whose vertex at `o` had the
/// normal `n`, is out of it: the first of the points along it, a reach apart (an eighth of the
/// hop apart if that is shorter; after 16 of them, twice as far each), from which a ray along
/// `n` or against it runs a reach free. None if no such point comes before the hop's end.
fn way_out(tracer: &Tracer, (o, d, t): (Vec3, Vec3, f32), n: Vec3, reach: f32) -> Option<Vec3> {
    let mut step = reach.min(t / 8.0);
    let mut s = step;
    let mut k = 0;
    while s < t {
        let m = o + d * s;
        if tracer.intersect_light(m, n, reach).is_none()
            || tracer.intersect_light(m, -n, reach).is_none()
        {
            return Some(m);
        }
        k += 1;
        if k >= 16 {
            step *= 2.0;
        }
        s += step;
    }
    None
}

/// Where a light path leaves punctual light `l`, its direction, and its power over the
/// density of that choice: `I f(cos) / pdf(direction)` for point and spot lights,
/// `E / pdf(point on the disk)` for a directional light.
fn emit(l: &PunctualLight, (c, radius): (Vec3, f32), r: &mut impl Rng) -> (Vec3, Vec3, Vec3) {
    let (u1, u2): (f32, f32) = (r.random(), r.random());
    let phi = 2.0 * PI * u2;
    match l.kind {
        LightKind::Point => {
            let z = 1.0 - 2.0 * u1;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            (l.position, d, l.intensity * (4.0 * PI))
        }
        LightKind::Spot { cos_outer, .. } => {
            let z = 1.0 - u1 * (1.0 - cos_outer);
            let s = (1.0 - z * z).max(0.0).sqrt();
            let (t, b) = basis(l.direction);
            let d = (t * (s * phi.cos()) + b * (s * phi.sin()) + l.direction * z).normalize();
            let f = l.kind.falloff(z);
            (
                l.position,
                d,
                l.intensity * (f * 2.0 * PI * (1.0 - cos_outer)),
            )
        }
        LightKind::Directional => {
            let (t, b) = basis(l.direction);
            let rr = radius * u1.sqrt();
            let o = c - l.direction * (radius * 1.01) + (t * phi.cos() + b * phi.sin()) * rr;
            (o, l.direction, l.intensity * (PI * radius * radius))
        }
    }
}

/// Traces paths `first..first+count` of stream `seed` in parallel; VPLs in path order.
pub fn trace_paths(frame: &Frame, tracer: &Tracer, seed: u64, first: u64, count: u64) -> Vec<Vpl> {
    (first..first + count)
        .into_par_iter()
        .map(|p| trace_path(frame, tracer, seed, p))
        .flatten_iter()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::luminance;
    use crate::scene::builtin;

    #[test]
    fn same_seed_same_vpls_other_seed_other_vpls() {
        let scene = builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        let a = trace_paths(&f, &tr, 7, 0, 500);
        let b = trace_paths(&f, &tr, 7, 0, 500);
        assert_eq!(a, b);
        assert!(
            a.len() > 500,
            "Cornell paths bounce more than once on average: {}",
            a.len()
        );
        // Path 123 alone is the same as path 123 in the batch.
        let one = trace_path(&f, &tr, 7, 123);
        let in_batch: Vec<Vpl> = a.iter().filter(|v| v.path == 123).copied().collect();
        assert_eq!(one, in_batch);
        assert_ne!(a, trace_paths(&f, &tr, 8, 0, 500));
    }

    /// The expected reflected power of the first bounce, `E[sum Phi_1 rho_1] / N`, equals the
    /// emitters' power times the mean albedo at the first hit, estimated here independently by
    /// shooting from the light quad directly (no emitter CDF, no shared warps).
    #[test]
    fn first_bounce_power_bookkeeping() {
        let scene = builtin::load("cornell").unwrap().unwrap();
        let f = scene.at(0.0);
        let tr = Tracer::new(&f);
        let n = 40_000u64;
        let vpls = trace_paths(&f, &tr, 3, 0, n);
        let samples: Vec<f32> = (0..n)
            .map(|p| {
                vpls.iter()
                    .filter(|v| v.path == p && v.depth == 1)
                    .map(|v| luminance(v.power * v.albedo))
                    .sum()
            })
            .collect();
        let (mean, se) = mean_se(&samples);
        // Independent estimate: uniform point on the light rectangle, direction by rejection
        // from the uniform hemisphere weighted by cos (so E[albedo] is flux-weighted).
        let mut r = rng(&[99]);
        let le = f.emission(f.emitters.tris[0] as usize);
        let area: f32 = f.emitters.tris.iter().map(|&t| f.areas[t as usize]).sum();
        let power = le * std::f32::consts::PI * area;
        let mut albedo_samples = Vec::new();
        while albedo_samples.len() < 40_000 {
            let p = Vec3::new(
                r.random_range(-0.23..0.23),
                0.99,
                r.random_range(-0.18..0.20),
            );
            let d = Vec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..0.0),
                r.random_range(-1.0..1.0),
            );
            let l = d.length();
            if !(1e-3..=1.0).contains(&l) || r.random::<f32>() > -d.y / l {
                continue;
            }
            let a = match tr.intersect(p + Vec3::new(0.0, -1e-4, 0.0), d / l, f32::INFINITY) {
                Some(h) => luminance(power * f.albedo(h.tri as usize)),
                None => 0.0,
            };
            albedo_samples.push(a);
        }
        let (mean2, se2) = mean_se(&albedo_samples);
        let z = (mean - mean2).abs() / (se * se + se2 * se2).sqrt();
        assert!(
            z < 4.0,
            "VPL depth-1 power {mean} +- {se} vs emitter power x albedo {mean2} +- {se2}"
        );
        // And the emitters' power is what the light's radiance and area say.
        assert!((f.emitters.total_power - power).length() < 1e-3 * power.length());
    }

    fn mean_se(x: &[f32]) -> (f32, f32) {
        let n = x.len() as f64;
        let m = x.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = x.iter().map(|&v| (v as f64 - m).powi(2)).sum::<f64>() / (n - 1.0);
        (m as f32, (var / n).sqrt() as f32)
    }
}
