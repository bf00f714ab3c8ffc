//! The measurement's floor: how much of a test's measured error and flicker the reference's
//! own noise accounts for (docs/math.md, "The floor of the measurement").
//!
//! The reference `R` is the spp-weighted mean of two independent halves `A` (`n_a` samples a
//! pixel) and `B` (`n_b`), traced with different seeds but each with the same random stream
//! for a pixel in every frame. Then `D = k (A - B)`, `k = sqrt(n_a n_b) / (n_a + n_b)`, has the
//! same mean (0) and the same covariance across pixels and frames as the reference's noise
//! `N = R - truth`, without containing the truth. A perfect renderer's error against `R` is
//! `-N`, so the floor is what the metrics say of the image `R + D` against `R`: its error is
//! `D`, distributed (to second order) as a perfect renderer's.

use super::warp::{warped_f1, Warp, WarpedFlicker};
use super::{sequence, SequenceMetrics};
use crate::image::Hdr;
use anyhow::{bail, Result};
use serde::Serialize;

/// The reference's noise floor under a comparison's figures.
#[derive(Clone, Debug, Serialize)]
pub struct Floor {
    /// Samples per pixel of the two halves.
    pub spp: [u32; 2],
    /// F1 a perfect renderer would measure: `mean_t mean_p |D_t - D_(t-1)|`.
    pub flicker_f1: f64,
    /// RMS of `D_t - D_(t-1)`.
    pub flicker_rms: f64,
    /// Warped F1 of `D` (None when the comparison has no motion fields).
    pub warped_f1: Option<f64>,
    /// relMSE a perfect renderer would measure: `mean (D^2 / (R^2 + 0.01))`.
    pub rel_mse: f64,
    /// Per frame: the floor's flicker (None for the first frame) and relMSE.
    pub frames: Vec<FloorFrame>,
}

/// The floor of one frame.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FloorFrame {
    pub frame: u32,
    pub flicker: Option<f64>,
    pub warped_flicker: Option<f64>,
    pub rel_mse: f64,
}

/// `k` with `D = k (A - B)` distributed as the noise of `(n_a A + n_b B) / (n_a + n_b)`.
pub fn scale(spp: [u32; 2]) -> f64 {
    let (a, b) = (spp[0] as f64, spp[1] as f64);
    (a * b).sqrt() / (a + b)
}

/// `R + D`: the reference plus a noise image distributed as its own.
pub fn noisy_twin(reference: &Hdr, a: &Hdr, b: &Hdr, spp: [u32; 2]) -> Hdr {
    let k = scale(spp) as f32;
    Hdr {
        width: reference.width,
        height: reference.height,
        data: reference
            .data
            .iter()
            .zip(a.data.iter().zip(&b.data))
            .map(|(r, (x, y))| *r + (*x - *y) * k)
            .collect(),
    }
}

/// The floor of the reference `reference` made of halves `a` and `b` (`spp` samples a pixel
/// each), frames `numbers`; `motion` (from [`super::warp::motion`]) adds the warped F1.
pub fn floor(
    numbers: &[u32],
    reference: &[Hdr],
    halves: [&[Hdr]; 2],
    spp: [u32; 2],
    motion: Option<&[Vec<Option<Warp>>]>,
) -> Result<Floor> {
    if spp[0] == 0 || spp[1] == 0 {
        bail!(
            "the reference's halves have {} and {} samples a pixel: each needs at least 1",
            spp[0],
            spp[1]
        );
    }
    let [a, b] = halves;
    if a.len() != reference.len() || b.len() != reference.len() {
        bail!(
            "the reference has {} frames but its halves {} and {}",
            reference.len(),
            a.len(),
            b.len()
        );
    }
    let twin: Vec<Hdr> = reference
        .iter()
        .zip(a.iter().zip(b))
        .map(|(r, (x, y))| {
            if (x.width, x.height) != (r.width, r.height)
                || (y.width, y.height) != (r.width, r.height)
            {
                bail!("the reference's halves differ in size from the reference");
            }
            Ok(noisy_twin(r, x, y, spp))
        })
        .collect::<Result<_>>()?;
    let m: SequenceMetrics = sequence(numbers, &twin, reference)?;
    let w: Option<WarpedFlicker> = motion
        .map(|mo| warped_f1(&twin, reference, mo))
        .transpose()?;
    let frames = m
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| FloorFrame {
            frame: f.frame,
            flicker: f.flicker,
            warped_flicker: match (&w, i) {
                (Some(w), i) if i > 0 => w.frames.get(i - 1).map(|x| x.0),
                _ => None,
            },
            rel_mse: f.error.rel_mse,
        })
        .collect();
    Ok(Floor {
        spp,
        flicker_f1: m.flicker_f1,
        flicker_rms: m.flicker_rms,
        warped_f1: w.map(|w| w.f1),
        rel_mse: m.mean_rel_mse,
        frames,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use rand::{Rng, SeedableRng};

    const W: u32 = 64;
    const H: u32 = 64;
    const T: usize = 6;

    /// A smooth truth that changes from frame to frame (as a moving light would).
    fn truth(t: usize) -> Hdr {
        Hdr {
            width: W,
            height: H,
            data: (0..W * H)
                .map(|i| {
                    let (x, y) = ((i % W) as f32 / W as f32, (i / W) as f32 / H as f32);
                    Vec3::new(0.3 + 0.4 * x, 0.5 + 0.2 * y, 0.4 + 0.1 * t as f32)
                })
                .collect(),
        }
    }

    /// Truth plus Gaussian noise of standard deviation `sigma / sqrt(n)` (a mean of n samples
    /// of per-sample deviation sigma), the same in every channel so luminance sees `sigma`.
    /// `fixed`: the same noise in every frame (a still scene with per-pixel streams).
    fn half(seed: u64, n: u32, sigma: f64, fixed: bool) -> Vec<Hdr> {
        let dev = sigma / (n as f64).sqrt();
        (0..T)
            .map(|t| {
                let stream = seed * 1000 + if fixed { 0 } else { t as u64 };
                let mut r = rand_pcg::Pcg32::seed_from_u64(stream);
                let mut img = truth(t);
                for c in &mut img.data {
                    // Box-Muller.
                    let (u, v): (f64, f64) = (1.0 - r.random::<f64>(), r.random());
                    let g = (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                    *c += Vec3::splat((g * dev) as f32);
                }
                img
            })
            .collect()
    }

    fn reference(a: &[Hdr], b: &[Hdr], spp: [u32; 2]) -> Vec<Hdr> {
        a.iter()
            .zip(b)
            .map(|(x, y)| {
                let (wa, wb) = (spp[0] as f32, spp[1] as f32);
                Hdr {
                    width: W,
                    height: H,
                    data: x
                        .data
                        .iter()
                        .zip(&y.data)
                        .map(|(p, q)| (*p * wa + *q * wb) / (wa + wb))
                        .collect(),
                }
            })
            .collect()
    }

    /// Synthetic halves with known noise: the reference's noise per pixel has deviation
    /// `s = sigma / sqrt(n_a + n_b)`, independent between frames, so its frame-to-frame change
    /// has deviation `sqrt(2) s` and `E|change| = sqrt(2/pi) sqrt(2) s = 2 s / sqrt(pi)`; the
    /// F1 over n pixels and T-1 pairs has standard error `sqrt(2 s^2 (1 - 2/pi) / (n (T-1)))`.
    /// The floor must match that, and the F1 that the truth itself (a perfect renderer)
    /// measures against the reference, within 3 standard errors; unequal splits (3:1, 15:1)
    /// checks the scale k.
    /// relMSE divides by the noisy reference, `N^2 / ((G + N)^2 + 0.01)`, which `D^2 / (R^2 +
    /// 0.01)` matches only to first order in the relative noise `s / G` (here at most 0.08,
    /// as for a reference worth comparing against); its second-order part makes the floor
    /// low by about `3 (s / G)^2` of itself.
    #[test]
    fn the_floor_equals_the_known_noise_of_the_reference() {
        let sigma = 0.1;
        for spp in [[8u32, 8], [12, 4], [15, 1]] {
            let a = half(1, spp[0], sigma, false);
            let b = half(2, spp[1], sigma, false);
            let r = reference(&a, &b, spp);
            let numbers: Vec<u32> = (0..T as u32).collect();
            let fl = floor(&numbers, &r, [&a, &b], spp, None).unwrap();
            let s = sigma / ((spp[0] + spp[1]) as f64).sqrt();
            let known = 2.0 * s / std::f64::consts::PI.sqrt();
            let n = (W * H) as f64 * (T - 1) as f64;
            let se = (2.0 * s * s * (1.0 - 2.0 / std::f64::consts::PI) / n).sqrt();
            // What a perfect renderer measures: the truth against the reference.
            let perfect: Vec<Hdr> = (0..T).map(truth).collect();
            let p = sequence(&numbers, &perfect, &r).unwrap();
            println!(
                "spp {spp:?}: floor F1 {:.6}, known {known:.6} (se {se:.2e}), perfect renderer {:.6}; relMSE floor {:.3e}, perfect {:.3e}",
                fl.flicker_f1, p.flicker_f1, fl.rel_mse, p.mean_rel_mse
            );
            // Measured: the floor 1.0 to 2.3 standard errors from the known value, the perfect
            // renderer 0.4 to 1.6.
            assert!((fl.flicker_f1 - known).abs() < 3.0 * se, "spp {spp:?}");
            assert!((p.flicker_f1 - known).abs() < 3.0 * se, "spp {spp:?}");
            // relMSE: the mean of D^2 / (R^2 + 0.01) against the perfect renderer's mean of
            // N^2 / (R^2 + 0.01); both are means of n T terms of relative spread sqrt(2).
            // Measured: apart by 0.3%, 0.6%, 1.8% (3.9e-5, 1.4 standard errors of the
            // difference, for 15:1).
            let rel_se = p.mean_rel_mse * (2.0 / (n * T as f64 / (T - 1) as f64)).sqrt();
            assert!(
                (fl.rel_mse - p.mean_rel_mse).abs() < 2.0 * 2f64.sqrt() * rel_se,
                "spp {spp:?}: {} vs {}",
                fl.rel_mse,
                p.mean_rel_mse
            );
        }
    }

    /// Noise that is the same in every frame (each pixel's stream repeats, as in the
    /// reference tracer) gives no flicker floor however the truth changes, while its relMSE
    /// floor stays; halves of 0 samples are refused.
    #[test]
    fn noise_fixed_in_time_has_no_flicker_floor() {
        let a = half(3, 4, 0.4, true);
        let b = half(4, 4, 0.4, true);
        let r = reference(&a, &b, [4, 4]);
        let numbers: Vec<u32> = (0..T as u32).collect();
        let fl = floor(&numbers, &r, [&a, &b], [4, 4], None).unwrap();
        // Measured: F1 ~1e-8 (f32 rounding of R + D), relMSE ~0.02.
        assert!(fl.flicker_f1 < 1e-6, "{}", fl.flicker_f1);
        assert!(fl.rel_mse > 1e-3, "{}", fl.rel_mse);
        assert!(floor(&numbers, &r, [&a, &b], [4, 0], None).is_err());
    }
}
