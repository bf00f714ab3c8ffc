//! Stage 8: output. Frame files, progress bars, and the run record (`run.json`).

pub mod charts;
pub mod compare;
pub mod html;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::Path;

use crate::image::Hdr;

/// `frame_FFFF` for frame number `f`.
pub fn frame_stem(f: u32) -> String {
    format!("frame_{f:04}")
}

/// Writes `DIR/frame_FFFF.exr` (linear) and `DIR/frame_FFFF.png` (tone-mapped).
pub fn write_frame(dir: &Path, f: u32, img: &Hdr, exposure: f32) -> Result<()> {
    let stem = frame_stem(f);
    img.write_exr(&dir.join(format!("{stem}.exr")))?;
    img.write_png(&dir.join(format!("{stem}.png")), exposure)
}

/// Writes a serializable record as pretty JSON, atomically.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let mut s = serde_json::to_string_pretty(value).context("serializing the run record")?;
    s.push('\n');
    crate::image::write_bytes(path, s.as_bytes())
}

/// Makes sure `dir` exists and is writable, before any rendering starts.
pub fn prepare_out_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the output folder", dir.display()))?;
    let probe = dir.join(format!(".irad-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .with_context(|| format!("{}: the output folder is not writable", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template(
            "{msg:>12} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})",
        )
        .expect("static template"),
    );
    pb.set_message(what.to_string());
    pb
}

/// Writes an animated GIF of 8-bit RGB frames at `fps`.
pub fn write_gif(path: &Path, frames: &[image::RgbImage], fps: f32) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    crate::image::atomic_write(path, |tmp| {
        let file = std::fs::File::create(tmp)?;
        let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
        enc.set_repeat(Repeat::Infinite)?;
        let delay = image::Delay::from_numer_denom_ms(1000, fps.max(1.0) as u32);
        for f in frames {
            let rgba = image::DynamicImage::ImageRgb8(f.clone()).to_rgba8();
            enc.encode_frame(image::Frame::from_parts(rgba, 0, 0, delay))?;
        }
        Ok(())
    })
}
