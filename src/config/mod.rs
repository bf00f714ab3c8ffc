//! The commands' settings: one type per command ([`Render`], [`Reference`], [`Compare`],
//! [`Bench`]) and what they share ([`Sequence`]), made of the stages' own settings types,
//! re-exported here: the sampler's [`SamplerConfig`] (`vpl::sampler`, its knobs declared once
//! in `vpl::sampler::knobs`) and the renderer's [`Quality`] (`gpu`). Each type has `Default`
//! (the one place a default lives: the CLI's help reads it from there) and one `validate()`
//! that every command calls before it renders anything. A Rust program fills these and calls
//! `commands::render::render` and friends.
//!
//! Every numeric value goes through [`check`]: NaN, infinity, sign and range. Errors name the
//! setting in backquotes (`` `exposure` NaN is not a number ``); the library has no clap in
//! it (`cargo check --lib --no-default-features`): with the `cli` feature the same types carry
//! clap's derive, and `irad`'s error report writes each named setting as its flag
//! (`--exposure NaN is not a number`, `cli::report`).

use crate::gpu::BackendChoice;
pub use crate::vpl::sampler::knobs::{Knob, SamplerKnobs, KNOBS};
use crate::vpl::sampler::SamplerKind;
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::PathBuf;

pub use crate::check;

mod cluster;
mod compare;
mod metrics;
mod sequence;

pub use crate::gpu::{Quality, MAX_SIZE};
pub use crate::vpl::sampler::SamplerConfig;
pub use cluster::Cluster;
pub use compare::*;
pub use metrics::Metrics;
pub use sequence::*;

/// Exposure of the PNG previews: a positive finite factor.
pub fn check_exposure(exposure: f32) -> Result<()> {
    check::float("`exposure`", exposure, 0.0, true, 1e6)
}

/// `irad render`: GPU instant radiosity of a sequence.
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Render {
    #[cfg_attr(feature = "cli", command(flatten))]
    pub sequence: Sequence,
    /// Global-illumination method: instant radiosity (VPLs), or a classical radiosity solver
    /// whose view-independent solution gives the indirect light (kept while geometry and
    /// lights are still)
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Render::default().method))]
    pub method: Method,
    /// Classical radiosity's elements: uniform, adaptive (split where neighbours differ, solve
    /// again), or discontinuity (cut along the direct light's shadow and penumbra boundaries
    /// first, then adaptive; progressive and stochastic)
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Render::default().meshing))]
    pub meshing: crate::radiosity::Meshing,
    /// VPL slots per frame
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Render::default().vpls, allow_hyphen_values = true))]
    pub vpls: u32,
    /// Distance clamp dmin of the VPL contribution, in scene units (0: off)
    /// [default: 1/14 of the scene's mean free path, the mean distance from its surfaces to
    /// what they see (docs/math.md, section 4)]
    #[cfg_attr(feature = "cli", arg(long, allow_hyphen_values = true))]
    pub clamp: Option<f32>,
    #[cfg_attr(feature = "cli", command(flatten))]
    pub sampler: SamplerConfig,
    #[cfg_attr(feature = "cli", command(flatten))]
    pub quality: Quality,
    /// Graphics backend (also WGPU_BACKEND=vulkan|gl|metal|dx12 with auto)
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Render::default().backend))]
    pub backend: BackendChoice,
    /// Output folder
    #[cfg_attr(feature = "cli", arg(long, default_value_os_t = Render::default().out))]
    pub out: PathBuf,
    /// Replace frame files, preview.gif, run.json or frames.jsonl in the output folder that
    /// no earlier irad run recorded writing (its .irad-manifest.json); refused by default
    #[cfg_attr(feature = "cli", arg(long))]
    pub overwrite: bool,
    /// Exposure of the PNG previews (EXR files are linear, unscaled)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Render::default().exposure, allow_hyphen_values = true))]
    pub exposure: f32,
    /// Also write each frame's direct and indirect light (frame_FFFF_direct.exr/.png, _indirect)
    #[cfg_attr(feature = "cli", arg(long))]
    pub components: bool,
    /// How the GPU passes are submitted and timed: auto (timestamp queries where they time
    /// the passes, else serialized), timestamps, serialized (a wait after each pass), off (one
    /// submission, no per-pass times)
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Render::default().profiling))]
    pub profiling: ProfilingChoice,
    /// Redraw everything every frame: no reuse of shadow maps, ISM tiles and uploads (for
    /// measuring what reuse saves; the frames are the same bits)
    #[cfg_attr(feature = "cli", arg(long))]
    pub no_reuse: bool,
    /// Draw every triangle in every view (the G-buffer and shadow maps otherwise leave out the
    /// mesh instances outside the view and the back faces of closed meshes seen from outside,
    /// which changes nothing they store but which of two coplanar faces wins a depth tie; for
    /// measuring)
    #[cfg_attr(feature = "cli", arg(long))]
    pub no_cull: bool,
}

/// `--method`: how the indirect light is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Instant radiosity: virtual point lights (the default)
    #[default]
    Instant,
    /// Progressive refinement: shooting from the element of largest unshot power
    Progressive,
    /// Hierarchical radiosity (Hanrahan, Salzman, Aupperle 1991): links refined by B*F
    Hierarchical,
    /// Stochastic Jacobi radiosity: rays distribute power, no form factors stored
    Stochastic,
}

impl Method {
    /// The classical solver this method runs (none for instant radiosity).
    pub fn solver(self) -> Option<crate::radiosity::Solver> {
        use crate::radiosity::Solver;
        match self {
            Method::Instant => None,
            Method::Progressive => Some(Solver::Progressive),
            Method::Hierarchical => Some(Solver::Hierarchical),
            Method::Stochastic => Some(Solver::Stochastic),
        }
    }
    pub fn name(self) -> &'static str {
        self.solver().map_or("instant", |s| s.name())
    }
}

/// `--profiling`: how a frame's GPU passes are submitted and timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
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
            method: Method::Instant,
            meshing: crate::radiosity::Meshing::Adaptive,
            vpls: 256,
            clamp: None,
            sampler: SamplerConfig::default(),
            quality: Quality::default(),
            backend: BackendChoice::Auto,
            out: PathBuf::from("out"),
            overwrite: false,
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
        check::int("`vpls`", self.vpls, 1, 65535)?;
        if let Some(c) = self.clamp {
            check::float("`clamp`", c, 0.0, false, 1e9)?;
        }
        self.sampler.validate(self.vpls)?;
        self.quality.validate()?;
        if self.quality.light_samples > 0 {
            // Before any device is opened or folder made (the renderer checks again, with
            // the adapter's limits and the count `--light-samples 0` chooses).
            crate::gpu::renderer::check_shadow_maps(
                self.quality.light_samples,
                self.quality.shadow_size,
            )?;
        }
        check_exposure(self.exposure)
    }

    /// The scene this render names, or the default animated Cornell box.
    pub fn scene_name(&self) -> &str {
        self.sequence.scene_or(DEFAULT_ANIMATED_SCENE)
    }
}

/// `irad reference`: the path-traced ground truth.
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Reference {
    #[cfg_attr(feature = "cli", command(flatten))]
    pub sequence: Sequence,
    /// Samples per pixel
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Reference::default().spp, allow_hyphen_values = true))]
    pub spp: u32,
    /// The bounce from which Russian roulette lets a path go on with probability at most 0.95
    /// (as Mitsuba 3 does from its rr_depth); before it, a path between albedo-1 surfaces goes
    /// on at weight 1. Later converges faster where light bounces long between white surfaces
    /// (3 to 65536; docs/math.md, "What the reference can show of a gap")
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Reference::default().rr_cap_depth, allow_hyphen_values = true))]
    pub rr_cap_depth: u32,
    /// Output folder
    #[cfg_attr(feature = "cli", arg(long, default_value_os_t = Reference::default().out))]
    pub out: PathBuf,
    /// Replace frame files or run.json in the output folder that no earlier irad run
    /// recorded writing (its .irad-manifest.json); refused by default
    #[cfg_attr(feature = "cli", arg(long))]
    pub overwrite: bool,
    /// Exposure of the PNG previews (the EXR files are linear, unscaled)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Reference::default().exposure, allow_hyphen_values = true))]
    pub exposure: f32,
    /// Past one machine: --plan DIR, --collect DIR (docs/cluster.md)
    #[cfg_attr(feature = "cli", command(flatten))]
    #[serde(skip)]
    pub cluster: Cluster,
}

/// The scene `irad reference` and `irad bench` use when none is named.
pub const DEFAULT_STILL_SCENE: &str = "cornell";
pub use crate::reference::MAX_SPP;

impl Default for Reference {
    fn default() -> Self {
        Reference {
            sequence: Sequence::default(),
            spp: 256,
            rr_cap_depth: crate::reference::RR_CAP_DEPTH,
            out: PathBuf::from("out/reference"),
            overwrite: false,
            exposure: 1.0,
            cluster: Cluster::default(),
        }
    }
}

impl Reference {
    pub fn validate(&self) -> Result<()> {
        self.sequence.validate()?;
        self.settings().validate()?;
        self.cluster.validate()?;
        check_exposure(self.exposure)
    }

    /// The path tracer's settings of this reference.
    pub fn settings(&self) -> crate::reference::ReferenceSettings {
        self.sequence.reference_settings(self.sampling())
    }

    /// How this reference traces each pixel.
    pub fn sampling(&self) -> crate::reference::Sampling {
        crate::reference::Sampling {
            spp: self.spp,
            rr_cap_depth: self.rr_cap_depth,
        }
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
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Bench {
    #[cfg_attr(feature = "cli", command(flatten))]
    pub render: Render,
    /// Configurations VPLS@WxH (each overrides --vpls and --size)
    #[cfg_attr(feature = "cli", arg(long = "configs", value_delimiter = ',', default_values_t = Bench::default().cases))]
    pub cases: Vec<BenchCase>,
    /// Frames measured per configuration (after one warm-up frame)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Bench::default().repeat, allow_hyphen_values = true))]
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
            bail!("`configs` needs at least one VPLS@WxH");
        }
        check::int("`repeat`", self.repeat, 1, 10_000)?;
        for &c in &self.cases {
            // The case's VPL count is its own, not `vpls` (which bench does not take).
            check::int(&format!("`configs` {c}: the VPL count"), c.vpls, 1, 65535)?;
            self.case(c)
                .validate()
                .map_err(|e| anyhow::anyhow!("`configs` {c}: {e}"))?;
        }
        Ok(())
    }
    /// The scene benchmarked, or the still Cornell box.
    pub fn scene_name(&self) -> &str {
        self.render.sequence.scene_or(DEFAULT_STILL_SCENE)
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
            assert!(e.contains("`interleave`") && e.contains("0 to 8"), "{e}");
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
