//! `irad metrics TEST REFERENCE`: error and flicker of one image sequence against another.

use crate::report;
use anyhow::Result;
use std::path::Path;

/// Writes per-frame metrics as CSV.
pub fn metrics_csv(m: &crate::metrics::SequenceMetrics) -> String {
    let mut s = String::from("frame,rel_mse,rmse,bias,rel_bias,flicker,flicker_rms,flip\n");
    for f in &m.frames {
        let o = |x: Option<f64>| x.map(|v| format!("{v:.8}")).unwrap_or_default();
        s += &format!(
            "{},{:.8},{:.8},{:.8},{:.8},{},{},{:.6}\n",
            f.frame,
            f.error.rel_mse,
            f.error.rmse,
            f.error.bias,
            f.error.rel_bias,
            o(f.flicker),
            o(f.flicker_rms),
            f.flip
        );
    }
    s
}

/// Error and flicker of one image sequence against another, printed and written.
pub fn metrics(
    test: &Path,
    reference: &Path,
    out: Option<&Path>,
) -> Result<crate::metrics::SequenceMetrics> {
    let (numbers, t, r) = crate::metrics::read_pair(test, reference)?;
    let m = crate::metrics::sequence(&numbers, &t, &r)?;
    crate::outln!(
        "{:>6} {:>10} {:>10} {:>10} {:>10} {:>8}",
        "frame",
        "relMSE",
        "RMSE",
        "bias",
        "flicker",
        "FLIP"
    )?;
    for f in &m.frames {
        crate::outln!(
            "{:>6} {:>10.5} {:>10.5} {:>+10.5} {:>10} {:>8.4}",
            f.frame,
            f.error.rel_mse,
            f.error.rmse,
            f.error.bias,
            f.flicker
                .map(|v| format!("{v:.5}"))
                .unwrap_or_else(|| "-".into()),
            f.flip
        )?;
    }
    crate::outln!(
        "mean relMSE {:.5}, RMSE {:.5}, bias {:+.5}, FLIP {:.4}; flicker F1 {:.5} (RMS {:.5}); temporal variance {:.3e}, temporal bias^2 {:.3e}",
        m.mean_rel_mse, m.mean_rmse, m.mean_bias, m.mean_flip, m.flicker_f1, m.flicker_rms, m.temporal_variance, m.temporal_bias
    )?;
    let dir = out.unwrap_or(test);
    report::prepare_out_dir(dir)?;
    report::write_json(&dir.join("metrics.json"), &m)?;
    crate::image::write_bytes(&dir.join("metrics.csv"), metrics_csv(&m).as_bytes())?;
    crate::outln!("wrote {}/metrics.json and metrics.csv", dir.display())?;
    Ok(m)
}

/// `irad metrics ... --scene S`: motion-compensated flicker of the frames of scene `S`, seen
/// from `camera` when the frames were rendered with `--camera`.
pub fn warped(
    test: &Path,
    reference: &Path,
    scene: &str,
    fps: f32,
    camera: Option<&crate::config::CameraSpec>,
    out: Option<&Path>,
    options: &crate::scene::load::LoadOptions,
) -> Result<()> {
    let (numbers, t, r) = crate::metrics::read_pair(test, reference)?;
    let mut scene = crate::scene::builtin::load_any_with(scene, options)?;
    if let Some(c) = camera {
        c.apply(&mut scene)?;
    }
    let w = crate::metrics::warp::for_scene(&scene, fps, &numbers, &t, &r)?;
    crate::outln!(
        "warped flicker F1 {:.5} ({:.1}% of pixels kept)",
        w.f1,
        100.0 * w.kept
    )?;
    let dir = out.unwrap_or(test);
    report::write_json(&dir.join("warped.json"), &w)?;
    crate::outln!("wrote {}/warped.json", dir.display())?;
    Ok(())
}
