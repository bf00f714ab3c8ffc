//! `irad render`: a sequence's frames (EXR + PNG), an animated preview and the run record.
//!
//! Memory stays flat over long runs: each frame is written and streamed into the GIF as it
//! comes, its record appended to `frames.jsonl`; `run.json` is written once at the end (the
//! settings, the adapter, the summary, and the per-frame records read back from
//! `frames.jsonl`).

use crate::config;
use crate::frame::{FrameOutput, Pipeline};
use crate::gpu::{AdapterDesc, Gpu};
use crate::report;
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;

/// One frame's record (a line of `frames.jsonl`, and an entry of `run.json`'s `frames`).
#[derive(Serialize)]
pub struct FrameRecord {
    pub frame: u32,
    pub time: f32,
    pub seconds: f64,
    /// Seconds per stage (CPU stages and GPU passes)...
    pub stages: std::collections::BTreeMap<String, f64>,
    /// ...and the order they ran in.
    pub stage_order: Vec<String>,
    pub vpls: usize,
    pub paths: u64,
    pub replaced: f32,
    pub acceptance: Option<f32>,
    /// MH: the frame's proposal rate; SMC: its renewal rate (the sampler's `renewal_rate`).
    pub renewal_rate: Option<f32>,
    pub b: Option<f32>,
    pub importance_seconds: f64,
    pub mean_rgb: [f32; 3],
    /// Resident memory of the process after the frame, in MiB (Linux).
    pub rss_mib: Option<f64>,
    /// What the GPU kept from the previous frame (uploads, shadow maps, ISM tiles).
    pub reused: crate::gpu::renderer::Reuse,
    /// What the raster passes drew of the triangles (after leaving out what each view
    /// cannot see).
    pub drawn: crate::gpu::renderer::Drawn,
    /// How the GPU passes were timed (timestamps, serialized, off).
    pub profiling: crate::gpu::Profiling,
    /// A classical method: whether this frame solved (else it reused the solution).
    pub radiosity_solved: Option<bool>,
    /// The classical solve's figures, in the frame that solved.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radiosity: Option<crate::radiosity::Stats>,
}

impl FrameRecord {
    pub fn of(fo: &FrameOutput) -> FrameRecord {
        FrameRecord {
            frame: fo.index,
            time: fo.time,
            seconds: fo.seconds,
            stages: fo.stages.iter().map(|(n, t)| (n.to_string(), *t)).collect(),
            stage_order: fo.stages.iter().map(|(n, _)| n.to_string()).collect(),
            vpls: fo.selection.vpls.len(),
            paths: fo.selection.paths,
            replaced: fo.selection.replaced,
            acceptance: fo.selection.acceptance,
            renewal_rate: fo.selection.renewal_rate,
            b: fo.selection.b,
            importance_seconds: fo.selection.importance_s,
            mean_rgb: fo.image.hdr.mean().to_array(),
            rss_mib: report::resident_bytes().map(|b| b as f64 / (1 << 20) as f64),
            reused: fo.image.reused,
            drawn: fo.image.drawn,
            profiling: fo.image.profiling,
            radiosity_solved: fo.solved,
            radiosity: fo.radiosity.clone(),
        }
    }
}

/// Mean seconds per stage over frames, in the first frame's order.
#[derive(Default, Serialize)]
pub struct StageMeans {
    pub frames: u32,
    pub seconds: f64,
    pub stages: Vec<(String, f64)>,
}

impl StageMeans {
    pub fn add(&mut self, r: &FrameRecord) {
        if self.stages.is_empty() {
            self.stages = r.stage_order.iter().map(|n| (n.clone(), 0.0)).collect();
        }
        for (name, t) in self.stages.iter_mut() {
            *t += r.stages.get(name.as_str()).copied().unwrap_or(0.0);
        }
        self.seconds += r.seconds;
        self.frames += 1;
    }
    /// Means over the frames added.
    pub fn means(&self) -> (f64, Vec<(String, f64)>) {
        let n = self.frames.max(1) as f64;
        (
            self.seconds / n,
            self.stages
                .iter()
                .map(|(s, t)| (s.clone(), t / n))
                .collect(),
        )
    }
    /// Prints one line per stage that took any time (stages a run skipped are left out).
    pub fn print(&self) -> std::io::Result<()> {
        let (frame, stages) = self.means();
        crate::outln!("mean seconds per frame: {frame:.3}")?;
        for (name, t) in stages.iter().filter(|(_, t)| *t > 0.0) {
            crate::outln!("  {name:14} {:8.2} ms", t * 1e3)?;
        }
        Ok(())
    }
}

#[derive(Serialize)]
struct RunRecord<'a> {
    command: &'static str,
    scene: &'a str,
    /// The environment that lit the run (`sky` or a map's path; null: none), whether chosen
    /// by `--environment` or given by the loader to a scene without lights.
    environment: Option<&'a str>,
    adapter: &'a AdapterDesc,
    settings: &'a config::Render,
    /// What the resolve step chose for the scene and adapter (`crate::resolve`).
    gpu: &'a crate::gpu::RendererConfig,
    sampler: &'a crate::vpl::sampler::SamplerParams,
    frames_rendered: u32,
    /// Whether a signal stopped the run before its last frame.
    interrupted: bool,
    mean: &'a StageMeans,
    frames: Vec<serde_json::Value>,
}

/// What a render did, for a caller of the library.
pub struct RenderSummary {
    pub adapter: AdapterDesc,
    pub frames: config::Frames,
    pub mean_seconds: f64,
}

/// `irad render` on a device of its own.
pub fn render(cfg: &config::Render) -> Result<RenderSummary> {
    cfg.validate()?;
    let gpu = Arc::new(Gpu::new(cfg.backend)?);
    render_on(gpu, cfg)
}

/// `irad render` on a device the caller opened.
pub fn render_on(gpu: Arc<Gpu>, cfg: &config::Render) -> Result<RenderSummary> {
    let spec = cfg.scene_name();
    // Sizes are checked against the adapter, and the folder for writing, before any frame.
    let (mut pipeline, frames, note) = start(gpu, cfg, None)?;
    let out = &cfg.out;
    let dir = report::prepare_run_dir(
        out,
        report::run_files(frames.iter(), cfg.components),
        cfg.overwrite,
    )?;
    if let Some(note) = note {
        eprintln!("note: {note}");
    }
    let adapter = pipeline.renderer.gpu.adapter.clone();
    let mut log = report::JsonLines::create(&out.join("frames.jsonl"))?;
    let mut gif = report::GifStream::create(&out.join("preview.gif"), cfg.sequence.fps)?;
    let mut means = StageMeans::default();
    let pb = report::progress(frames.len() as u64, "render");
    let bar = pb.clone();
    pipeline.on_solve_progress(move |s| bar.set_detail(s.to_string()));
    let mut done = 0;
    for f in frames.iter() {
        // A signal stops the run between frames: what is done is written as a whole run's.
        if crate::interrupt::requested() {
            break;
        }
        let fo = pipeline.render_frame(f, cfg.components)?;
        // A signal during the frame (a long radiosity solve stops early): drop the frame.
        if crate::interrupt::requested() {
            break;
        }
        // The record first: frames.jsonl lists every frame whose files are on disk (a run
        // killed between the two leaves a record whose files are missing, never the reverse).
        let record = FrameRecord::of(&fo);
        log.push(&record)?;
        means.add(&record);
        let png = write_frame(out, &fo, cfg)?;
        gif.push(&png)?;
        done += 1;
        pb.inc(1);
    }
    let interrupted = done < frames.len();
    pb.finish_and_clear();
    drop(log);
    gif.finish()?;
    report::write_json(
        &out.join("run.json"),
        &RunRecord {
            command: "render",
            scene: spec,
            environment: pipeline
                .scene
                .environment
                .as_deref()
                .map(|e| e.name.as_str()),
            adapter: &adapter,
            settings: cfg,
            gpu: &pipeline.renderer.config,
            sampler: &pipeline.params,
            frames_rendered: done,
            interrupted,
            mean: &means,
            frames: read_json_lines(&out.join("frames.jsonl"))?,
        },
    )?;
    dir.finish()?;
    if interrupted {
        return Err(crate::interrupt::Interrupted {
            done,
            planned: frames.len(),
            what: format!(
                "wrote their frames, preview.gif and run.json (marked interrupted) to {}",
                out.display()
            ),
        }
        .into());
    }
    crate::outln!("adapter: {adapter}")?;
    let method = match cfg.method {
        crate::config::Method::Instant => {
            format!("{} VPLs, sampler {}", cfg.vpls, cfg.sampler.kind)
        }
        m => format!("method {}", m.name()),
    };
    crate::outln!(
        "{} of {spec} at {}, {method}",
        report::count(frames.len(), "frame", "frames"),
        cfg.sequence.size
    )?;
    means.print()?;
    crate::outln!(
        "wrote {}/frame_*.exr, frame_*.png, preview.gif, run.json, frames.jsonl",
        out.display()
    )?;
    Ok(RenderSummary {
        adapter,
        frames,
        mean_seconds: means.means().0,
    })
}

/// A render without its files: `cfg` checked, the scene loaded (or `scene`, given `cfg`'s
/// camera and environment), the pipeline built on `gpu` and the frames to render (with the
/// note when a long animation is capped). [`render_on`] writes each
/// [`Pipeline::render_frame`]'s output; a library caller (the Python package) keeps it.
pub fn start(
    gpu: Arc<Gpu>,
    cfg: &config::Render,
    scene: Option<crate::scene::Scene>,
) -> Result<(Pipeline, config::Frames, Option<String>)> {
    cfg.validate()?;
    let scene = match scene {
        Some(s) => cfg.sequence.prepare_scene(s)?,
        None => cfg.sequence.load_scene(config::DEFAULT_ANIMATED_SCENE)?,
    };
    let pipeline = Pipeline::new(gpu, scene, cfg)?;
    let (frames, note) = cfg.sequence.frames_or_all(pipeline.scene.duration());
    Ok((pipeline, frames, note))
}

/// Writes a frame's EXR and PNG (and its components'); returns the PNG's image.
fn write_frame(out: &Path, fo: &FrameOutput, cfg: &config::Render) -> Result<image::RgbImage> {
    let stem = report::frame_stem(fo.index);
    if let (Some(d), Some(i)) = (&fo.image.direct, &fo.image.indirect) {
        for (img, part) in [(d, "direct"), (i, "indirect")] {
            img.write_exr(&out.join(format!("{stem}_{part}.exr")))?;
            img.write_png(&out.join(format!("{stem}_{part}.png")), cfg.exposure)?;
        }
    }
    fo.image.hdr.write_exr(&out.join(format!("{stem}.exr")))?;
    let (w, h) = (cfg.sequence.size.width, cfg.sequence.size.height);
    let png = image::RgbImage::from_raw(w, h, fo.image.ldr.clone()).expect("w*h*3 bytes");
    crate::image::write_bytes(
        &out.join(format!("{stem}.png")),
        &crate::image::encode(&png, image::ImageFormat::Png)?,
    )?;
    Ok(png)
}

/// The records of a JSON Lines file.
pub fn read_json_lines(path: &Path) -> Result<Vec<serde_json::Value>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).with_context(|| format!("{}: bad line", path.display())))
        .collect()
}
