//! `irad compare`'s settings: methods, samplers, VPL counts, sweeps of one knob, and what
//! every run shares.

use super::*;
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::PathBuf;

/// `irad compare`: samplers x VPL counts against a cached reference.
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Compare {
    #[cfg_attr(feature = "cli", command(flatten))]
    pub sequence: Sequence,
    /// Methods to compare: instant (every sampler x VPL count) and classical radiosity
    /// solvers (progressive, hierarchical, stochastic: one run each)
    #[cfg_attr(feature = "cli", arg(long, value_enum, value_delimiter = ',', default_values_t = Compare::default().methods))]
    pub methods: Vec<Method>,
    /// Samplers to compare
    #[cfg_attr(feature = "cli", arg(long, value_enum, value_delimiter = ',', default_values_t = Compare::default().samplers))]
    pub samplers: Vec<SamplerKind>,
    /// VPL counts to compare
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_values_t = Compare::default().vpls, allow_hyphen_values = true))]
    pub vpls: Vec<u32>,
    /// Samples per pixel of the reference
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Compare::default().spp, allow_hyphen_values = true))]
    pub spp: u32,
    /// Output folder
    #[cfg_attr(feature = "cli", arg(long, default_value_os_t = Compare::default().out))]
    pub out: PathBuf,
    /// Where reference frames are cached (keyed by scene, size, spp, fps and seed)
    #[cfg_attr(feature = "cli", arg(long, default_value_os_t = Compare::default().cache))]
    pub cache: PathBuf,
    /// The VPL count whose animations the report shows [default: the middle one]
    #[cfg_attr(feature = "cli", arg(long, allow_hyphen_values = true))]
    pub show_vpls: Option<u32>,
    /// Sweep one sampler's knob: SAMPLER:KNOB=V1,V2,... (knobs: mh-rate, mh-follow, mh-escape,
    /// smc-rate, smc-follow, rmsmc-ess, rmsmc-rate, rmsmc-follow, eps, candidates,
    /// camera-points), e.g. `--sweep mh:mh-rate=0.01,0.1,1`; repeat the flag for
    /// more. The swept sampler runs once per value and VPL count, drawn as one curve on the
    /// flicker-against-error charts; other samplers draw a curve over --vpls
    #[cfg_attr(feature = "cli", arg(long, value_name = "SAMPLER:KNOB=V1,V2,.."))]
    pub sweep: Vec<Sweep>,
    /// Every run's renderer settings besides the sampler kind and VPL count (--mh-rate,
    /// --ism-size, --backend, --exposure, ...)
    #[cfg_attr(feature = "cli", command(flatten))]
    pub render: CompareRender,
    /// Past one machine: --plan DIR, --collect DIR (docs/cluster.md)
    #[cfg_attr(feature = "cli", command(flatten))]
    #[serde(skip)]
    pub cluster: Cluster,
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
        let form = "it must be SAMPLER:KNOB=V1,V2,... (e.g. mh:mh-rate=0.01,0.1,1)";
        let (sampler, rest) = s
            .split_once(':')
            .ok_or_else(|| format!("'{s}' names no sampler: {form}"))?;
        let sampler = SamplerKind::parse(sampler.trim()).ok_or_else(|| {
            let names: Vec<&str> = SamplerKind::ALL.iter().map(|k| k.name()).collect();
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
#[derive(Clone, Debug, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct CompareRender {
    /// Distance clamp dmin (see `irad render --help`)
    #[cfg_attr(feature = "cli", arg(long, allow_hyphen_values = true))]
    pub clamp: Option<f32>,
    /// The samplers' knobs (--mh-rate, --eps, ...: see `irad render --help`)
    #[cfg_attr(feature = "cli", command(flatten))]
    pub knobs: SamplerKnobs,
    #[cfg_attr(feature = "cli", command(flatten))]
    pub quality: Quality,
    /// Graphics backend
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Render::default().backend))]
    pub backend: BackendChoice,
    /// Exposure of previews
    #[cfg_attr(feature = "cli", arg(long, default_value_t = Render::default().exposure, allow_hyphen_values = true))]
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
            methods: vec![Method::Instant],
            samplers: vec![SamplerKind::Uniform, SamplerKind::Cdf, SamplerKind::Mh],
            vpls: vec![64, 256, 1024],
            spp: 256,
            out: PathBuf::from("out/compare"),
            cache: PathBuf::from("out/cache"),
            show_vpls: None,
            sweep: Vec::new(),
            render: CompareRender::default(),
            cluster: Cluster::default(),
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
            method: Method::Instant,
            meshing: Default::default(),
            vpls,
            clamp: r.clamp,
            sampler: SamplerConfig {
                kind: sampler,
                knobs: r.knobs.clone(),
            },
            quality: r.quality.clone(),
            backend: r.backend,
            out: self.out.clone(),
            overwrite: false,
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
        self.cluster.validate()?;
        if self.methods.is_empty() {
            bail!("`methods` needs at least one method");
        }
        if self.samplers.is_empty() {
            bail!("`samplers` needs at least one sampler");
        }
        if self.vpls.is_empty() {
            bail!("`vpls` needs at least one VPL count");
        }
        if self.spp < 2 {
            bail!(
                "`spp` {}: the reference is traced as two independent halves (to measure its own noise), so it needs at least 2 samples per pixel",
                self.spp
            );
        }
        check::int("`spp`", self.spp, 2, MAX_SPP)?;
        once(
            "`methods`",
            self.methods.iter().map(|m| m.name().to_string()),
        )?;
        once("`samplers`", self.samplers.iter().map(|s| s.to_string()))?;
        once("`vpls`", self.vpls.iter().map(|v| v.to_string()))?;
        for sw in &self.sweep {
            once(
                &format!("`sweep` {sw}"),
                sw.values.iter().map(|x| x.to_string()),
            )?;
        }
        if let Some(v) = self.show_vpls {
            if !self.vpls.contains(&v) {
                bail!("`show_vpls` {v} is not one of `vpls` {:?}", self.vpls);
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
                    "`sweep` {sw}: {} is not one of `samplers` {}",
                    sw.sampler,
                    names.join(",")
                );
            }
            if !sw.knob.used_by(sw.sampler) {
                let used: Vec<String> = KNOBS
                    .iter()
                    .filter(|k| k.used_by(sw.sampler))
                    .map(|k| k.setting())
                    .collect();
                bail!(
                    "`sweep` {sw}: {} does not use {} (it uses {})",
                    sw.sampler,
                    sw.knob.setting(),
                    if used.is_empty() {
                        "none of the knobs; sweep `vpls` instead".to_string()
                    } else {
                        used.join(", ")
                    }
                );
            }
            if sw.values.is_empty() {
                bail!("`sweep` {sw}: no values");
            }
            for &x in &sw.values {
                for &v in &self.vpls {
                    self.run_with(sw.sampler, v, Some((sw.knob, x)))
                        .validate()
                        .map_err(|e| anyhow::anyhow!("`sweep` {sw}: {e}"))?;
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
/// Each entry of the list `setting` once: a repeated one would be run (or swept) twice and
/// drawn as two curves on top of each other.
fn once(setting: &str, items: impl Iterator<Item = String>) -> Result<()> {
    let mut seen = std::collections::BTreeSet::new();
    for it in items {
        if !seen.insert(it.clone()) {
            bail!("{setting} lists {it} twice: name each entry once");
        }
    }
    Ok(())
}
