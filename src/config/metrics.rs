//! `irad metrics`: the settings of measuring one image sequence against another.

use super::CameraSpec;
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::PathBuf;

/// `irad metrics TEST REFERENCE`: error and flicker of a folder of frames against another.
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Metrics {
    /// Folder of test frames
    pub test: PathBuf,
    /// Folder of reference frames
    pub reference: PathBuf,
    /// Where metrics.json and metrics.csv go [default: the test folder]
    #[cfg_attr(feature = "cli", arg(long))]
    pub out: Option<PathBuf>,
    /// The scene the frames show (built-in name or glTF file): also the motion-compensated
    /// flicker (warped.json)
    #[cfg_attr(feature = "cli", arg(long))]
    pub scene: Option<String>,
    /// With --scene: frames per second (frame f is at time f / fps)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Metrics::default().fps, allow_hyphen_values = true))]
    pub fps: f32,
    /// With --scene: the --camera EYE:TARGET:FOV the frames were rendered with (the
    /// motion warp must see the scene from the same camera)
    #[cfg_attr(
        feature = "cli",
        arg(long, allow_hyphen_values = true, value_name = "EYE:TARGET:FOV")
    )]
    pub camera: Option<CameraSpec>,
    /// With --scene: let a glTF scene read files outside its own folder
    #[cfg_attr(feature = "cli", arg(long))]
    pub allow_outside_paths: bool,
}

impl Default for Metrics {
    fn default() -> Self {
        Metrics {
            test: PathBuf::new(),
            reference: PathBuf::new(),
            out: None,
            scene: None,
            fps: 24.0,
            camera: None,
            allow_outside_paths: false,
        }
    }
}

impl Metrics {
    /// Checks every setting that does not need the frames.
    pub fn validate(&self) -> Result<()> {
        super::check::float("`fps`", self.fps, 0.0, true, 1000.0)?;
        if self.camera.is_some() && self.scene.is_none() {
            bail!("`camera` needs `scene`: it is the camera the scene's frames were rendered with");
        }
        match &self.camera {
            Some(c) => c.validate(),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_checked_naming_the_setting() {
        assert!(Metrics::default().validate().is_ok());
        let e = Metrics {
            fps: 0.0,
            ..Default::default()
        };
        assert!(e
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("`fps` 0 is out of range"));
        let e = Metrics {
            camera: Some("0,1,3:0,1,0:40".parse().unwrap()),
            ..Default::default()
        };
        assert!(e
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("`camera` needs `scene`"));
    }
}
