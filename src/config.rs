//! Every command's settings, in the library: the sequence to render ([`Sequence`]), the
//! sampler ([`SamplerConfig`]), the GPU's quality knobs ([`Quality`]), and one type per
//! command ([`Render`], [`Reference`], [`Compare`], [`Bench`]). Each has `Default` (the one
//! place a default lives: the CLI's help reads it from here) and one `validate()` that every
//! command calls before it renders anything. A Rust program fills these and calls
//! [`crate::render::render`] and friends; `irad`'s CLI only maps flags onto them.
//!
//! Every numeric value goes through [`check`]: NaN, infinity, sign and range, with a message
//! that names the flag as the user typed it (`--exposure NaN is not a finite number`).

use crate::gpu::BackendChoice;
use crate::scene::Scene;
pub use crate::vpl::sampler::knobs::{Knob, SamplerKnobs, KNOBS};
use crate::vpl::sampler::SamplerKind;
use anyhow::{bail, Result};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;

pub use crate::check;

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
                bail!("--camera {self}: the {what} is not a finite point");
            }
            if p.abs().max_element() > lim {
                bail!("--camera {self}: the {what} is farther than {lim:e} from the origin");
            }
        }
        let d = (self.target - self.eye).length();
        if d <= 1e-6 * self.eye.abs().max_element().max(1.0) {
            bail!("--camera {self}: the eye and the target are the same point");
        }
        let (lo, hi) = crate::scene::load::FOV_RANGE;
        let fov = self.fov_deg;
        if !(fov.is_finite() && fov >= lo.to_degrees() && fov <= hi.to_degrees()) {
            bail!(
                "--camera {self}: the field of view {fov} degrees is out of range: it must be between 0 and 180 degrees ({:.2} to {:.1})",
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
            .map_err(|e| anyhow::anyhow!("--camera {self}: {e}"))
    }
}

/// Loads a built-in scene or a glTF file and prints its warnings.
pub fn load_scene(spec: &str) -> Result<Scene> {
    let scene = crate::scene::builtin::load_any(spec)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// The sequence every rendering command renders: scene, image size, frames, rate and seed.
#[derive(Args, Clone, Debug, Serialize)]
pub struct Sequence {
    /// A built-in scene name (see `irad scenes`) or a .gltf/.glb path [default: the command's]
    pub scene: Option<String>,
    /// Image size WxH
    #[arg(long, default_value_t = Sequence::default().size)]
    pub size: Size,
    /// Frames: A..B (half-open) or a single frame N; frame f is at time f / fps
    /// [default: render and compare: the whole animation (at most 2400 frames); others: 0]
    #[arg(long)]
    pub frames: Option<Frames>,
    /// Frames per second of the animation
    #[arg(long, default_value_t = Sequence::default().fps, allow_hyphen_values = true)]
    pub fps: f32,
    /// Random seed; the same seed gives the same frames
    #[arg(long, default_value_t = Sequence::default().seed, allow_hyphen_values = true)]
    pub seed: u64,
    /// Camera EYE:TARGET:FOV, e.g. 0,0,3.9:0,0,0:39.3 (points x,y,z in scene units, vertical
    /// field of view in degrees): replaces the scene's camera, animated or not, in every frame
    #[arg(long, allow_hyphen_values = true, value_name = "EYE:TARGET:FOV")]
    pub camera: Option<CameraSpec>,
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
        }
    }
}

impl Sequence {
    pub fn validate(&self) -> Result<()> {
        check::float("--fps", self.fps, 0.0, true, 1000.0)?;
        match &self.camera {
            Some(c) => c.validate(),
            None => Ok(()),
        }
    }
    /// Loads the scene named (or `default`), prints its warnings, and puts `--camera` in it.
    pub fn load_scene(&self, default: &str) -> Result<Scene> {
        let mut scene = load_scene(self.scene_or(default))?;
        if let Some(c) = &self.camera {
            c.apply(&mut scene)?;
        }
        Ok(scene)
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

/// How the frame's VPLs are picked (stage 6): the sampler and its knobs (declared once each
/// in `vpl::sampler::knobs`; their flags are built from that list).
#[derive(Args, Clone, Debug, Serialize)]
pub struct SamplerConfig {
    /// VPL sampler
    #[arg(long = "sampler", value_enum, default_value_t = SamplerConfig::default().kind)]
    pub kind: SamplerKind,
    #[command(flatten)]
    pub knobs: SamplerKnobs,
}

impl Default for SamplerConfig {
    fn default() -> Self {
        SamplerConfig {
            kind: SamplerKind::Uniform,
            // From the flicker-against-error sweep (docs/results.md): a twentieth of the
            // chains propose where nothing moves, and the rate rises with the target's change
            // so that chains follow a moving view or light (the knobs' defaults).
            knobs: SamplerKnobs::default(),
        }
    }
}

impl std::ops::Deref for SamplerConfig {
    type Target = SamplerKnobs;
    fn deref(&self) -> &SamplerKnobs {
        &self.knobs
    }
}

impl std::ops::DerefMut for SamplerConfig {
    fn deref_mut(&mut self) -> &mut SamplerKnobs {
        &mut self.knobs
    }
}

/// The knobs' flags, one a knob of [`KNOBS`]: its name, help, default and value type.
impl clap::Args for SamplerKnobs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        KNOBS.iter().fold(cmd, |cmd, k| {
            // clap keeps names as &'static str: the few built here live for the process.
            let leak = |s: String| -> &'static str { Box::leak(s.into_boxed_str()) };
            let help: Vec<&str> = k.help.lines().map(str::trim).collect();
            let mut a = clap::Arg::new(k.name)
                .long(k.name)
                .help(help.join(" "))
                .allow_hyphen_values(true)
                .value_name(leak(k.name.to_uppercase().replace('-', "_")));
            a = if k.integer() {
                a.value_parser(clap::value_parser!(u32))
            } else {
                a.value_parser(clap::value_parser!(f32))
            };
            if let Some(d) = k.default() {
                a = a.default_value(leak(if k.integer() {
                    (d as u32).to_string()
                } else {
                    (d as f32).to_string()
                }));
            }
            cmd.arg(a)
        })
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl clap::FromArgMatches for SamplerKnobs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut k = SamplerKnobs::default();
        k.update_from_arg_matches(m)?;
        Ok(k)
    }
    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        for k in KNOBS {
            let v = if k.integer() {
                m.get_one::<u32>(k.name).map(|&v| v as f64)
            } else {
                m.get_one::<f32>(k.name).map(|&v| v as f64)
            };
            if let Some(v) = v {
                k.set(self, v);
            }
        }
        Ok(())
    }
}

/// The GPU renderer's quality knobs (stage 7).
#[derive(Args, Clone, Debug, Serialize)]
pub struct Quality {
    /// ISM tile side in texels (a power of two, 8 to 1024)
    #[arg(long, default_value_t = Quality::default().ism_size, allow_hyphen_values = true)]
    pub ism_size: u32,
    /// Points of the scene's point set each VPL splats into its ISM (besides its ray-cast
    /// near-field points); 0: from the scene, enough that the points a VPL sees close its tile
    /// at pull-push's coarsest level and at least one for every 32 triangles (see
    /// `ism_points_for`), 64 to 4096
    #[arg(long, default_value_t = Quality::default().ism_points, allow_hyphen_values = true)]
    pub ism_points: u32,
    /// Pull-push levels of the ISMs (holes up to 2^levels texels are filled; at most log2 of --ism-size)
    #[arg(long, default_value_t = Quality::default().pull_levels, allow_hyphen_values = true)]
    pub pull_levels: u32,
    /// ISM depth bias, in texel footprints
    #[arg(long, default_value_t = Quality::default().ism_bias, allow_hyphen_values = true)]
    pub ism_bias: f32,
    /// Emitter samples for direct light (each a shadow hemicube); 0: from the scene, enough
    /// that the direct light's sampling noise is about 5% of it where the camera looks at
    /// frame 0 (see `light_samples_for`), 4 to 64
    #[arg(long, default_value_t = Quality::default().light_samples, allow_hyphen_values = true)]
    pub light_samples: u32,
    /// Shadow hemicube face side in texels
    #[arg(long, default_value_t = Quality::default().shadow_size, allow_hyphen_values = true)]
    pub shadow_size: u32,
    /// Interleaved gather: each pixel of an NxN block gathers every (N^2)-th VPL, then a
    /// depth- and normal-aware NxN filter recombines them (1: off, every pixel gathers all;
    /// 0: from the VPL count, 8 from 4096 VPLs, else 4; see `interleave_for`)
    #[arg(long, default_value_t = Quality::default().interleave, allow_hyphen_values = true)]
    pub interleave: u32,
    /// Anti-aliasing: S x S sub-samples per pixel, box-filtered into the pixel (the
    /// reference's pixel filter); the passes run at S times the size (1: pixel centres only)
    #[arg(long, default_value_t = Quality::default().aa, allow_hyphen_values = true)]
    pub aa: u32,
    /// Emitter edges: in pixels where an emitter's edge crosses the sub-samples, its emission
    /// is box-filtered from N x N camera rays cast on the CPU (0: off, the sub-samples only;
    /// the rest of such a pixel's light stays as the sub-samples give it)
    #[arg(long, default_value_t = Quality::default().edge_rays, allow_hyphen_values = true)]
    pub edge_rays: u32,
    /// Clamping-bias compensation: K short rays a pixel (CPU) add back the light the distance
    /// clamp leaves out where surfaces meet within --clamp (Kollig & Keller 2004; 0: off)
    #[arg(long, default_value_t = Quality::default().compensate, allow_hyphen_values = true)]
    pub compensate: u32,
    /// Temporal accumulation: each pixel's indirect light is the mean of up to N frames'
    /// estimates of its surface point (reprojected; a disoccluded pixel starts anew), while
    /// the triangles and emitter samples stay the same; a moving light or object starts it
    /// anew everywhere (0 or 1: off, every frame stands alone)
    #[arg(long, default_value_t = Quality::default().accumulate, allow_hyphen_values = true)]
    pub accumulate: u32,
}

impl Default for Quality {
    fn default() -> Self {
        Quality {
            ism_size: 64,
            // From the scene (`Render::ism_points`): 464 for the Cornell box (its VPLs see
            // 42% of its area), 4096 for the atrium (the most: its 134k triangles ask 4183).
            ism_points: 0,
            pull_levels: 3,
            ism_bias: 1.5,
            // From the scene (`Render::light_samples`): 26 for the Cornell box, 33 for
            // cornell-light (its light starts near a wall), 24 for two-rooms, 14 for the atrium.
            light_samples: 0,
            shadow_size: 256,
            // From the VPL count (`interleave_for`): 4, or 8 from 4096 VPLs.
            interleave: 0,
            // 2x2 sub-samples: measured on the Cornell box at 128x128 (README, "Pixels"),
            // the mean luminance goes from +6.9% of the reference's to +0.9% for +20% of the
            // frame's time; 3x3 and 4x4 cost 2.2x and 3.1x.
            aa: 2,
            // Off: the correction replaces only the emission of an edge pixel and leaves the
            // rest of its light as the sub-samples give it, so a dark emitter in front of a
            // bright surface comes out too dark (tests/textures.rs's room: -1.2% with 16, from
            // -0.02%). `--edge-rays 16` on `cornell-orbit` at 96x96 takes the warped flicker of
            // the pixels next to the light from 0.00165 to 0.00062 for 6.5 ms a frame (README).
            edge_rays: 0,
            // Off: it costs CPU time in proportion to the pixels near creases (README,
            // "Clamping-bias compensation").
            compensate: 0,
            accumulate: 0,
        }
    }
}

impl Quality {
    pub fn validate(&self) -> Result<()> {
        if !self.ism_size.is_power_of_two() || !(8..=1024).contains(&self.ism_size) {
            bail!(
                "--ism-size {} is out of range: it must be a power of two from 8 to 1024",
                self.ism_size
            );
        }
        // The splat dispatches one invocation per point in x: 65535 groups of 64.
        check::int("--ism-points", self.ism_points, 0, 65535 * 64)?;
        check::int(
            "--pull-levels",
            self.pull_levels,
            0,
            self.ism_size.trailing_zeros(),
        )?;
        check::float("--ism-bias", self.ism_bias, 0.0, false, 100.0)?;
        check::int("--light-samples", self.light_samples, 0, 4096)?;
        check::int("--shadow-size", self.shadow_size, 8, MAX_SIZE)?;
        check::int("--interleave", self.interleave, 0, 8)?;
        check::int("--aa", self.aa, 1, 8)?;
        check::int("--edge-rays", self.edge_rays, 0, 32)?;
        check::int("--compensate", self.compensate, 0, 256)?;
        check::int("--accumulate", self.accumulate, 0, 4096)
    }
}

/// Exposure of the PNG previews: a positive finite factor.
pub fn check_exposure(exposure: f32) -> Result<()> {
    check::float("--exposure", exposure, 0.0, true, 1e6)
}

/// `irad render`: GPU instant radiosity of a sequence.
#[derive(Args, Clone, Debug, Serialize)]
pub struct Render {
    #[command(flatten)]
    pub sequence: Sequence,
    /// Global-illumination method: instant radiosity (VPLs), or a classical radiosity solver
    /// whose view-independent solution gives the indirect light (kept while geometry and
    /// lights are still)
    #[arg(long, value_enum, default_value_t = Render::default().method)]
    pub method: crate::radiosity::Method,
    /// VPL slots per frame
    #[arg(long, default_value_t = Render::default().vpls, allow_hyphen_values = true)]
    pub vpls: u32,
    /// Distance clamp dmin of the VPL contribution, in scene units (0: off)
    /// [default: 2% of the scene's bounding-box diagonal]
    #[arg(long, allow_hyphen_values = true)]
    pub clamp: Option<f32>,
    #[command(flatten)]
    pub sampler: SamplerConfig,
    #[command(flatten)]
    pub quality: Quality,
    /// Graphics backend (also WGPU_BACKEND=vulkan|gl|metal|dx12 with auto)
    #[arg(long, value_enum, default_value_t = Render::default().backend)]
    pub backend: BackendChoice,
    /// Output folder
    #[arg(long, default_value_os_t = Render::default().out)]
    pub out: PathBuf,
    /// Exposure of the PNG previews (EXR files are linear, unscaled)
    #[arg(long, default_value_t = Render::default().exposure, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Also write each frame's direct and indirect light (frame_FFFF_direct.exr/.png, _indirect)
    #[arg(long)]
    pub components: bool,
    /// How the GPU passes are submitted and timed: auto (timestamp queries where they time
    /// the passes, else serialized), timestamps, serialized (a wait after each pass), off (one
    /// submission, no per-pass times)
    #[arg(long, value_enum, default_value_t = Render::default().profiling)]
    pub profiling: ProfilingChoice,
    /// Redraw everything every frame: no reuse of shadow maps, ISM tiles and uploads (for
    /// measuring what reuse saves; the frames are the same bits)
    #[arg(long)]
    pub no_reuse: bool,
    /// Draw every triangle in every view (the G-buffer and shadow maps otherwise leave out the
    /// mesh instances outside the view and the back faces of closed meshes seen from outside,
    /// which changes nothing they store but which of two coplanar faces wins a depth tie; for
    /// measuring)
    #[arg(long)]
    pub no_cull: bool,
}

/// `--profiling`: how a frame's GPU passes are submitted and timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProfilingChoice {
    Auto,
    Timestamps,
    Serialized,
    Off,
}

impl ProfilingChoice {
    /// The mode on `gpu` (auto: [`crate::gpu::Profiling::default_for`]).
    pub fn on(self, gpu: &crate::gpu::Gpu) -> crate::gpu::Profiling {
        use crate::gpu::Profiling;
        match self {
            ProfilingChoice::Auto => Profiling::default_for(gpu),
            ProfilingChoice::Timestamps => Profiling::Timestamps,
            ProfilingChoice::Serialized => Profiling::Serialized,
            ProfilingChoice::Off => Profiling::Off,
        }
    }
}

/// The scene `irad render` and `irad compare` use when none is named.
pub const DEFAULT_ANIMATED_SCENE: &str = "cornell-orbit";

impl Default for Render {
    fn default() -> Self {
        Render {
            sequence: Sequence::default(),
            method: crate::radiosity::Method::Instant,
            vpls: 256,
            clamp: None,
            sampler: SamplerConfig::default(),
            quality: Quality::default(),
            backend: BackendChoice::Auto,
            out: PathBuf::from("out"),
            exposure: 1.0,
            components: false,
            profiling: ProfilingChoice::Auto,
            no_reuse: false,
            no_cull: false,
        }
    }
}

impl Render {
    /// Checks every setting that does not need the scene or the adapter.
    pub fn validate(&self) -> Result<()> {
        self.sequence.validate()?;
        check::int("--vpls", self.vpls, 1, 65535)?;
        if let Some(c) = self.clamp {
            check::float("--clamp", c, 0.0, false, 1e9)?;
        }
        self.sampler.validate(self.vpls)?;
        self.quality.validate()?;
        check_exposure(self.exposure)
    }

    /// The scene this render names, or the default animated Cornell box.
    pub fn scene_name(&self) -> &str {
        self.sequence.scene_or(DEFAULT_ANIMATED_SCENE)
    }
}

/// `irad reference`: the path-traced ground truth.
#[derive(Args, Clone, Debug, Serialize)]
pub struct Reference {
    #[command(flatten)]
    pub sequence: Sequence,
    /// Samples per pixel
    #[arg(long, default_value_t = Reference::default().spp, allow_hyphen_values = true)]
    pub spp: u32,
    /// Output folder
    #[arg(long, default_value_os_t = Reference::default().out)]
    pub out: PathBuf,
    /// Exposure of the PNG previews (the EXR files are linear, unscaled)
    #[arg(long, default_value_t = Reference::default().exposure, allow_hyphen_values = true)]
    pub exposure: f32,
}

/// The scene `irad reference` and `irad bench` use when none is named.
pub const DEFAULT_STILL_SCENE: &str = "cornell";
/// The most samples per pixel a reference may take.
pub const MAX_SPP: u32 = 1 << 20;

impl Default for Reference {
    fn default() -> Self {
        Reference {
            sequence: Sequence::default(),
            spp: 256,
            out: PathBuf::from("out/reference"),
            exposure: 1.0,
        }
    }
}

impl Reference {
    pub fn validate(&self) -> Result<()> {
        self.sequence.validate()?;
        check::int("--spp", self.spp, 1, MAX_SPP)?;
        check_exposure(self.exposure)
    }
}

/// `irad compare`: samplers x VPL counts against a cached reference.
#[derive(Args, Clone, Debug, Serialize)]
pub struct Compare {
    #[command(flatten)]
    pub sequence: Sequence,
    /// Methods to compare: instant (every sampler x VPL count) and classical radiosity
    /// solvers (progressive, hierarchical, stochastic: one run each)
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = Compare::default().methods)]
    pub methods: Vec<crate::radiosity::Method>,
    /// Samplers to compare
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = Compare::default().samplers)]
    pub samplers: Vec<SamplerKind>,
    /// VPL counts to compare
    #[arg(long, value_delimiter = ',', default_values_t = Compare::default().vpls, allow_hyphen_values = true)]
    pub vpls: Vec<u32>,
    /// Samples per pixel of the reference
    #[arg(long, default_value_t = Compare::default().spp, allow_hyphen_values = true)]
    pub spp: u32,
    /// Output folder
    #[arg(long, default_value_os_t = Compare::default().out)]
    pub out: PathBuf,
    /// Where reference frames are cached (keyed by scene, size, spp, fps and seed)
    #[arg(long, default_value_os_t = Compare::default().cache)]
    pub cache: PathBuf,
    /// The VPL count whose animations the report shows [default: the middle one]
    #[arg(long, allow_hyphen_values = true)]
    pub show_vpls: Option<u32>,
    /// Sweep one sampler's knob: SAMPLER:KNOB=V1,V2,... (knobs: mh-rate, mh-follow, mh-escape,
    /// smc-rate, smc-follow, eps, candidates, camera-points), e.g. `--sweep mh:mh-rate=0.01,0.1,1`; repeat the flag for
    /// more. The swept sampler runs once per value and VPL count, drawn as one curve on the
    /// flicker-against-error charts; other samplers draw a curve over --vpls
    #[arg(long, value_name = "SAMPLER:KNOB=V1,V2,..")]
    pub sweep: Vec<Sweep>,
    /// Every run's renderer settings besides the sampler kind and VPL count (--mh-rate,
    /// --ism-size, --backend, --exposure, ...)
    #[command(flatten)]
    pub render: CompareRender,
}

/// `--sweep SAMPLER:KNOB=V1,V2,...`: the runs of one sampler at each value of one knob.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub sampler: SamplerKind,
    pub knob: &'static Knob,
    pub values: Vec<f64>,
}

impl std::str::FromStr for Sweep {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        use clap::ValueEnum;
        let form = "it must be SAMPLER:KNOB=V1,V2,... (e.g. mh:mh-rate=0.01,0.1,1)";
        let (sampler, rest) = s
            .split_once(':')
            .ok_or_else(|| format!("'{s}' names no sampler: {form}"))?;
        let sampler = SamplerKind::from_str(sampler.trim(), true).map_err(|_| {
            let names: Vec<String> = SamplerKind::value_variants()
                .iter()
                .filter_map(|k| k.to_possible_value().map(|v| v.get_name().to_string()))
                .collect();
            format!(
                "'{sampler}' in '{s}' is not a sampler ({})",
                names.join(", ")
            )
        })?;
        let (knob, values) = rest
            .split_once('=')
            .ok_or_else(|| format!("'{s}' has no values: {form}"))?;
        let knob = Knob::named(knob).ok_or_else(|| {
            let names: Vec<&str> = KNOBS.iter().map(|k| k.name).collect();
            format!(
                "'{knob}' in '{s}' is not a knob that can be swept ({})",
                names.join(", ")
            )
        })?;
        let values = values
            .split(',')
            .map(|v| {
                let x: f64 = v
                    .trim()
                    .parse()
                    .map_err(|_| format!("'{v}' in '{s}' is not a number"))?;
                if !x.is_finite() {
                    return Err(format!("'{v}' in '{s}' is not a finite number"));
                }
                if knob.integer() && (x.fract() != 0.0 || x < 0.0 || x > u32::MAX as f64) {
                    return Err(format!("'{v}' in '{s}': {knob} takes whole numbers"));
                }
                Ok(x)
            })
            .collect::<Result<Vec<f64>, String>>()?;
        Ok(Sweep {
            sampler,
            knob,
            values,
        })
    }
}

impl std::fmt::Display for Sweep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v: Vec<String> = self.values.iter().map(|v| v.to_string()).collect();
        write!(f, "{}:{}={}", self.sampler, self.knob, v.join(","))
    }
}

impl Serialize for Sweep {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

/// What every run of a comparison shares: the renderer's knobs except the sampler kind, the
/// VPL count, the sequence and the output folder, which the comparison sets per run.
#[derive(Args, Clone, Debug, Serialize)]
pub struct CompareRender {
    /// Distance clamp dmin (see `irad render --help`)
    #[arg(long, allow_hyphen_values = true)]
    pub clamp: Option<f32>,
    /// The samplers' knobs (--mh-rate, --eps, ...: see `irad render --help`)
    #[command(flatten)]
    pub knobs: SamplerKnobs,
    #[command(flatten)]
    pub quality: Quality,
    /// Graphics backend
    #[arg(long, value_enum, default_value_t = Render::default().backend)]
    pub backend: BackendChoice,
    /// Exposure of previews
    #[arg(long, default_value_t = Render::default().exposure, allow_hyphen_values = true)]
    pub exposure: f32,
}

impl Default for CompareRender {
    fn default() -> Self {
        let r = Render::default();
        CompareRender {
            clamp: r.clamp,
            knobs: r.sampler.knobs,
            quality: r.quality,
            backend: r.backend,
            exposure: r.exposure,
        }
    }
}

impl Default for Compare {
    fn default() -> Self {
        Compare {
            sequence: Sequence::default(),
            methods: vec![crate::radiosity::Method::Instant],
            samplers: vec![SamplerKind::Uniform, SamplerKind::Cdf, SamplerKind::Mh],
            vpls: vec![64, 256, 1024],
            spp: 256,
            out: PathBuf::from("out/compare"),
            cache: PathBuf::from("out/cache"),
            show_vpls: None,
            sweep: Vec::new(),
            render: CompareRender::default(),
        }
    }
}

impl Compare {
    /// The render settings of the run of `sampler` at `vpls` with `knob` (from a sweep) set.
    pub fn run_with(
        &self,
        sampler: SamplerKind,
        vpls: u32,
        knob: Option<(&'static Knob, f64)>,
    ) -> Render {
        let mut r = self.run(sampler, vpls);
        if let Some((k, v)) = knob {
            k.set(&mut r.sampler.knobs, v);
        }
        r
    }

    /// The render settings of the run of `sampler` at `vpls`.
    pub fn run(&self, sampler: SamplerKind, vpls: u32) -> Render {
        let r = &self.render;
        Render {
            sequence: self.sequence.clone(),
            method: crate::radiosity::Method::Instant,
            vpls,
            clamp: r.clamp,
            sampler: SamplerConfig {
                kind: sampler,
                knobs: r.knobs.clone(),
            },
            quality: r.quality.clone(),
            backend: r.backend,
            out: self.out.clone(),
            exposure: r.exposure,
            components: false,
            profiling: ProfilingChoice::Auto,
            no_reuse: false,
            no_cull: false,
        }
    }

    /// The VPL count whose animations the report shows.
    pub fn shown_vpls(&self) -> u32 {
        self.show_vpls
            .unwrap_or_else(|| self.vpls.get(self.vpls.len() / 2).copied().unwrap_or(0))
    }

    pub fn validate(&self) -> Result<()> {
        self.sequence.validate()?;
        if self.methods.is_empty() {
            bail!("--methods needs at least one method");
        }
        if self.samplers.is_empty() {
            bail!("--samplers needs at least one sampler");
        }
        if self.vpls.is_empty() {
            bail!("--vpls needs at least one VPL count");
        }
        if self.spp < 2 {
            bail!(
                "--spp {}: the reference is traced as two independent halves (to measure its own noise), so it needs at least 2 samples per pixel",
                self.spp
            );
        }
        check::int("--spp", self.spp, 2, MAX_SPP)?;
        if let Some(v) = self.show_vpls {
            if !self.vpls.contains(&v) {
                bail!("--show-vpls {v} is not one of --vpls {:?}", self.vpls);
            }
        }
        // Every run's settings, checked before anything renders.
        for &s in &self.samplers {
            for &v in &self.vpls {
                self.run(s, v).validate()?;
            }
        }
        for sw in &self.sweep {
            if !self.samplers.contains(&sw.sampler) {
                let names: Vec<String> = self.samplers.iter().map(|s| s.to_string()).collect();
                bail!(
                    "--sweep {sw}: {} is not one of --samplers {}",
                    sw.sampler,
                    names.join(",")
                );
            }
            if !sw.knob.used_by(sw.sampler) {
                let used: Vec<&str> = KNOBS
                    .iter()
                    .filter(|k| k.used_by(sw.sampler))
                    .map(|k| k.name)
                    .collect();
                bail!(
                    "--sweep {sw}: {} does not use --{} (it uses {})",
                    sw.sampler,
                    sw.knob,
                    if used.is_empty() {
                        "none of the knobs; sweep --vpls instead".to_string()
                    } else {
                        used.iter()
                            .map(|k| format!("--{k}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                );
            }
            if sw.values.is_empty() {
                bail!("--sweep {sw}: no values");
            }
            for &x in &sw.values {
                for &v in &self.vpls {
                    self.run_with(sw.sampler, v, Some((sw.knob, x)))
                        .validate()
                        .map_err(|e| anyhow::anyhow!("--sweep {sw}: {e}"))?;
                }
            }
        }
        Ok(())
    }

    /// The scene this comparison names, or the default animated Cornell box.
    pub fn scene_name(&self) -> &str {
        self.sequence.scene_or(DEFAULT_ANIMATED_SCENE)
    }
}

/// One bench configuration: VPL count and image size, written `256@256x256`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BenchCase {
    pub vpls: u32,
    pub size: Size,
}

impl std::str::FromStr for BenchCase {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (v, size) = s
            .split_once('@')
            .ok_or_else(|| format!("'{s}' is not VPLS@WxH (e.g. 256@256x256)"))?;
        Ok(BenchCase {
            vpls: v
                .trim()
                .parse()
                .map_err(|_| format!("'{v}' in '{s}' is not a VPL count"))?,
            size: size.parse()?,
        })
    }
}

impl std::fmt::Display for BenchCase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}@{}", self.vpls, self.size)
    }
}

impl Serialize for BenchCase {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

/// `irad bench`: time per stage of whole frames for several configurations.
#[derive(Args, Clone, Debug, Serialize)]
pub struct Bench {
    #[command(flatten)]
    pub render: Render,
    /// Configurations VPLS@WxH (each overrides --vpls and --size)
    #[arg(long = "configs", value_delimiter = ',', default_values_t = Bench::default().cases)]
    pub cases: Vec<BenchCase>,
    /// Frames measured per configuration (after one warm-up frame)
    #[arg(long, default_value_t = Bench::default().repeat, allow_hyphen_values = true)]
    pub repeat: u32,
}

impl Default for Bench {
    fn default() -> Self {
        Bench {
            render: Render::default(),
            cases: vec![
                BenchCase {
                    vpls: 256,
                    size: Size {
                        width: 256,
                        height: 256,
                    },
                },
                BenchCase {
                    vpls: 1024,
                    size: Size {
                        width: 512,
                        height: 512,
                    },
                },
            ],
            repeat: 5,
        }
    }
}

impl Bench {
    /// The render settings of one case.
    pub fn case(&self, c: BenchCase) -> Render {
        let mut r = self.render.clone();
        r.vpls = c.vpls;
        r.sequence.size = c.size;
        r
    }
    pub fn validate(&self) -> Result<()> {
        if self.cases.is_empty() {
            bail!("--configs needs at least one VPLS@WxH");
        }
        check::int("--repeat", self.repeat, 1, 10_000)?;
        for &c in &self.cases {
            self.case(c).validate()?;
        }
        Ok(())
    }
    /// The scene benchmarked, or the still Cornell box.
    pub fn scene_name(&self) -> &str {
        self.render.sequence.scene_or(DEFAULT_STILL_SCENE)
    }
}

impl std::fmt::Display for SamplerKind {
    /// The name the CLI spells (`uniform`, `cdf`, `mh`, `frozen`, `rejection`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use clap::ValueEnum;
        let v = self.to_possible_value().expect("no skipped variants");
        f.write_str(v.get_name())
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
        let last = "4294967295".parse::<Frames>().unwrap_err();
        assert!(last.contains("past the last frame"), "{last}");
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

    #[test]
    fn defaults_validate() {
        Render::default().validate().unwrap();
        Reference::default().validate().unwrap();
        Compare::default().validate().unwrap();
        Bench::default().validate().unwrap();
    }

    #[test]
    fn interleave_out_of_range_names_the_flag() {
        for bad in [9, 64] {
            let q = Quality {
                interleave: bad,
                ..Quality::default()
            };
            let e = q.validate().unwrap_err().to_string();
            assert!(e.contains("--interleave") && e.contains("0 to 8"), "{e}");
        }
        let q = Quality {
            interleave: 8,
            ..Quality::default()
        };
        q.validate().unwrap();
    }

    #[test]
    fn a_long_animation_is_capped_with_a_note_and_a_short_one_is_whole() {
        let s = Sequence::default();
        let (f, note) = s.frames_or_all(3.0);
        assert_eq!((f.start, f.end, note), (0, 72, None));
        let (f, note) = s.frames_or_all(3.0e7);
        assert_eq!(f.end, DEFAULT_FRAME_CAP);
        assert!(note.unwrap().contains("first 2400 frames"));
    }
}
