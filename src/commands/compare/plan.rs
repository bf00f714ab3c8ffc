//! What a comparison will do, checked before anything renders: the scene, the frames, and
//! every run's settings (against the adapter too), on the one device all runs share.

use crate::config::Method;
use crate::config::{self, Knob};
use crate::gpu::Gpu;
use crate::scene::Scene;
use crate::vpl::sampler::SamplerKind;
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub struct Plan {
    pub cfg: config::Compare,
    pub spec: String,
    pub scene: Scene,
    pub frames: config::Frames,
    /// The frame indices, in order.
    pub numbers: Vec<u32>,
    /// The device every run renders on (None: a plan that renders no run here: one written
    /// for a cluster, a reference chunk, or the collection of a cluster's results).
    pub gpu: Option<Arc<Gpu>>,
    /// Where the reference frames are cached.
    pub cache: PathBuf,
}

/// A run's label: `mh 256`, or `mh 256 mh-rate=0.1` for a run of a sweep.
pub fn label(s: SamplerKind, vpls: u32, knob: Option<(&'static Knob, f64)>) -> String {
    match knob {
        Some((k, v)) => format!("{s} {vpls} {k}={v}"),
        None => format!("{s} {vpls}"),
    }
}

/// One run of a comparison.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSpec {
    pub method: Method,
    pub sampler: SamplerKind,
    pub vpls: u32,
    /// The swept knob and its value (None: the shared settings).
    pub knob: Option<(&'static Knob, f64)>,
    /// Whether the report shows this run's animation.
    pub shown: bool,
}

impl Plan {
    pub fn new(cfg: &config::Compare) -> Result<Plan> {
        Plan::open(cfg, true, true)
    }

    /// The plan of `cfg`: with the device (every run's settings checked against it) when
    /// `gpu`, with the output and cache folders made (and checked writable) when `folders`.
    pub fn open(cfg: &config::Compare, gpu: bool, folders: bool) -> Result<Plan> {
        let device = || -> Result<Arc<Gpu>> { Ok(Arc::new(Gpu::new(cfg.render.backend)?)) };
        Plan::open_with(cfg, if gpu { Some(&device) } else { None }, folders)
    }

    /// [`Plan::open`] on the device `gpu` gives (a caller's shared device), or none.
    pub fn open_with(
        cfg: &config::Compare,
        gpu: Option<&dyn Fn() -> Result<Arc<Gpu>>>,
        folders: bool,
    ) -> Result<Plan> {
        cfg.validate()?;
        let spec = cfg.scene_name().to_string();
        let scene = cfg.sequence.load_scene(config::DEFAULT_ANIMATED_SCENE)?;
        let (frames, note) = cfg.sequence.frames_or_all(scene.duration());
        if let Some(note) = note {
            eprintln!("note: {note}");
        }
        let gpu = gpu.map(|open| open()).transpose()?;
        if let Some(gpu) = &gpu {
            let triangles = scene.at(0.0).tris.len();
            for &v in &cfg.vpls {
                let r = cfg.run(cfg.samplers[0], v);
                crate::gpu::renderer::check_config(
                    &crate::resolve::bounds(&r, triangles),
                    &gpu.limits,
                )?;
                for sw in &cfg.sweep {
                    for &x in &sw.values {
                        let r = cfg.run_with(sw.sampler, v, Some((sw.knob, x)));
                        crate::gpu::renderer::check_config(
                            &crate::resolve::bounds(&r, triangles),
                            &gpu.limits,
                        )
                        .map_err(|e| anyhow::anyhow!("`sweep` {sw}: {e}"))?;
                    }
                }
            }
        }
        let cache = dir(cfg, &spec);
        if folders {
            crate::report::prepare_out_dir(&cfg.out)?;
            crate::report::prepare_out_dir(&cache)?;
        }
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

    /// Every run, in order. Instant radiosity runs every sampler at every VPL count, a swept
    /// sampler once per value of each of its sweeps and VPL count; a classical method runs
    /// once (its sampler and VPL count unused). The report shows the runs at the shown VPL
    /// count, of a swept sampler only its first sweep's first value.
    pub fn runs(&self) -> Vec<RunSpec> {
        let c = &self.cfg;
        let show = c.shown_vpls();
        let mut runs = Vec::new();
        for &method in &c.methods {
            if method == Method::Instant {
                for &sampler in &c.samplers {
                    let mut knobs: Vec<Option<(&'static Knob, f64)>> = c
                        .sweep
                        .iter()
                        .filter(|sw| sw.sampler == sampler)
                        .flat_map(|sw| sw.values.iter().map(|&x| Some((sw.knob, x))))
                        .collect();
                    if knobs.is_empty() {
                        knobs.push(None);
                    }
                    for (i, &knob) in knobs.iter().enumerate() {
                        runs.extend(c.vpls.iter().map(|&vpls| RunSpec {
                            method,
                            sampler,
                            vpls,
                            knob,
                            shown: i == 0 && vpls == show,
                        }));
                    }
                }
            } else {
                runs.push(RunSpec {
                    method,
                    sampler: c.samplers[0],
                    vpls: c.vpls[0],
                    knob: None,
                    shown: true,
                });
            }
        }
        runs
    }

    /// Where each frame's pixels were in the frame before (for warped flicker), from the
    /// scene's exact motion.
    pub fn motion(&self) -> Vec<Vec<Option<crate::metrics::warp::Warp>>> {
        let s = &self.cfg.sequence;
        let frames: Vec<crate::scene::Frame> = self
            .numbers
            .iter()
            .map(|&f| self.scene.at(s.time(f)))
            .collect();
        crate::metrics::warp::motion(&frames, s.size.width, s.size.height)
    }
}

/// The two halves' samples per pixel for a reference of `spp` (at least 2).
pub fn halves(spp: u32) -> [u32; 2] {
    [spp.div_ceil(2), spp / 2]
}

/// The cache folder of a reference.
pub fn dir(cfg: &config::Compare, spec: &str) -> PathBuf {
    let name: String = Path::new(spec)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| spec.to_string())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let s = &cfg.sequence;
    // A --camera of its own: the same scene seen from elsewhere.
    let camera = s
        .camera
        .map(|c| format!("_camera{:016x}", fnv(c.to_string().as_bytes())))
        .unwrap_or_default();
    // An --environment of its own: the same scene lit otherwise (a map by its bytes).
    let environment = s
        .environment
        .as_ref()
        .map(|e| {
            let mut key = e.to_string().into_bytes();
            if let crate::config::EnvironmentChoice::File(p) = e {
                key.extend(std::fs::read(p).unwrap_or_default());
            }
            format!("_env{:016x}", fnv(&key))
        })
        .unwrap_or_default();
    let [a, b] = halves(cfg.spp);
    cfg.cache.join("reference").join(format!(
        "{name}_{:016x}_{}_{}spp_{}fps_seed{}_halves{a}+{b}{camera}{environment}",
        source_hash(spec),
        s.size,
        cfg.spp,
        s.fps,
        s.seed
    ))
}

/// FNV-1a of the scene's source: a built-in's generated text, else the file's bytes (0 if
/// unreadable: loading the scene reports that).
fn source_hash(spec: &str) -> u64 {
    let bytes = crate::scene::builtin::generate(spec)
        .map(String::into_bytes)
        .or_else(|| std::fs::read(spec).ok())
        .unwrap_or_default();
    fnv(&bytes)
}

fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}
