//! Error and flicker metrics (DESIGN.md "Metrics"). Per frame, I = test, R = reference,
//! e = lum(I) - lum(R).

use crate::image::Hdr;
use crate::math::luminance;
pub mod floor;
pub mod pattern;
pub mod warp;

use anyhow::{bail, Result};
use serde::Serialize;

/// Per-frame error of a test image against the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameError {
    /// `mean over pixels and channels of (I-R)^2 / (R^2 + 0.01)`.
    pub rel_mse: f64,
    /// Root mean squared error of RGB.
    pub rmse: f64,
    /// `mean lum(I) - mean lum(R)`.
    pub bias: f64,
    /// `mean lum(I) / mean lum(R) - 1`.
    pub rel_bias: f64,
}

fn same_size(a: &Hdr, b: &Hdr) -> Result<()> {
    if (a.width, a.height) != (b.width, b.height) {
        bail!(
            "image sizes differ: {}x{} against {}x{}",
            a.width,
            a.height,
            b.width,
            b.height
        );
    }
    Ok(())
}

/// relMSE, RMSE and bias of `test` against `reference`.
pub fn frame_error(test: &Hdr, reference: &Hdr) -> Result<FrameError> {
    same_size(test, reference)?;
    let n = test.data.len() as f64;
    let (mut rel, mut se, mut lt, mut lr) = (0.0, 0.0, 0.0, 0.0);
    for (i, r) in test.data.iter().zip(&reference.data) {
        for c in 0..3 {
            let (x, y) = (i[c] as f64, r[c] as f64);
            rel += (x - y).powi(2) / (y * y + 0.01);
            se += (x - y).powi(2);
        }
        lt += luminance(*i) as f64;
        lr += luminance(*r) as f64;
    }
    Ok(FrameError {
        rel_mse: rel / (3.0 * n),
        rmse: (se / (3.0 * n)).sqrt(),
        bias: (lt - lr) / n,
        rel_bias: if lr > 0.0 { lt / lr - 1.0 } else { 0.0 },
    })
}

/// Mean LDR FLIP (NVIDIA's perceptual error, 0 = same) of the tone-mapped images
/// (exposure 1, sRGB) at the default 67 pixels per degree.
pub fn flip(test: &Hdr, reference: &Hdr) -> Result<f64> {
    same_size(test, reference)?;
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.to_srgb8(1.0));
    let r = nv_flip::FlipImageRgb8::with_data(
        reference.width,
        reference.height,
        &reference.to_srgb8(1.0),
    );
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec();
    Ok(map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64)
}

/// Luminance error image `e = lum(I) - lum(R)`.
pub fn error_image(test: &Hdr, reference: &Hdr) -> Vec<f64> {
    test.data
        .iter()
        .zip(&reference.data)
        .map(|(i, r)| luminance(*i) as f64 - luminance(*r) as f64)
        .collect()
}

/// Metrics of one frame of a sequence: its error, and its flicker against the previous frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameMetrics {
    pub frame: u32,
    #[serde(flatten)]
    pub error: FrameError,
    /// `mean_p |e_t - e_{t-1}|` (None for the first frame).
    pub flicker: Option<f64>,
    /// `sqrt(mean_p (e_t - e_{t-1})^2)`.
    pub flicker_rms: Option<f64>,
    /// Mean LDR FLIP against the reference.
    pub flip: f64,
}

/// Metrics of a whole sequence.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SequenceMetrics {
    pub frames: Vec<FrameMetrics>,
    pub mean_rel_mse: f64,
    pub mean_rmse: f64,
    pub mean_bias: f64,
    pub mean_flip: f64,
    /// F1: mean over frame pairs of `mean_p |e_t - e_{t-1}|`: change the reference lacks.
    pub flicker_f1: f64,
    /// RMS of the frame-to-frame error change.
    pub flicker_rms: f64,
    /// `mean_p Var_t(e_t)`: the temporal variance of the error.
    pub temporal_variance: f64,
    /// `mean_p (mean_t e_t)^2`: the error that stays.
    pub temporal_bias: f64,
}

/// Metrics of test frames against reference frames (same sizes, in frame order, consecutive).
pub fn sequence(numbers: &[u32], test: &[Hdr], reference: &[Hdr]) -> Result<SequenceMetrics> {
    if test.len() != reference.len() || test.len() != numbers.len() || test.is_empty() {
        bail!(
            "sequences differ in length: {} test frames, {} reference frames",
            test.len(),
            reference.len()
        );
    }
    let mut out = SequenceMetrics::default();
    let mut prev: Option<Vec<f64>> = None;
    let np = test[0].data.len();
    let mut sum_e = vec![0.0f64; np];
    let mut sum_e2 = vec![0.0f64; np];
    for ((&f, t), r) in numbers.iter().zip(test).zip(reference) {
        same_size(t, &test[0])?;
        let error = frame_error(t, r)?;
        let e = error_image(t, r);
        let (flicker, flicker_rms) = match &prev {
            Some(p) => {
                let d: Vec<f64> = e.iter().zip(p).map(|(a, b)| a - b).collect();
                (
                    Some(d.iter().map(|x| x.abs()).sum::<f64>() / np as f64),
                    Some((d.iter().map(|x| x * x).sum::<f64>() / np as f64).sqrt()),
                )
            }
            None => (None, None),
        };
        for (i, &x) in e.iter().enumerate() {
            sum_e[i] += x;
            sum_e2[i] += x * x;
        }
        let flip = flip(t, r)?;
        out.frames.push(FrameMetrics {
            frame: f,
            error,
            flicker,
            flicker_rms,
            flip,
        });
        prev = Some(e);
    }
    let n = test.len() as f64;
    out.mean_rel_mse = out.frames.iter().map(|f| f.error.rel_mse).sum::<f64>() / n;
    out.mean_rmse = out.frames.iter().map(|f| f.error.rmse).sum::<f64>() / n;
    out.mean_bias = out.frames.iter().map(|f| f.error.bias).sum::<f64>() / n;
    out.mean_flip = out.frames.iter().map(|f| f.flip).sum::<f64>() / n;
    let pairs: Vec<&FrameMetrics> = out.frames.iter().filter(|f| f.flicker.is_some()).collect();
    if !pairs.is_empty() {
        out.flicker_f1 =
            pairs.iter().map(|f| f.flicker.unwrap_or(0.0)).sum::<f64>() / pairs.len() as f64;
        out.flicker_rms = (pairs
            .iter()
            .map(|f| f.flicker_rms.unwrap_or(0.0).powi(2))
            .sum::<f64>()
            / pairs.len() as f64)
            .sqrt();
    }
    out.temporal_variance = sum_e
        .iter()
        .zip(&sum_e2)
        .map(|(s, s2)| (s2 / n - (s / n).powi(2)).max(0.0))
        .sum::<f64>()
        / np as f64;
    out.temporal_bias = sum_e.iter().map(|s| (s / n).powi(2)).sum::<f64>() / np as f64;
    Ok(out)
}

/// A folder of frames `frame_FFFF.exr` or `.png`: frame numbers and paths, in order
/// (EXR preferred where both exist).
pub fn list_frames(dir: &std::path::Path) -> Result<Vec<(u32, std::path::PathBuf)>> {
    use anyhow::Context;
    let mut found = std::collections::BTreeMap::new();
    for entry in std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read the folder", dir.display()))?
    {
        let path = entry?.path();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let Some(rest) = name.strip_prefix("frame_") else {
            continue;
        };
        let Some((num, ext)) = rest.split_once('.') else {
            continue;
        };
        let Ok(f) = num.parse::<u32>() else { continue };
        match ext {
            "exr" => {
                found.insert(f, path);
            }
            "png" => {
                found.entry(f).or_insert(path);
            }
            _ => {}
        }
    }
    if found.is_empty() {
        bail!(
            "{}: no frame_FFFF.exr or frame_FFFF.png files",
            dir.display()
        );
    }
    Ok(found.into_iter().collect())
}

/// Reads the frames of `test` and `reference` folders matched by frame number.
pub fn read_pair(
    test: &std::path::Path,
    reference: &std::path::Path,
) -> Result<(Vec<u32>, Vec<Hdr>, Vec<Hdr>)> {
    let t = list_frames(test)?;
    let r: std::collections::BTreeMap<u32, std::path::PathBuf> =
        list_frames(reference)?.into_iter().collect();
    let mut numbers = Vec::new();
    let (mut ti, mut ri) = (Vec::new(), Vec::new());
    for (f, path) in t {
        let Some(rp) = r.get(&f) else {
            bail!(
                "{}: frame {f} has no counterpart in {}",
                path.display(),
                reference.display()
            );
        };
        let a = Hdr::read(&path)?;
        let b = Hdr::read(rp)?;
        if (a.width, a.height) != (b.width, b.height) {
            bail!(
                "{}: {}x{} but {} is {}x{}",
                path.display(),
                a.width,
                a.height,
                rp.display(),
                b.width,
                b.height
            );
        }
        numbers.push(f);
        ti.push(a);
        ri.push(b);
    }
    if numbers.windows(2).any(|w| w[1] != w[0] + 1) {
        bail!(
            "{}: the frames are not consecutive ({:?}...); flicker needs consecutive frames",
            test.display(),
            &numbers[..numbers.len().min(8)]
        );
    }
    Ok((numbers, ti, ri))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn img(v: &[f32]) -> Hdr {
        Hdr {
            width: v.len() as u32,
            height: 1,
            data: v.iter().map(|&x| Vec3::splat(x)).collect(),
        }
    }

    #[test]
    fn constant_sequence_has_no_flicker() {
        let r: Vec<Hdr> = (0..5).map(|_| img(&[0.2, 0.5, 0.9])).collect();
        let t: Vec<Hdr> = (0..5).map(|_| img(&[0.25, 0.4, 1.0])).collect();
        let m = sequence(&[0, 1, 2, 3, 4], &t, &r).unwrap();
        assert_eq!(m.flicker_f1, 0.0);
        assert_eq!(m.temporal_variance, 0.0);
        assert!(m.temporal_bias > 0.0 && m.mean_rel_mse > 0.0 && m.mean_flip > 0.0);
    }

    #[test]
    fn alternating_by_d_has_flicker_2d() {
        let d = 0.1f32;
        let r: Vec<Hdr> = (0..6).map(|_| img(&[0.3, 0.6])).collect();
        let t: Vec<Hdr> = (0..6)
            .map(|i| {
                let s = if i % 2 == 0 { d } else { -d };
                img(&[0.3 + s, 0.6 + s])
            })
            .collect();
        let m = sequence(&[0, 1, 2, 3, 4, 5], &t, &r).unwrap();
        assert!(
            (m.flicker_f1 - 2.0 * d as f64).abs() < 1e-6,
            "{}",
            m.flicker_f1
        );
        assert!((m.flicker_rms - 2.0 * d as f64).abs() < 1e-6);
        // Var_t of +-d is d^2, and the mean error is 0.
        assert!((m.temporal_variance - (d * d) as f64).abs() < 1e-6 && m.temporal_bias < 1e-12);
    }

    #[test]
    fn gradient_moving_with_the_reference_is_perfect() {
        let frames: Vec<Hdr> = (0..8)
            .map(|t| {
                img(&(0..16)
                    .map(|x| ((x + t) % 16) as f32 / 16.0)
                    .collect::<Vec<_>>())
            })
            .collect();
        let m = sequence(&(0..8).collect::<Vec<_>>(), &frames, &frames.clone()).unwrap();
        assert_eq!(
            (m.flicker_f1, m.mean_rel_mse, m.temporal_bias, m.mean_flip),
            (0.0, 0.0, 0.0, 0.0)
        );
        // The same gradient against a still reference does flicker.
        let still: Vec<Hdr> = (0..8).map(|_| frames[0].clone()).collect();
        assert!(
            sequence(&(0..8).collect::<Vec<_>>(), &frames, &still)
                .unwrap()
                .flicker_f1
                > 0.01
        );
    }

    #[test]
    fn known_errors() {
        let r = Hdr {
            width: 2,
            height: 1,
            data: vec![Vec3::splat(1.0), Vec3::splat(0.0)],
        };
        let t = Hdr {
            width: 2,
            height: 1,
            data: vec![Vec3::splat(1.5), Vec3::splat(0.1)],
        };
        let e = frame_error(&t, &r).unwrap();
        // ((0.25 / 1.01) + (0.01 / 0.01)) / 2
        assert!(
            (e.rel_mse - (0.25 / 1.01 + 1.0) / 2.0).abs() < 1e-6,
            "{e:?}"
        );
        assert!((e.rmse - ((0.25 + 0.01) / 2.0f64).sqrt()).abs() < 1e-6);
        assert!((e.bias - 0.3).abs() < 1e-6);
        assert!(frame_error(&t, &Hdr::new(3, 1)).is_err());
        assert_eq!(frame_error(&r, &r).unwrap(), FrameError::default());
    }
}
