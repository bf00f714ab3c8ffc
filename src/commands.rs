//! The command implementations behind `irad`'s subcommands.

use crate::cli::SceneOpts;
use crate::image::Hdr;
use crate::report;
use crate::scene::{builtin, Scene};
use crate::trace::Tracer;
use anyhow::{bail, Result};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// Loads the scene and prints its warnings.
pub fn load_scene(spec: &str) -> Result<Scene> {
    let scene = builtin::load_any(spec)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

#[derive(Serialize)]
struct ReferenceRun<'a> {
    command: &'static str,
    scene: &'a str,
    width: u32,
    height: u32,
    spp: u32,
    fps: f32,
    seed: u64,
    frames: Vec<ReferenceFrame>,
    threads: usize,
}

#[derive(Serialize)]
struct ReferenceFrame {
    frame: u32,
    time: f32,
    seconds: f64,
    mean_rgb: [f32; 3],
}

/// `irad reference`: path-traced ground truth, one EXR + PNG per frame and run.json.
pub fn reference(opts: &SceneOpts, spp: u32, out: &Path, exposure: f32) -> Result<Vec<Hdr>> {
    opts.validate()?;
    if spp == 0 || spp > 1 << 20 {
        bail!("--spp {spp} is out of range (1 to 1048576)");
    }
    let spec = opts.scene_or("cornell");
    let scene = load_scene(spec)?;
    report::prepare_out_dir(out)?;
    let s = crate::reference::Settings {
        width: opts.size.width,
        height: opts.size.height,
        spp,
        seed: opts.seed,
    };
    let pb = report::progress(
        opts.frames.len() as u64 * opts.size.height as u64,
        "reference",
    );
    let mut record = ReferenceRun {
        command: "reference",
        scene: spec,
        width: s.width,
        height: s.height,
        spp,
        fps: opts.fps,
        seed: opts.seed,
        frames: Vec::new(),
        threads: rayon::current_num_threads(),
    };
    let mut tracer: Option<Tracer> = None;
    let mut images = Vec::new();
    for f in opts.frames.iter() {
        let start = Instant::now();
        let frame = scene.at(opts.time(f));
        match &mut tracer {
            Some(t) => {
                t.update(&frame);
            }
            None => tracer = Some(Tracer::new(&frame)),
        }
        let img = crate::reference::render(
            &frame,
            tracer.as_ref().expect("set above"),
            &s,
            f as u64,
            &|| pb.inc(1),
        );
        let seconds = start.elapsed().as_secs_f64();
        report::write_frame(out, f, &img, exposure)?;
        record.frames.push(ReferenceFrame {
            frame: f,
            time: frame.time,
            seconds,
            mean_rgb: img.mean().to_array(),
        });
        report::write_json(&out.join("run.json"), &record)?;
        images.push(img);
    }
    pb.finish_and_clear();
    for fr in &record.frames {
        println!(
            "frame {:4}  t={:.3}s  {:.2}s  mean RGB ({:.4}, {:.4}, {:.4})",
            fr.frame, fr.time, fr.seconds, fr.mean_rgb[0], fr.mean_rgb[1], fr.mean_rgb[2]
        );
    }
    println!("wrote {} frames to {}", record.frames.len(), out.display());
    Ok(images)
}

/// `irad scenes`: the built-in scenes and what each stresses; `--generate DIR` writes them.
pub fn scenes(generate: Option<&Path>) -> Result<()> {
    if let Some(dir) = generate {
        report::prepare_out_dir(dir)?;
        for b in builtin::BUILTINS {
            let text = builtin::generate(b.name).expect("every built-in has a generator");
            let path = dir.join(format!("{}.gltf", b.name));
            crate::image::write_bytes(&path, text.as_bytes())?;
            println!("wrote {}", path.display());
        }
        return Ok(());
    }
    for b in builtin::BUILTINS {
        let scene = builtin::load(b.name).expect("listed")?;
        let f = scene.at(0.0);
        println!(
            "{:14} {:5} triangles  {:4.1} s  {}",
            b.name,
            f.tris.len(),
            scene.duration(),
            b.stresses
        );
    }
    Ok(())
}
