//! The GPU renderer's quality knobs: the renderer's own settings, with their defaults and one
//! `validate()`; [`crate::resolve`] turns them (and the scene's budgets) into a
//! [`super::RendererConfig`].

pub use super::temporal::HistoryMode;
use crate::check;
use anyhow::{bail, Result};
use serde::Serialize;

/// The largest width or height any command accepts (images, shadow faces).
pub const MAX_SIZE: u32 = 8192;

/// The GPU renderer's quality knobs (stage 7).
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Quality {
    /// ISM tile side in texels (a power of two, 8 to 1024)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().ism_size, allow_hyphen_values = true))]
    pub ism_size: u32,
    /// Points of the scene's point set each VPL splats into its ISM (besides its ray-cast
    /// near-field points); 0: from the scene, enough that the points a VPL sees close its tile
    /// at pull-push's coarsest level and at least one for every 32 triangles (see
    /// `ism_points_for`), 64 to 4096
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().ism_points, allow_hyphen_values = true))]
    pub ism_points: u32,
    /// Pull-push levels of the ISMs (holes up to 2^levels texels are filled; at most log2 of --ism-size)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().pull_levels, allow_hyphen_values = true))]
    pub pull_levels: u32,
    /// ISM depth bias, in texel footprints
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().ism_bias, allow_hyphen_values = true))]
    pub ism_bias: f32,
    /// Emitter samples for direct light (each a shadow hemicube); 0: from the scene, enough
    /// that the direct light's sampling noise is about 5% of it where the camera looks at
    /// frame 0 (3.5%, about twice the samples, for a classical method; see
    /// `light_samples_for`), 4 to 64
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().light_samples, allow_hyphen_values = true))]
    pub light_samples: u32,
    /// Shadow hemicube face side in texels
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().shadow_size, allow_hyphen_values = true))]
    pub shadow_size: u32,
    /// Interleaved gather: each pixel of an NxN block gathers every (N^2)-th VPL, then a
    /// depth- and normal-aware NxN filter recombines them (1: off, every pixel gathers all;
    /// 0: from the VPL count and the image's size, at most 8 from 4096 VPLs, else 4, and 1
    /// where the full gather costs little; see `resolve::interleave_for`)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().interleave, allow_hyphen_values = true))]
    pub interleave: u32,
    /// Anti-aliasing: S x S sub-samples per pixel, box-filtered into the pixel (the
    /// reference's pixel filter); the passes run at S times the size (1: pixel centres only;
    /// 0: from the method, 2 for instant radiosity and 4 for the classical methods, see
    /// `resolve::aa`)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().aa, allow_hyphen_values = true))]
    pub aa: u32,
    /// Edges box-filtered on the CPU: in pixels at an emitter's edge its emission is the
    /// exact covered area (N x N camera rays find what hides it); with a classical method,
    /// pixels at silhouettes and creases take the solution's light box-filtered by about
    /// N x N camera rays, a Fibonacci lattice (0: off, the sub-samples only; the rest of an
    /// emitter edge pixel's light stays as the sub-samples give it)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().edge_rays, allow_hyphen_values = true))]
    pub edge_rays: u32,
    /// Clamping-bias compensation: K short paths a pixel (CPU) add back the light the distance
    /// clamp leaves out where surfaces meet within --clamp, and the near field of emitters
    /// (Kollig & Keller 2004; thin gaps, docs/math.md section 4). `auto`: 64 where a tenth or
    /// more of the emitters' light meets a surface within the clamp (a lamp under a ceiling,
    /// in a recess), else off (see `resolve::compensate`); `off` or 0: off; K: 1 to 256. A
    /// pixel whose K paths leave it noisy (the view into a gap's mouth) traces up to 16 rounds
    /// of K (`compensation::compensate_in_rounds`)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().compensate, allow_hyphen_values = true))]
    pub compensate: Compensate,
    /// Temporal accumulation: each pixel's indirect light is the mean of up to N frames'
    /// estimates of its surface point (reprojected; a disoccluded pixel starts anew); under a
    /// moving light or object --history says what becomes of it (0 or 1: off, every frame
    /// stands alone)
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Quality::default().accumulate, allow_hyphen_values = true))]
    pub accumulate: u32,
    /// What the accumulated history does under a moving light or object
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Quality::default().history))]
    pub history: HistoryMode,
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
            // From the VPL count and the image's size (`resolve::interleave_for`): 4, or 8 from
            // 4096 VPLs, less in a small image.
            interleave: 0,
            // From the method (`resolve::aa`): 2x2 sub-samples for instant radiosity, measured
            // on the Cornell box at 128x128 (docs/antialiasing.md): the mean luminance goes
            // from +6.9% of the reference's to +0.9% for +20% of the frame's time (3x3 and 4x4
            // cost 2.2x and 3.1x); 4x4 for a classical method's still solution.
            aa: 0,
            // 24: an emitter triangle's share of an edge pixel is its projection's exact area
            // in the pixel (`trace::edges`), the rays deciding only what hides it and what it
            // emits there; a classical method's silhouettes and creases take their light
            // box-filtered by the same rays, each seeing what the surfaces show. On
            // `cornell-orbit` at 96x96 against a 2048-spp reference (warped F1 floor 0.00101),
            // 8 took cdf's warped flicker from 0.00356 to 0.00209 and progressive's from
            // 0.00279 to 0.00110 (docs/antialiasing.md); against an 8192-spp reference, 16
            // (with 4x4 sub-samples) takes progressive's own flicker from 0.000207 to 0.000173
            // at 1.5x its frame's time; 24 (a Fibonacci lattice of 610 rays for the
            // silhouettes) to 0.000154 against 0.000164 at 16 (233 rays), at 1.25x the frame's
            // time; instant radiosity's emitter edges cost 5.1 ms at 256x256 (2.3 ms at 16).
            edge_rays: 24,
            // Only where the scene needs it: 16 paths a pixel take a 256x256 Cornell frame from
            // 0.14 s to 0.35 s (docs/math.md section 4), and no built-in scene needs it.
            compensate: Compensate::Auto,
            // 8 frames, the history weighed by the light's gradient under a moving light or
            // object: on the built-in animations at 96x96 with 256 VPLs, against 2048-spp
            // references, mh's median relMSE and warped flicker fall to 0.31-0.69x and
            // 0.04-0.17x of plain cdf's (docs/results/default_sampler.md).
            accumulate: 8,
            history: HistoryMode::Gradient,
        }
    }
}

impl Quality {
    pub fn validate(&self) -> Result<()> {
        if !self.ism_size.is_power_of_two() || !(8..=1024).contains(&self.ism_size) {
            bail!(
                "`ism_size` {} is out of range: it must be a power of two from 8 to 1024",
                self.ism_size
            );
        }
        // The splat dispatches one invocation per point in x: 65535 groups of 64.
        check::int("`ism_points`", self.ism_points, 0, 65535 * 64)?;
        check::int(
            "`pull_levels`",
            self.pull_levels,
            0,
            self.ism_size.trailing_zeros(),
        )?;
        check::float("`ism_bias`", self.ism_bias, 0.0, false, 100.0)?;
        check::int("`light_samples`", self.light_samples, 0, 4096)?;
        check::int("`shadow_size`", self.shadow_size, 8, MAX_SIZE)?;
        check::int("`interleave`", self.interleave, 0, 8)?;
        check::int("`aa`", self.aa, 0, 8)?;
        check::int("`edge_rays`", self.edge_rays, 0, 32)?;
        if let Compensate::Paths(k) = self.compensate {
            check::int("`compensate`", k, 0, 256)?;
        }
        check::int("`accumulate`", self.accumulate, 0, 4096)
    }
}

/// `--compensate`: how many compensation paths a pixel traces ([`crate::compensation`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compensate {
    /// From the scene: [`crate::resolve::AUTO_COMPENSATE`] paths a pixel where a tenth or more
    /// of its emitters' light meets a surface within the distance clamp, else none.
    Auto,
    /// K paths a pixel (0: off).
    Paths(u32),
}

impl std::fmt::Display for Compensate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Compensate::Auto => f.write_str("auto"),
            Compensate::Paths(0) => f.write_str("off"),
            Compensate::Paths(k) => write!(f, "{k}"),
        }
    }
}

impl std::str::FromStr for Compensate {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "auto" => Ok(Compensate::Auto),
            "off" => Ok(Compensate::Paths(0)),
            n => n.parse().map(Compensate::Paths).map_err(|_| {
                format!("'{s}' is not auto, off or a count of paths a pixel (0 to 256)")
            }),
        }
    }
}

/// As written on the command line: "auto", "off" or the count.
impl Serialize for Compensate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}
