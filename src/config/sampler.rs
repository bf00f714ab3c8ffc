//! The sampler's settings and the CLI's flags for its knobs, built from the knobs' one
//! declaration (`vpl::sampler::knobs`).

use super::*;
use anyhow::Result;
use clap::Args;
use serde::Serialize;

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
