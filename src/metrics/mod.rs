//! Error and flicker metrics (DESIGN.md "Metrics"). Per frame, I = test, R = reference,
//! e = lum(I) - lum(R).

use crate::image::Hdr;
use crate::math::luminance;
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
