//! The indirect light's temporal gradient, for temporal accumulation under a moving light or
//! object (`gpu::temporal`, docs/math.md section 14): how much of a pixel's accumulated history
//! still estimates this frame's light.
//!
//! After Schied, Peters and Dachsbacher (2018, "Gradient estimation for real-time adaptive
//! temporal filtering"): the change of the light is measured with the same random numbers in
//! both frames, so the difference holds the change and little of the noise. Here the random
//! numbers are [`PROBE_PATHS`] light paths of a stream of their own, traced in each frame's
//! scene (as `frozen` traces its paths: they slide with a moving light), and the points they
//! light are a grid of [`GRID`] x [`GRID`] probes, the surfaces seen through the cell centres
//! of this frame's camera. At each probe, the light of this frame's probe VPLs `E` and that of
//! the last frame's probe VPLs `E'` (both with ray-traced visibility in this frame's geometry,
//! and the distance clamped at least at the probes' spacing, the finest light the grid
//! resolves) give the relative change
//!
//! `lambda = blur |E - E'| / blur max(E, E', floor)`,
//!
//! with both sums blurred over the probe's 3x3 neighbours (the gradient's noise, mostly paths
//! whose bounce moved to another surface) and `floor` a twentieth of the mean `E`, so dark
//! probes do not count as changed for a small absolute change. The temporal pass reads
//! `lambda` bilinearly at each pixel and gives this frame's estimate the weight
//! `alpha + (1 - alpha) lambda` instead of the history's `alpha = 1 / (frames + 1)`: an
//! unchanged light keeps the history whole, a light switched off (`lambda = 1`) drops it.

use super::{trace_path, ShadedVpl, Vpl};
use crate::math::luminance;
use crate::scene::Frame;
use crate::trace::Tracer;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Probes per side of the grid over the image. Fewer probes and more paths, for the same rays:
/// the indirect light changes smoothly, and the gradient's noise is the paths'. Measured on
/// `cornell-light` at 96x96 (median / 90th percentile of lambda over the frames): 16 x 16
/// probes with 64 paths 0.05-0.11 / 0.14-0.37, with 128 paths 0.03-0.09 / 0.08-0.27, with 1024
/// paths 0.02-0.04 / 0.05-0.11 (the change itself); 8 x 8 with 512 paths 0.02-0.05 /
/// 0.05-0.11, in 9-13 ms a frame.
pub const GRID: usize = 8;
/// Light paths traced for the gradient each frame.
pub const PROBE_PATHS: u64 = 512;
/// The probe paths' ids: a range no sampler draws from (samplers use `frame * 2^20 + i`).
const PROBE_PATH_BASE: u64 = 1 << 62;
/// The floor of the gradient's denominator, as a fraction of the mean light of the probes.
const FLOOR: f32 = 0.05;

/// The relative change of the light over a grid of the image (row-major, `GRID x GRID`).
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    pub width: u32,
    pub height: u32,
    pub lambda: Vec<f32>,
}

/// The gradient's state between frames: the last frame's probe VPLs.
#[derive(Default)]
pub struct LightGradient {
    last: Option<Vec<Vpl>>,
}

impl LightGradient {
    /// Whether a frame was measured (the next one can be compared with it).
    pub fn primed(&self) -> bool {
        self.last.is_some()
    }

    /// Traces this frame's probe paths and measures the change against the last frame's (None
    /// for the first frame, or when no probe sees a surface).
    pub fn measure(
        &mut self,
        frame: &Frame,
        tracer: &Tracer,
        seed: u64,
        (width, height): (u32, u32),
        clamp: f32,
    ) -> Option<Gradient> {
        let vpls: Vec<Vpl> = (0..PROBE_PATHS)
            .into_par_iter()
            .flat_map_iter(|i| trace_path(frame, tracer, seed, PROBE_PATH_BASE + i))
            .collect();
        let last = self.last.replace(vpls);
        let last = last?;
        let now = self.last.as_deref().unwrap_or_default();
        let probes = probe_points(frame, tracer, width, height);
        let spacing = spacing(frame, &probes);
        let light = |vs: &[Vpl], x: Vec3, n: Vec3, h: f32| -> f32 {
            // The light the GPU gathers: not a crevice's VPLs (vpl::crevice).
            vs.iter()
                .filter(|v| v.near.is_none())
                .map(|v| {
                    let s = ShadedVpl::new(v, 1.0 / PROBE_PATHS as f32);
                    let c = s.radiance_at(x, n, Vec3::ONE, clamp.max(h));
                    if c == Vec3::ZERO || tracer.occluded(x, n, v.position, v.normal) {
                        0.0
                    } else {
                        luminance(c)
                    }
                })
                .sum()
        };
        let e: Vec<Option<(f32, f32)>> = probes
            .par_iter()
            .zip(&spacing)
            .map(|(p, &h)| p.map(|(x, n)| (light(now, x, n, h), light(&last, x, n, h))))
            .collect();
        let seen: Vec<f32> = e.iter().flatten().map(|&(a, _)| a).collect();
        if seen.is_empty() {
            return None;
        }
        let floor = FLOOR * seen.iter().sum::<f32>() / seen.len() as f32;
        Some(Gradient {
            width: GRID as u32,
            height: GRID as u32,
            lambda: blurred_ratio(&e, floor),
        })
    }
}

/// The surface point and camera-facing normal seen through each cell centre of a `GRID x
/// GRID` grid over the image (None where the ray hits nothing).
fn probe_points(
    frame: &Frame,
    tracer: &Tracer,
    width: u32,
    height: u32,
) -> Vec<Option<(Vec3, Vec3)>> {
    (0..GRID * GRID)
        .into_par_iter()
        .map(|s| {
            let (i, j) = (s % GRID, s / GRID);
            let p = Vec2::new(
                (i as f32 + 0.5) / GRID as f32 * width as f32,
                (j as f32 + 0.5) / GRID as f32 * height as f32,
            );
            let d = frame.camera.ray_dir(p, width, height);
            let h = tracer.intersect(frame.camera.position, d, f32::INFINITY)?;
            let ng = frame.normals[h.tri as usize];
            let n = if ng.dot(d) < 0.0 { ng } else { -ng };
            Some((frame.point(h.tri as usize, h.b1, h.b2), n))
        })
        .collect()
}

/// Each probe's spacing: the distance its camera ray travels times the angle between cell
/// centres, so that VPLs nearer a probe than its neighbours are (light the grid does not
/// resolve) count with their distance clamped there.
fn spacing(frame: &Frame, probes: &[Option<(Vec3, Vec3)>]) -> Vec<f32> {
    let cam = frame.camera.position;
    let cell = frame.camera.yfov / GRID as f32;
    probes
        .iter()
        .map(|p| p.map_or(0.0, |(x, _)| x.distance(cam) * cell))
        .collect()
}

/// `blur |E - E'| / blur max(E, E', floor)` over each probe's 3x3 neighbours that see a
/// surface (0 where none does).
fn blurred_ratio(e: &[Option<(f32, f32)>], floor: f32) -> Vec<f32> {
    (0..GRID * GRID)
        .map(|s| {
            let (i, j) = ((s % GRID) as i64, (s / GRID) as i64);
            let (mut num, mut den) = (0.0f32, 0.0f32);
            for dj in -1..=1 {
                for di in -1..=1 {
                    let (a, b) = (i + di, j + dj);
                    if a < 0 || b < 0 || a >= GRID as i64 || b >= GRID as i64 {
                        continue;
                    }
                    if let Some((now, then)) = e[(b * GRID as i64 + a) as usize] {
                        num += (now - then).abs();
                        den += now.max(then).max(floor);
                    }
                }
            }
            if den > 0.0 {
                (num / den).min(1.0)
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{blurred_ratio, GRID};

    #[test]
    fn the_ratio_is_zero_for_the_same_light_one_for_light_gone_and_floored_in_the_dark() {
        let same = vec![Some((2.0, 2.0)); GRID * GRID];
        assert!(blurred_ratio(&same, 0.1).iter().all(|&l| l == 0.0));
        let gone = vec![Some((0.0, 2.0)); GRID * GRID];
        assert!(blurred_ratio(&gone, 0.1).iter().all(|&l| l == 1.0));
        // A 10% dimming everywhere.
        let dim = vec![Some((1.8, 2.0)); GRID * GRID];
        assert!(blurred_ratio(&dim, 0.1)
            .iter()
            .all(|&l| (l - 0.1).abs() < 1e-6));
        // In the dark, a change small against the floor counts for little.
        let dark = vec![Some((0.001, 0.002)); GRID * GRID];
        assert!(blurred_ratio(&dark, 0.1).iter().all(|&l| l < 0.011));
        // No probe sees a surface: no change.
        assert!(blurred_ratio(&[None; GRID * GRID], 0.1)
            .iter()
            .all(|&l| l == 0.0));
    }
}
