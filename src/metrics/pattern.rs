//! How visible a periodic pattern is in an image: the interleaved gather's block pattern
//! (`--interleave n`: each pixel of an n x n block gathers its own subset of the VPLs, and the
//! interleave filter must average the subsets back into one estimate). A pattern of period n
//! is the same offset at every pixel of the same phase (x mod n, y mod n). So the image's
//! detail (its luminance less its 5x5 box mean, which leaves a 4-pixel pattern nearly whole
//! and the shading's slow change out; pixels near an edge left out) is averaged per phase: with no pattern the n^2 phase
//! means differ only by the detail's noise and edges; with one they differ by the pattern.
//! [`Pattern`] gives their RMS over the image's mean luminance (the pattern's amplitude), and
//! its ratio to the same measure at periods that share no factor with n (what noise and edges
//! alone give).

use crate::image::Hdr;
use crate::math::luminance;

/// A periodic pattern's measure in an image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pattern {
    /// The RMS of the phase means of the detail, over the mean luminance.
    pub amplitude: f64,
    /// `amplitude` over its median at the periods [`CONTROL`] (about 1 without a pattern).
    pub ratio: f64,
}

/// The periods the measure is compared with: prime, so no pattern of period 2, 4 or 8 (the
/// interleave's) aligns with their phases.
pub const CONTROL: [usize; 3] = [3, 5, 7];

/// The image's detail: luminance less its 5x5 box mean, None near an edge: where the 5x5
/// window holds a step between neighbours above [`EDGE`] times the image's median step, or
/// runs over the border.
fn detail(lum: &[f64], width: usize, height: usize) -> Vec<Option<f64>> {
    let at = |x: usize, y: usize| lum[y * width + x];
    let step: Vec<f64> = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let dx = if x + 1 < width {
                (at(x + 1, y) - at(x, y)).abs()
            } else {
                0.0
            };
            let dy = if y + 1 < height {
                (at(x, y + 1) - at(x, y)).abs()
            } else {
                0.0
            };
            dx.max(dy)
        })
        .collect();
    let mut sorted = step.clone();
    sorted.sort_by(f64::total_cmp);
    let limit = EDGE * sorted[sorted.len() / 2];
    (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            if x < 2 || y < 2 || x + 2 >= width || y + 2 >= height {
                return None;
            }
            let mut sum = 0.0;
            for b in y - 2..=y + 2 {
                for a in x - 2..=x + 2 {
                    if step[b * width + a] > limit {
                        return None;
                    }
                    sum += at(a, b);
                }
            }
            Some(lum[i] - sum / 25.0)
        })
        .collect()
}

/// A step between neighbours this many times the image's median step marks an edge.
const EDGE: f64 = 6.0;

/// The RMS over the `period`^2 phases of the mean detail at each phase.
fn phase_rms(d: &[Option<f64>], width: usize, period: usize) -> f64 {
    let mut sum = vec![0.0; period * period];
    let mut count = vec![0.0; period * period];
    for (i, v) in d.iter().enumerate() {
        let Some(v) = *v else { continue };
        let (x, y) = (i % width, i / width);
        let k = (y % period) * period + x % period;
        sum[k] += v;
        count[k] += 1.0;
    }
    let means: Vec<f64> = sum
        .iter()
        .zip(&count)
        .filter(|(_, &c)| c > 0.0)
        .map(|(s, c)| s / c)
        .collect();
    (means.iter().map(|m| m * m).sum::<f64>() / means.len().max(1) as f64).sqrt()
}

/// The pattern of period `period` in luminance `lum` (`width` x `height`); None for a period
/// below 2, an image smaller than 2 periods a side or a black one.
pub fn periodic_pattern(
    lum: &[f64],
    width: usize,
    height: usize,
    period: usize,
) -> Option<Pattern> {
    if period < 2 || lum.len() != width * height || width.min(height) < 2 * period.max(7) {
        return None;
    }
    let mean = lum.iter().sum::<f64>() / lum.len() as f64;
    if mean <= 0.0 {
        return None;
    }
    let d = detail(lum, width, height);
    let at = |p: usize| phase_rms(&d, width, p) / mean;
    let amplitude = at(period);
    let mut control: Vec<f64> = CONTROL.iter().map(|&p| at(p)).collect();
    control.sort_by(f64::total_cmp);
    let ratio = if control[1] > 0.0 {
        amplitude / control[1]
    } else {
        f64::INFINITY
    };
    Some(Pattern { amplitude, ratio })
}

/// [`periodic_pattern`] of an image's luminance.
pub fn image_pattern(img: &Hdr, period: usize) -> Option<Pattern> {
    let lum: Vec<f64> = img.data.iter().map(|&c| luminance(c) as f64).collect();
    periodic_pattern(&lum, img.width as usize, img.height as usize, period)
}

#[cfg(test)]
mod tests {
    use super::periodic_pattern;
    use crate::math::rng;
    use rand::Rng;

    /// Shading that varies slowly, a sharp edge, and white noise: an image without a pattern.
    fn noisy(w: usize, h: usize, sigma: f64) -> Vec<f64> {
        let mut r = rng(&[7]);
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                let edge = if x > 0.37 * w as f64 { 0.3 } else { 0.0 };
                0.5 + 0.3 * (x / w as f64)
                    + 0.1 * (y / h as f64 * 3.0).sin()
                    + edge
                    + sigma * (r.random::<f64>() - 0.5)
            })
            .collect()
    }

    #[test]
    fn noise_and_edges_show_no_pattern_and_a_faint_block_pattern_does() {
        let (w, h) = (96, 96);
        let clean = noisy(w, h, 0.1);
        let p0 = periodic_pattern(&clean, w, h, 4).unwrap();
        assert!(p0.ratio > 0.3 && p0.ratio < 2.0, "noise alone: {p0:?}");
        // A 4x4 pattern of up to +-1.5% of a mean of about 0.8 (RMS 0.8%; the noise is 3.6% a
        // pixel), the kind an unfiltered interleaved gather leaves: found, with about its
        // amplitude. (The phase means' noise here is about 0.17% of the mean: patterns much
        // fainter than that cannot be told from noise in a 96x96 image.)
        let mut r = rng(&[8]);
        let cell: Vec<f64> = (0..16)
            .map(|_| 0.012 * (r.random::<f64>() * 2.0 - 1.0))
            .collect();
        let rms = (cell.iter().map(|c| c * c).sum::<f64>() / 16.0).sqrt();
        let planted: Vec<f64> = clean
            .iter()
            .enumerate()
            .map(|(i, &v)| v + cell[(i / w % 4) * 4 + i % w % 4])
            .collect();
        let p1 = periodic_pattern(&planted, w, h, 4).unwrap();
        println!("without a pattern {p0:?}; planted {p1:?}");
        let mean = planted.iter().sum::<f64>() / planted.len() as f64;
        assert!(p1.ratio > 3.0, "planted pattern: {p1:?}");
        assert!(
            p1.amplitude > 0.5 * rms / mean && p1.amplitude < 1.5 * rms / mean,
            "planted pattern of RMS {}: {p1:?}",
            rms / mean
        );
        assert_eq!(periodic_pattern(&clean, w, h, 1), None);
        assert_eq!(periodic_pattern(&vec![0.0; w * h], w, h, 4), None);
    }
}
