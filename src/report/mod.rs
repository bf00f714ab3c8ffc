//! Stage 8: output. Frame files, progress bars, and the run record (`run.json`).

pub mod charts;
pub mod heatmap;
pub mod html;
mod progress;
mod run_dir;

pub use progress::Progress;
pub(crate) use run_dir::parse_temporary;
pub use run_dir::{prepare_run_dir, run_files, RunDir, MANIFEST};

use anyhow::{Context, Result};
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
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!(
            "{}: is a file, not a folder (the output goes into a folder of frames; name a folder)",
            dir.display()
        );
    }
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the output folder", dir.display()))?;
    let probe = dir.join(format!(".irad-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .with_context(|| format!("{}: the output folder is not writable", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// `n` followed by `one` or `many`: "1 frame", "2 frames".
pub fn count(n: impl Into<u64>, one: &str, many: &str) -> String {
    let n = n.into();
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Progress on stderr: a bar on a terminal, plain lines elsewhere ([`Progress`]).
pub fn progress(len: u64, what: &str) -> Progress {
    Progress::new(len, what)
}

/// Writes an animated GIF of 8-bit RGB frames at `fps`.
pub fn write_gif(path: &Path, frames: &[image::RgbImage], fps: f32) -> Result<()> {
    let mut gif = GifStream::create(path, fps)?;
    for f in frames {
        gif.push(f)?;
    }
    gif.finish()
}

/// An animated GIF written frame by frame, so a long render holds no frames in memory. It
/// is written to a temporary name and moved into place by [`GifStream::finish`]; dropped
/// unfinished, it leaves nothing behind.
pub struct GifStream {
    path: std::path::PathBuf,
    tmp: std::path::PathBuf,
    encoder: Option<image::codecs::gif::GifEncoder<std::io::BufWriter<std::fs::File>>>,
    /// The same file, to sync once the encoder has written the trailer and been dropped.
    file: std::fs::File,
    delay: image::Delay,
}

impl GifStream {
    pub fn create(path: &Path, fps: f32) -> Result<GifStream> {
        use image::codecs::gif::{GifEncoder, Repeat};
        let tmp = path.with_file_name(format!(
            ".{}.tmp-{}.gif",
            path.file_name().unwrap_or_default().to_string_lossy(),
            std::process::id()
        ));
        let file = std::fs::File::create(&tmp)
            .with_context(|| format!("{}: cannot write", path.display()))?;
        let same = file.try_clone()?;
        let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
        enc.set_repeat(Repeat::Infinite)?;
        Ok(GifStream {
            path: path.to_path_buf(),
            tmp,
            encoder: Some(enc),
            file: same,
            delay: image::Delay::from_numer_denom_ms(1000, fps.round().max(1.0) as u32),
        })
    }

    /// Appends one frame.
    pub fn push(&mut self, frame: &image::RgbImage) -> Result<()> {
        let rgba = image::DynamicImage::ImageRgb8(frame.clone()).to_rgba8();
        self.encoder
            .as_mut()
            .expect("present until finish")
            .encode_frame(image::Frame::from_parts(rgba, 0, 0, self.delay))
            .with_context(|| format!("{}: cannot write", self.path.display()))
    }

    /// Flushes the file and moves it into place.
    pub fn finish(mut self) -> Result<()> {
        // Dropping the encoder writes the GIF trailer and flushes the buffer.
        drop(self.encoder.take());
        self.file
            .sync_all()
            .with_context(|| format!("{}: cannot write", self.path.display()))?;
        std::fs::rename(&self.tmp, &self.path)
            .with_context(|| format!("{}: cannot move into place", self.path.display()))
    }
}

impl Drop for GifStream {
    fn drop(&mut self) {
        if self.encoder.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Whether `name` is one of the files `irad render` or `irad reference` writes into its
/// output folder: `frame_FFFF.exr|png`, `frame_FFFF_direct|indirect.exr|png`, `preview.gif`,
/// `run.json`, `frames.jsonl`.
pub fn is_run_output(name: &str) -> bool {
    if matches!(name, "preview.gif" | "run.json" | "frames.jsonl") {
        return true;
    }
    let Some(stem) = name
        .strip_suffix(".exr")
        .or_else(|| name.strip_suffix(".png"))
    else {
        return false;
    };
    let Some(rest) = stem.strip_prefix("frame_") else {
        return false;
    };
    let digits = rest
        .strip_suffix("_direct")
        .or_else(|| rest.strip_suffix("_indirect"))
        .unwrap_or(rest);
    digits.len() >= 4 && digits.bytes().all(|b| b.is_ascii_digit())
}

/// Appends one JSON record a line to `path` (JSON Lines): a long run's per-frame records are
/// written as they come, never rewritten.
pub struct JsonLines {
    file: std::io::BufWriter<std::fs::File>,
    path: std::path::PathBuf,
}

impl JsonLines {
    pub fn create(path: &Path) -> Result<JsonLines> {
        let file = std::fs::File::create(path)
            .with_context(|| format!("{}: cannot write", path.display()))?;
        Ok(JsonLines {
            file: std::io::BufWriter::new(file),
            path: path.to_path_buf(),
        })
    }

    pub fn push(&mut self, value: &impl Serialize) -> Result<()> {
        use std::io::Write;
        serde_json::to_writer(&mut self.file, value)
            .map_err(anyhow::Error::from)
            .and_then(|_| Ok(self.file.write_all(b"\n")?))
            .and_then(|_| Ok(self.file.flush()?))
            .with_context(|| format!("{}: cannot write", self.path.display()))
    }
}

/// The resident memory of this process in bytes (Linux; None elsewhere).
pub fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_irads_output_shapes_count_as_run_outputs() {
        for yes in [
            "frame_0000.exr",
            "frame_0012.png",
            "frame_12345.exr",
            "frame_0003_direct.png",
            "frame_0003_indirect.exr",
            "preview.gif",
            "run.json",
            "frames.jsonl",
        ] {
            assert!(is_run_output(yes), "{yes}");
        }
        for no in [
            "frame_12.exr",
            "frame_0001.jpg",
            "frame_abcd.png",
            "frame_0001_other.png",
            "notes.txt",
            "myframe_0001.png",
            "metrics.json",
        ] {
            assert!(!is_run_output(no), "{no}");
        }
    }
}
