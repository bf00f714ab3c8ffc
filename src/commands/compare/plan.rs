//! What a comparison will do, checked before anything renders: the scene, the frames, and
//! every run's settings (against the adapter too), on the one device all runs share.

use crate::config;
use crate::gpu::Gpu;
use crate::radiosity::Method;
use crate::scene::Scene;
use crate::vpl::sampler::SamplerKind;
use anyhow::Result;
use std::path::PathBuf;
use std::sync::Arc;

pub struct Plan {
    pub cfg: config::Compare,
    pub spec: String,
    pub scene: Scene,
    pub frames: config::Frames,
    /// The frame indices, in order.
    pub numbers: Vec<u32>,
    pub gpu: Arc<Gpu>,
    /// Where the reference frames are cached.
    pub cache: PathBuf,
}

/// A run's label: `mh 256`.
pub fn label(s: SamplerKind, vpls: u32) -> String {
    format!("{s} {vpls}")
}

impl Plan {
    pub fn new(cfg: &config::Compare) -> Result<Plan> {
        cfg.validate()?;
        let spec = cfg.scene_name().to_string();
        let scene = cfg.sequence.load_scene(config::DEFAULT_ANIMATED_SCENE)?;
        let (frames, note) = cfg.sequence.frames_or_all(scene.duration());
        if let Some(note) = note {
            eprintln!("note: {note}");
        }
        let gpu = Arc::new(Gpu::new(cfg.render.backend)?);
        for &v in &cfg.vpls {
            let r = cfg.run(cfg.samplers[0], v);
            crate::gpu::renderer::check_config(&r.renderer_config(), &gpu.limits)?;
        }
        crate::report::prepare_out_dir(&cfg.out)?;
        let cache = super::reference_cache::dir(cfg, &spec);
        crate::report::prepare_out_dir(&cache)?;
        Ok(Plan {
            cfg: cfg.clone(),
            numbers: frames.iter().collect(),
            spec,
            scene,
            frames,
            gpu,
            cache,
        })
    }

    /// Every run, in order: (method, sampler, VPLs). Instant radiosity runs every sampler at
    /// every VPL count; a classical method runs once (its sampler and VPL count unused).
    pub fn runs(&self) -> Vec<(Method, SamplerKind, u32)> {
        let c = &self.cfg;
        let mut runs = Vec::new();
        for &m in &c.methods {
            if m == Method::Instant {
                for &s in &c.samplers {
                    runs.extend(c.vpls.iter().map(|&v| (m, s, v)));
                }
            } else {
                runs.push((m, c.samplers[0], c.vpls[0]));
            }
        }
        runs
    }

    /// The progress bar's length: reference rows still to trace, plus every run's frames.
    pub fn work_units(&self) -> u64 {
        let missing = super::reference_cache::missing(self) as u64;
        let runs = self.runs().len() as u64;
        missing * self.cfg.sequence.size.height as u64 + runs * self.numbers.len() as u64
    }
}
