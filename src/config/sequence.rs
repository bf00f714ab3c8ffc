//! What every rendering command renders: the frames, the image size, the camera, the scene
//! and the sequence that names them.

use super::*;
use crate::scene::Scene;
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// A half-open frame range `A..B`, or a single frame `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Frames {
    pub start: u32,
    pub end: u32,
}

/// The most frames one range may hold.
pub const MAX_FRAMES: u32 = 100_000;
/// A render without `--frames` renders at most this many frames of a long animation.
pub const DEFAULT_FRAME_CAP: u32 = 2400;

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
                format!("'{s}' is not a frame range: use A..B (half-open, 0..24 is 24 frames) or N (0 to {})", u32::MAX - 1)
            })
        };
        let (start, end) = match s.split_once("..") {
            Some((a, b)) => (num(a)?, num(b)?),
            None => {
                let n = num(s)?;
                let end = n
                    .checked_add(1)
                    .ok_or_else(|| format!("frame {n} is past the last frame {}", u32::MAX - 1))?;
                (n, end)
            }
        };
        if end <= start {
            return Err(format!(
                "frame range '{s}' is empty (A..B renders frames A to B-1)"
            ));
        }
        if end - start > MAX_FRAMES {
            return Err(format!(
                "frame range '{s}' has more than {MAX_FRAMES} frames"
            ));
        }
        Ok(Frames { start, end })
    }
}

impl std::fmt::Display for Frames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

/// An image size `WxH`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

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

impl Serialize for Size {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

/// `--camera EYE:TARGET:FOV`: a camera at `EYE` looking at `TARGET` with a vertical field of
/// view of `FOV` degrees, e.g. `0,0,3.9:0,0,0:39.3` (points as `x,y,z`, in the scene's units).
/// It replaces the scene's camera, animated or not, for every frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    pub eye: glam::Vec3,
    pub target: glam::Vec3,
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
}

impl std::str::FromStr for CameraSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = |why: String| {
            format!("'{s}' is not EYE:TARGET:FOV ({why}); e.g. 0,0,3.9:0,0,0:39.3 (points x,y,z; vertical field of view in degrees)")
        };
        let parts: Vec<&str> = s.split(':').collect();
        let [eye, target, fov] = parts[..] else {
            return Err(bad(format!(
                "{} parts separated by ':', not 3",
                parts.len()
            )));
        };
        let point = |what: &str, p: &str| {
            let v: Vec<&str> = p.split(',').collect();
            if v.len() != 3 {
                return Err(bad(format!("the {what} '{p}' is not three numbers x,y,z")));
            }
            let mut out = [0f32; 3];
            for (o, x) in out.iter_mut().zip(&v) {
                *o = x
                    .trim()
                    .parse()
                    .map_err(|_| bad(format!("'{x}' in the {what} is not a number")))?;
            }
            Ok(glam::Vec3::from_array(out))
        };
        Ok(CameraSpec {
            eye: point("eye", eye)?,
            target: point("target", target)?,
            fov_deg: fov
                .trim()
                .parse()
                .map_err(|_| bad(format!("the field of view '{fov}' is not a number")))?,
        })
    }
}

impl std::fmt::Display for CameraSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (e, t) = (self.eye, self.target);
        write!(
            f,
            "{},{},{}:{},{},{}:{}",
            e.x, e.y, e.z, t.x, t.y, t.z, self.fov_deg
        )
    }
}

impl Serialize for CameraSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl CameraSpec {
    /// Finite points within the loader's coordinate limit, eye apart from target, a field of
    /// view strictly between 0 and 180 degrees (within what the renderer takes).
    pub fn validate(&self) -> Result<()> {
        let lim = crate::scene::load::MAX_COORD;
        for (what, p) in [("eye", self.eye), ("target", self.target)] {
            if !p.is_finite() {
                bail!("`camera` {self}: the {what} is not a finite point");
            }
            if p.abs().max_element() > lim {
                bail!("`camera` {self}: the {what} is farther than {lim:e} from the origin");
            }
        }
        let d = (self.target - self.eye).length();
        if d <= 1e-6 * self.eye.abs().max_element().max(1.0) {
            bail!("`camera` {self}: the eye and the target are the same point");
        }
        let (lo, hi) = crate::scene::load::FOV_RANGE;
        let fov = self.fov_deg;
        if !(fov.is_finite() && fov >= lo.to_degrees() && fov <= hi.to_degrees()) {
            bail!(
                "`camera` {self}: the field of view {fov} degrees is out of range: it must be between 0 and 180 degrees ({:.2} to {:.1})",
                lo.to_degrees(),
                hi.to_degrees()
            );
        }
        Ok(())
    }

    /// Puts this camera in `scene` in place of its own (for every frame).
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        self.validate()?;
        scene
            .set_camera(self.eye, self.target, self.fov_deg.to_radians())
            .map_err(|e| anyhow::anyhow!("`camera` {self}: {e}"))
    }
}

/// `--environment`: what lights a scene from where rays meet no geometry.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentChoice {
    /// The default sky: a constant radiance
    /// ([`crate::scene::environment::SKY_RADIANCE`]) in every direction.
    Sky,
    /// No environment: a scene without emitters is refused, as before irad had one.
    None,
    /// An equirectangular radiance map (.hdr or .exr), read wherever it is (the user named it).
    File(PathBuf),
}

impl std::str::FromStr for EnvironmentChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "sky" => EnvironmentChoice::Sky,
            "none" => EnvironmentChoice::None,
            "" => return Err("an empty --environment: use sky, none or a .hdr/.exr file".into()),
            _ => EnvironmentChoice::File(PathBuf::from(s)),
        })
    }
}

impl std::fmt::Display for EnvironmentChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EnvironmentChoice::Sky => f.write_str("sky"),
            EnvironmentChoice::None => f.write_str("none"),
            EnvironmentChoice::File(p) => write!(f, "{}", p.display()),
        }
    }
}

impl Serialize for EnvironmentChoice {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl EnvironmentChoice {
    /// Puts this environment in `scene`: `sky` or a map for any scene; `none` takes away the
    /// default sky the loader gave a scene without emitters, and so refuses it. Errors name
    /// the setting (`` `environment` ``) and say what is wrong with the file.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        use crate::scene::Environment;
        match self {
            EnvironmentChoice::Sky => scene.environment = Some(Arc::new(Environment::sky())),
            EnvironmentChoice::None => {
                if let Some(why) = &scene.unlit {
                    bail!("{why} (`environment` none: no default sky)");
                }
                scene.environment = None;
            }
            EnvironmentChoice::File(p) => {
                let env = crate::scene::load::read_environment(p)
                    .map_err(|e| anyhow::anyhow!("`environment` {e}"))?;
                scene.environment = Some(Arc::new(env));
            }
        }
        Ok(())
    }
}

/// Loads a built-in scene or a glTF file (nothing outside its folder) and prints its warnings.
pub fn load_scene(spec: &str) -> Result<Scene> {
    load_scene_with(spec, &Default::default())
}

/// Loads a built-in scene or a glTF file and prints its warnings.
pub fn load_scene_with(spec: &str, options: &crate::scene::load::LoadOptions) -> Result<Scene> {
    let scene = crate::scene::builtin::load_any_with(spec, options)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// The sequence every rendering command renders: scene, image size, frames, rate and seed.
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Sequence {
    /// A built-in scene name (see `irad scenes`) or a .gltf/.glb path [default: the command's]
    pub scene: Option<String>,
    /// Image size WxH
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Sequence::default().size))]
    pub size: Size,
    /// Frames: A..B (half-open) or a single frame N; frame f is at time f / fps
    /// [default: render and compare: the whole animation (at most 2400 frames); others: 0]
    #[cfg_attr(feature = "cli", arg(long))]
    pub frames: Option<Frames>,
    /// Frames per second of the animation
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Sequence::default().fps, allow_hyphen_values = true))]
    pub fps: f32,
    /// Random seed; the same seed gives the same frames
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Sequence::default().seed, allow_hyphen_values = true))]
    pub seed: u64,
    /// Camera EYE:TARGET:FOV, e.g. 0,0,3.9:0,0,0:39.3 (points x,y,z in scene units, vertical
    /// field of view in degrees): replaces the scene's camera, animated or not, in every frame
    #[cfg_attr(
        feature = "cli",
        arg(long, allow_hyphen_values = true, value_name = "EYE:TARGET:FOV")
    )]
    pub camera: Option<CameraSpec>,
    /// Let a glTF scene read buffer and image files outside its own folder (absolute URIs,
    /// `..`, symbolic links leading out); refused by default
    #[cfg_attr(feature = "cli", arg(long))]
    pub allow_outside_paths: bool,
    /// Light from where rays meet no geometry: `sky` (a uniform radiance of 1 W/m^2/sr: an
    /// unoccluded white surface under it is 1), a .hdr or .exr equirectangular map (+Y up,
    /// the centre column toward -Z), or `none`
    /// [default: none, or sky for a scene that nothing else lights (with a note)]
    #[cfg_attr(feature = "cli", arg(long, value_name = "sky|none|FILE"))]
    pub environment: Option<EnvironmentChoice>,
}

impl Default for Sequence {
    fn default() -> Self {
        Sequence {
            scene: None,
            size: Size {
                width: 256,
                height: 256,
            },
            frames: None,
            fps: 24.0,
            seed: 1,
            camera: None,
            allow_outside_paths: false,
            environment: None,
        }
    }
}

impl Sequence {
    /// The path tracer's settings for this sequence's size and seed and a sampling.
    pub fn reference_settings(
        &self,
        s: crate::reference::Sampling,
    ) -> crate::reference::ReferenceSettings {
        crate::reference::ReferenceSettings {
            width: self.size.width,
            height: self.size.height,
            spp: s.spp,
            seed: self.seed,
            rr_cap_depth: s.rr_cap_depth,
        }
    }

    pub fn validate(&self) -> Result<()> {
        check::float("`fps`", self.fps, 0.0, true, 1000.0)?;
        match &self.camera {
            Some(c) => c.validate(),
            None => Ok(()),
        }
    }
    /// Loads the scene named (or `default`), prints its warnings, and puts `--camera` in it.
    pub fn load_scene(&self, default: &str) -> Result<Scene> {
        self.prepare_scene(load_scene_with(
            self.scene_or(default),
            &self.load_options(),
        )?)
    }
    /// Puts `--camera` and `--environment` in a loaded scene (what [`Sequence::load_scene`]
    /// does after loading; a library caller holding a scene calls it directly).
    pub fn prepare_scene(&self, mut scene: Scene) -> Result<Scene> {
        if let Some(c) = &self.camera {
            c.apply(&mut scene)?;
        }
        match &self.environment {
            Some(e) => e.apply(&mut scene)?,
            None => {
                if let Some(why) = &scene.unlit {
                    eprintln!(
                        "note: {why}: lit by the default environment, a uniform sky of radiance {} (--environment chooses another, --environment none refuses the scene)",
                        crate::scene::environment::SKY_RADIANCE
                    );
                }
            }
        }
        Ok(scene)
    }
    /// How the scene's files are read.
    pub fn load_options(&self) -> crate::scene::load::LoadOptions {
        crate::scene::load::LoadOptions {
            allow_outside_paths: self.allow_outside_paths,
        }
    }
    /// The scene named, or `default`.
    pub fn scene_or<'a>(&'a self, default: &'a str) -> &'a str {
        self.scene.as_deref().unwrap_or(default)
    }
    /// The frames named, or all frames of an animation of `duration` seconds (at least one,
    /// at most [`DEFAULT_FRAME_CAP`], with a note when capped).
    pub fn frames_or_all(&self, duration: f32) -> (Frames, Option<String>) {
        if let Some(f) = self.frames {
            return (f, None);
        }
        let all = (duration as f64 * self.fps as f64).round().max(1.0);
        if all > DEFAULT_FRAME_CAP as f64 {
            let note = format!(
                "the animation lasts {duration:.1} s ({all:.0} frames at {} fps): rendering its first {DEFAULT_FRAME_CAP} frames; --frames A..B chooses others",
                self.fps
            );
            return (
                Frames {
                    start: 0,
                    end: DEFAULT_FRAME_CAP,
                },
                Some(note),
            );
        }
        (
            Frames {
                start: 0,
                end: all as u32,
            },
            None,
        )
    }
    /// The frames named, or frame 0.
    pub fn frames_or_first(&self) -> Frames {
        self.frames.unwrap_or(Frames { start: 0, end: 1 })
    }
    /// The time of frame `f`, in seconds.
    pub fn time(&self, f: u32) -> f32 {
        (f as f64 / self.fps as f64) as f32
    }
}
