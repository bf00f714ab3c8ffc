//! Argument types shared by the commands: frame ranges, image sizes, and the scene options.

use anyhow::{bail, Result};
use clap::Args;

/// A half-open frame range `A..B`, or a single frame `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frames {
    pub start: u32,
    pub end: u32,
}

impl Frames {
    pub fn iter(&self) -> std::ops::Range<u32> {
        self.start..self.end
    }
    pub fn len(&self) -> u32 {
        self.end - self.start
    }
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}

impl std::str::FromStr for Frames {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let num = |x: &str| {
            x.trim().parse::<u32>().map_err(|_| {
                format!("'{s}' is not a frame range: use A..B (half-open, 0..24 is 24 frames) or N")
            })
        };
        let (start, end) = match s.split_once("..") {
            Some((a, b)) => (num(a)?, num(b)?),
            None => {
                let n = num(s)?;
                (n, n + 1)
            }
        };
        if end <= start {
            return Err(format!(
                "frame range '{s}' is empty (A..B renders frames A to B-1)"
            ));
        }
        if end - start > 100_000 {
            return Err(format!("frame range '{s}' has more than 100000 frames"));
        }
        Ok(Frames { start, end })
    }
}

/// An image size `WxH`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

/// The largest width or height any command accepts.
pub const MAX_SIZE: u32 = 8192;

impl std::str::FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("'{s}' is not an image size: use WxH, e.g. 256x256");
        let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let (width, height) = (
            w.trim().parse::<u32>().map_err(|_| bad())?,
            h.trim().parse::<u32>().map_err(|_| bad())?,
        );
        if width == 0 || height == 0 || width > MAX_SIZE || height > MAX_SIZE {
            return Err(format!(
                "image size {s} is out of range: each side must be 1 to {MAX_SIZE}"
            ));
        }
        Ok(Size { width, height })
    }
}

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// Options every rendering command shares.
#[derive(Args, Clone, Debug)]
pub struct SceneOpts {
    /// A built-in scene name (see `irad scenes`) or a .gltf/.glb path
    pub scene: Option<String>,
    /// Image size WxH
    #[arg(long, default_value = "256x256")]
    pub size: Size,
    /// Frames: A..B (half-open) or a single frame N; frame f is at time f / fps
    /// [default: render: the whole animation; others: 0]
    #[arg(long)]
    pub frames: Option<Frames>,
    /// Frames per second of the animation
    #[arg(long, default_value_t = 24.0)]
    pub fps: f32,
    /// Random seed; the same seed gives the same frames
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl SceneOpts {
    pub fn validate(&self) -> Result<()> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= 1000.0) {
            bail!("--fps {} is out of range (0 to 1000)", self.fps);
        }
        Ok(())
    }
    /// The scene named, or the command's default.
    pub fn scene_or<'a>(&'a self, default: &'a str) -> &'a str {
        self.scene.as_deref().unwrap_or(default)
    }
    /// The frames named, or all frames of an animation of `duration` seconds (at least one).
    pub fn frames_or_all(&self, duration: f32) -> Frames {
        self.frames.unwrap_or(Frames {
            start: 0,
            end: ((duration * self.fps).round() as u32).max(1),
        })
    }
    /// The frames named, or frame 0.
    pub fn frames_or_first(&self) -> Frames {
        self.frames.unwrap_or(Frames { start: 0, end: 1 })
    }
    pub fn time(&self, f: u32) -> f32 {
        f as f32 / self.fps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_and_sizes_parse_as_documented() {
        assert_eq!("0..24".parse::<Frames>().unwrap().len(), 24);
        assert_eq!("7".parse::<Frames>().unwrap(), Frames { start: 7, end: 8 });
        assert!("5..5".parse::<Frames>().unwrap_err().contains("empty"));
        assert!("a..b".parse::<Frames>().is_err());
        assert_eq!(
            "256x128".parse::<Size>().unwrap(),
            Size {
                width: 256,
                height: 128
            }
        );
        assert!("0x10".parse::<Size>().unwrap_err().contains("out of range"));
        assert!("100000x10".parse::<Size>().is_err());
        assert!("256".parse::<Size>().is_err());
    }
}
