//! The sampler's settings: which sampler, and its knobs (declared once each in
//! [`super::knobs`]; the CLI builds their flags from that list).

use super::knobs::SamplerKnobs;
use super::SamplerKind;
use serde::Serialize;

/// How the frame's VPLs are picked (stage 6): the sampler and its knobs (declared once each
/// in `vpl::sampler::knobs`; their flags are built from that list).
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct SamplerConfig {
    /// VPL sampler
    #[cfg_attr(feature = "cli", arg(long = "sampler", value_enum, default_value_t = SamplerConfig::default().kind))]
    pub kind: SamplerKind,
    #[cfg_attr(feature = "cli", command(flatten))]
    pub knobs: SamplerKnobs,
}

impl Default for SamplerConfig {
    fn default() -> Self {
        SamplerConfig {
            kind: SamplerKind::Mh,
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
