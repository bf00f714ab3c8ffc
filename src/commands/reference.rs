//! `irad reference`: path-traced ground truth, one EXR + PNG per frame and run.json.

use crate::config;
use crate::image::Hdr;
use crate::reference::Sampling;
use crate::report;
use crate::trace::Tracer;
use anyhow::Result;
use serde::Serialize;
use std::time::Instant;

#[derive(Serialize)]
pub(crate) struct ReferenceRun<'a> {
    pub command: &'static str,
    pub scene: &'a str,
    /// The environment that lit the run (see `irad render`'s run.json).
    pub environment: Option<String>,
    pub settings: &'a config::Reference,
    pub frames: Vec<ReferenceFrame>,
    pub threads: usize,
    /// Whether a signal stopped the run before its last frame.
    pub interrupted: bool,
}

/// One traced frame, as run.json records it.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct ReferenceFrame {
    pub frame: u32,
    pub time: f32,
    pub seconds: f64,
    pub mean_rgb: [f32; 3],
}

/// Path-traces frame indices `frames` of `scene`, calling `tick` once per image row and
/// `done` with each finished image (in order).
pub fn trace_frames(
    scene: &crate::scene::Scene,
    seq: &config::Sequence,
    sampling: Sampling,
    frames: impl IntoIterator<Item = u32>,
    tick: &(dyn Fn() + Sync),
    done: &mut dyn FnMut(u32, f32, Hdr) -> Result<()>,
) -> Result<()> {
    trace_walking(scene, seq, sampling, frames, &|_| true, tick, done)
}

/// Path-traces the frames of `walk` that are `wanted`, with the tracer updated through every
/// frame of `walk` (in order) as if all were traced: an image depends only on the seed, the
/// pixel and the tracer, and the tracer's state (its scale, offsets and the split of moving
/// triangles) on the frames it was built and updated with. So any subset of a sequence, traced
/// by walking it from its first frame, is bit-identical to the same frames of the whole
/// sequence traced at once: what lets a reference be cached frame by frame and split into
/// chunks that run on other machines (see `docs/cluster.md`).
pub fn trace_walking(
    scene: &crate::scene::Scene,
    seq: &config::Sequence,
    sampling: Sampling,
    walk: impl IntoIterator<Item = u32>,
    wanted: &dyn Fn(u32) -> bool,
    tick: &(dyn Fn() + Sync),
    done: &mut dyn FnMut(u32, f32, Hdr) -> Result<()>,
) -> Result<()> {
    let p = seq.reference_settings(sampling);
    let mut tracer: Option<Tracer> = None;
    for f in walk {
        let mut frame = scene.at(seq.time(f));
        let tracer = match &mut tracer {
            Some(t) => {
                t.update(&frame);
                t
            }
            None => tracer.insert(Tracer::new(&frame)),
        };
        if !wanted(f) {
            continue;
        }
        // Next-event estimation draws among the emitters whose light gets out, as the
        // renderer's frames do (not a closed lamp's back-emitting twins: trace::solids).
        tracer.keep_lit_emitters(&mut frame);
        let img = crate::reference::render(&frame, tracer, &p, tick);
        done(f, frame.time, img)?;
    }
    Ok(())
}

/// `irad reference`.
pub fn reference(cfg: &config::Reference) -> Result<Vec<Hdr>> {
    cfg.validate()?;
    let seq = &cfg.sequence;
    let spec = seq.scene_or(config::DEFAULT_STILL_SCENE);
    let scene = seq.load_scene(config::DEFAULT_STILL_SCENE)?;
    let out = &cfg.out;
    let frames = seq.frames_or_first();
    let mut planned = report::run_files(frames.iter(), false);
    planned.retain(|f| f != "preview.gif" && f != "frames.jsonl");
    let dir = report::prepare_run_dir(out, planned, cfg.overwrite)?;
    let pb = report::progress(frames.len() as u64 * seq.size.height as u64, "reference");
    let mut record = ReferenceRun {
        command: "reference",
        scene: spec,
        environment: scene.environment.as_deref().map(|e| e.name.clone()),
        settings: cfg,
        frames: Vec::new(),
        threads: rayon::current_num_threads(),
        interrupted: false,
    };
    let mut images = Vec::new();
    let mut start = Instant::now();
    trace_frames(
        &scene,
        seq,
        cfg.sampling(),
        // A signal stops the run between frames (the frame in flight is finished).
        frames.iter().take_while(|_| !crate::interrupt::requested()),
        &|| pb.inc(1),
        &mut |f, time, img| {
            report::write_frame(out, f, &img, cfg.exposure)?;
            record.frames.push(ReferenceFrame {
                frame: f,
                time,
                seconds: start.elapsed().as_secs_f64(),
                mean_rgb: img.mean().to_array(),
            });
            images.push(img);
            start = Instant::now();
            Ok(())
        },
    )?;
    pb.finish_and_clear();
    let done = record.frames.len() as u32;
    record.interrupted = done < frames.len();
    report::write_json(&out.join("run.json"), &record)?;
    dir.finish()?;
    if record.interrupted {
        return Err(crate::interrupt::Interrupted {
            done,
            planned: frames.len(),
            what: format!(
                "wrote their frames and run.json (marked interrupted) to {}",
                out.display()
            ),
        }
        .into());
    }
    for fr in &record.frames {
        crate::outln!(
            "frame {:4}  t={:.3}s  {:.2}s  mean RGB ({:.4}, {:.4}, {:.4})",
            fr.frame,
            fr.time,
            fr.seconds,
            fr.mean_rgb[0],
            fr.mean_rgb[1],
            fr.mean_rgb[2]
        )?;
    }
    let n = crate::report::count(record.frames.len() as u64, "frame", "frames");
    crate::outln!("wrote {n} to {}", out.display())?;
    Ok(images)
}
