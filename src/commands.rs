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
        opts.frames_or_first().len() as u64 * opts.size.height as u64,
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
    for f in opts.frames_or_first().iter() {
        let start = Instant::now();
        let frame = scene.at(opts.time(f));
        match &mut tracer {
            Some(t) => {
                t.update(&frame);
            }
            None => tracer = Some(Tracer::new(&frame)),
        }
        let img =
            crate::reference::render(&frame, tracer.as_ref().expect("set above"), &s, &|| {
                pb.inc(1)
            });
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

/// `irad scenes`: the built-in scenes and what each stresses; `--generate DIR` writes them;
/// `irad scenes FILE` inspects one.
pub fn scenes(scene: Option<&str>, generate: Option<&Path>) -> Result<()> {
    if let Some(spec) = scene {
        print!(
            "{}",
            crate::scene::inspect::inspect(&builtin::load_any(spec)?)
        );
        return Ok(());
    }
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

/// `irad info`: the adapters found and the one irad would choose.
pub fn info(backend: crate::gpu::BackendChoice) -> Result<()> {
    let list = crate::gpu::adapters(backend);
    if list.is_empty() {
        println!("no adapters found");
    }
    for (a, usable) in &list {
        println!("{} {a}", if *usable { "usable " } else { "no     " });
    }
    let gpu = crate::gpu::Gpu::new(backend)?;
    println!("chosen: {}", gpu.adapter);
    let l = &gpu.limits;
    println!(
        "limits: storage buffer {} MiB, 2D texture {}, array layers {}",
        l.max_storage_buffer_binding_size >> 20,
        l.max_texture_dimension_2d,
        l.max_texture_array_layers
    );
    Ok(())
}

/// The GPU renderer's options.
#[derive(clap::Args, Clone, Debug)]
pub struct RenderOpts {
    #[command(flatten)]
    pub scene: SceneOpts,
    /// VPL slots per frame
    #[arg(long, default_value_t = 256)]
    pub vpls: u32,
    /// Distance clamp dmin of the VPL contribution, in scene units (0: off); default 2% of
    /// the scene's bounding-box diagonal
    #[arg(long)]
    pub clamp: Option<f32>,
    /// VPL sampler
    #[arg(long, value_enum, default_value = "uniform")]
    pub sampler: crate::frame::SamplerKind,
    /// M: candidate VPLs a frame for cdf and mh [default: 4 x --vpls]
    #[arg(long)]
    pub candidates: Option<u32>,
    /// K: camera points for importance
    #[arg(long, default_value_t = 256)]
    pub camera_points: u32,
    /// Defensive floor of the importance, as a fraction of its mean
    #[arg(long, default_value_t = 0.05)]
    pub eps: f32,
    /// MH: probability that a chain proposes in a frame (1: one step every frame; lower keeps
    /// VPLs longer, at the cost of following a moving view more slowly)
    #[arg(long, default_value_t = 1.0)]
    pub mh_rate: f32,
    /// MH: extra proposals in a frame for a chain whose VPL no camera point sees (0: none)
    #[arg(long, default_value_t = 8)]
    pub mh_escape: u32,
    /// Graphics backend (also WGPU_BACKEND=vulkan|gl|metal|dx12 with auto)
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: crate::gpu::BackendChoice,
    /// Output folder
    #[arg(long, default_value = "out")]
    pub out: std::path::PathBuf,
    /// Exposure of the PNG previews (EXR files are linear, unscaled)
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// ISM tile side in texels (power of two)
    #[arg(long, default_value_t = 64)]
    pub ism_size: u32,
    /// Points each VPL splats into its ISM
    #[arg(long, default_value_t = 4096)]
    pub ism_points: u32,
    /// Pull-push levels of the ISMs (holes up to 2^levels texels are filled)
    #[arg(long, default_value_t = 3)]
    pub pull_levels: u32,
    /// ISM depth bias, in texel footprints
    #[arg(long, default_value_t = 1.5)]
    pub ism_bias: f32,
    /// Emitter samples for direct light (each a shadow hemicube)
    #[arg(long, default_value_t = 32)]
    pub light_samples: u32,
    /// Shadow hemicube face side in texels
    #[arg(long, default_value_t = 256)]
    pub shadow_size: u32,
    /// Also write each frame's direct and indirect light (frame_FFFF_direct.exr/.png, _indirect)
    #[arg(long)]
    pub components: bool,
}

impl RenderOpts {
    /// The GPU renderer's configuration.
    pub fn config(&self) -> crate::gpu::RendererConfig {
        crate::gpu::RendererConfig {
            width: self.scene.size.width,
            height: self.scene.size.height,
            max_vpls: self.vpls,
            ism_size: self.ism_size,
            points_per_vpl: self.ism_points,
            num_points: self
                .ism_points
                .saturating_mul(16)
                .clamp(1 << 16, 1 << 22)
                .max(self.ism_points),
            pull_levels: self.pull_levels,
            ism_bias: self.ism_bias,
            light_samples: self.light_samples,
            shadow_size: self.shadow_size,
            shadow_bias: 1.5,
            exposure: self.exposure,
            seed: self.scene.seed,
        }
    }

    /// The sequence settings for `scene`.
    pub fn settings(&self, scene: &Scene) -> Result<crate::frame::Settings> {
        let dmin = match self.clamp {
            Some(c) if c.is_finite() && c >= 0.0 => c,
            Some(c) => bail!("--clamp {c} must be a distance >= 0"),
            None => {
                let (lo, hi) = scene.at(0.0).bounds();
                0.02 * (hi - lo).length()
            }
        };
        if !(self.eps.is_finite() && self.eps >= 0.0) {
            bail!("--eps {} must be >= 0", self.eps);
        }
        if self.camera_points == 0 || self.camera_points > 1 << 20 {
            bail!(
                "--camera-points {} is out of range (1 to 1048576)",
                self.camera_points
            );
        }
        if !(self.mh_rate > 0.0 && self.mh_rate <= 1.0) {
            bail!("--mh-rate {} must be in (0, 1]", self.mh_rate);
        }
        let candidates = self.candidates.unwrap_or(self.vpls.saturating_mul(4));
        if candidates == 0 || candidates > 1 << 24 {
            bail!("--candidates {candidates} is out of range (1 to 16777216)");
        }
        Ok(crate::frame::Settings {
            sampler: crate::vpl::sampler::SamplerParams {
                kind: self.sampler,
                slots: self.vpls as usize,
                candidates: candidates as usize,
                camera_points: self.camera_points as usize,
                eps: self.eps,
                mh_rate: self.mh_rate,
                mh_escape: self.mh_escape,
                dmin,
                seed: self.scene.seed,
                width: self.scene.size.width,
                height: self.scene.size.height,
            },
            fps: self.scene.fps,
        })
    }
}

#[derive(Serialize)]
struct RenderRun<'a> {
    command: &'static str,
    scene: &'a str,
    adapter: crate::gpu::AdapterDesc,
    settings: &'a crate::frame::Settings,
    gpu: &'a crate::gpu::RendererConfig,
    frames: Vec<RenderFrame>,
}

#[derive(Serialize)]
struct RenderFrame {
    frame: u32,
    time: f32,
    seconds: f64,
    stages: std::collections::BTreeMap<String, f64>,
    stage_order: Vec<&'static str>,
    vpls: usize,
    paths: u64,
    replaced: f32,
    acceptance: Option<f32>,
    b: Option<f32>,
    importance_seconds: f64,
    mean_rgb: [f32; 3],
}

/// `irad render`: frames, an animated preview and the run record.
pub fn render(opts: &RenderOpts) -> Result<()> {
    opts.scene.validate()?;
    if !(opts.exposure.is_finite() && opts.exposure > 0.0) {
        bail!("--exposure {} must be > 0", opts.exposure);
    }
    let spec = opts.scene.scene_or("cornell-orbit");
    let scene = load_scene(spec)?;
    let settings = opts.settings(&scene)?;
    let out = &opts.out;
    // Sizes are checked against the adapter, and the folder for writing, before any frame.
    let mut pipeline =
        crate::frame::Pipeline::new(scene, settings.clone(), opts.config(), opts.backend)?;
    report::prepare_out_dir(out)?;
    eprintln!("adapter: {}", pipeline.renderer.gpu.adapter);
    let mut record = RenderRun {
        command: "render",
        scene: spec,
        adapter: pipeline.renderer.gpu.adapter.clone(),
        settings: &settings,
        gpu: &pipeline.renderer.config.clone(),
        frames: Vec::new(),
    };
    let frames = opts.scene.frames_or_all(pipeline.scene.duration());
    let pb = report::progress(frames.len() as u64, "render");
    let mut previews = Vec::new();
    for f in frames.iter() {
        let fo = pipeline.render_frame(f, opts.components)?;
        let stem = report::frame_stem(f);
        if let (Some(d), Some(i)) = (&fo.image.direct, &fo.image.indirect) {
            for (img, part) in [(d, "direct"), (i, "indirect")] {
                img.write_exr(&out.join(format!("{stem}_{part}.exr")))?;
                img.write_png(&out.join(format!("{stem}_{part}.png")), opts.exposure)?;
            }
        }
        fo.image.hdr.write_exr(&out.join(format!("{stem}.exr")))?;
        let (w, h) = (opts.scene.size.width, opts.scene.size.height);
        let png = image::RgbImage::from_raw(w, h, fo.image.ldr.clone()).expect("w*h*3 bytes");
        crate::image::atomic_write(&out.join(format!("{stem}.png")), |tmp| {
            png.save_with_format(tmp, image::ImageFormat::Png)
                .map_err(anyhow::Error::from)
        })?;
        previews.push(png);
        record.frames.push(RenderFrame {
            frame: f,
            time: fo.time,
            seconds: fo.seconds,
            stages: fo.stages.iter().map(|(n, t)| (n.to_string(), *t)).collect(),
            stage_order: fo.stages.iter().map(|(n, _)| *n).collect(),
            vpls: fo.selection.vpls.len(),
            paths: fo.selection.paths,
            replaced: fo.selection.replaced,
            acceptance: fo.selection.acceptance,
            b: fo.selection.b,
            importance_seconds: fo.selection.importance_s,
            mean_rgb: fo.image.hdr.mean().to_array(),
        });
        report::write_json(&out.join("run.json"), &record)?;
        pb.inc(1);
    }
    pb.finish_and_clear();
    report::write_gif(&out.join("preview.gif"), &previews, opts.scene.fps)?;
    let n = record.frames.len() as f64;
    let mean = |name: &str| {
        record
            .frames
            .iter()
            .map(|f| f.stages.get(name).copied().unwrap_or(0.0))
            .sum::<f64>()
            / n
    };
    println!("adapter: {}", record.adapter);
    println!(
        "{} frames of {} at {}, {} VPLs, sampler {:?}",
        record.frames.len(),
        spec,
        opts.scene.size,
        opts.vpls,
        settings.sampler.kind
    );
    println!(
        "mean seconds per frame: {:.3}",
        record.frames.iter().map(|f| f.seconds).sum::<f64>() / n
    );
    for name in &record.frames[0].stage_order {
        println!("  {name:14} {:8.2} ms", mean(name) * 1e3);
    }
    println!(
        "wrote {}/frame_*.exr, frame_*.png, preview.gif, run.json",
        out.display()
    );
    Ok(())
}

/// One bench configuration: VPL count and image size, written `256@256x256`.
#[derive(Clone, Copy, Debug)]
pub struct BenchConfig {
    pub vpls: u32,
    pub size: crate::cli::Size,
}

impl std::str::FromStr for BenchConfig {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (v, size) = s
            .split_once('@')
            .ok_or_else(|| format!("'{s}' is not VPLS@WxH (e.g. 256@256x256)"))?;
        Ok(BenchConfig {
            vpls: v.parse().map_err(|_| format!("'{v}' is not a VPL count"))?,
            size: size.parse()?,
        })
    }
}

#[derive(Serialize)]
struct BenchRow {
    vpls: u32,
    size: String,
    frames: u32,
    seconds_per_frame: f64,
    stages: Vec<(&'static str, f64)>,
}

/// `irad bench`: time per stage of whole frames, averaged after one warm-up frame.
pub fn bench(opts: &RenderOpts, configs: &[BenchConfig], frames: u32) -> Result<()> {
    opts.scene.validate()?;
    let spec = opts.scene.scene_or("cornell");
    let scene = load_scene(spec)?;
    let mut rows = Vec::new();
    let mut adapter = None;
    let pb = report::progress(configs.len() as u64 * (frames as u64 + 1), "bench");
    for c in configs {
        let mut o = opts.clone();
        o.vpls = c.vpls;
        o.scene.size = c.size;
        let settings = o.settings(&scene)?;
        let mut p = crate::frame::Pipeline::new(scene.clone(), settings, o.config(), o.backend)?;
        adapter = Some(p.renderer.gpu.adapter.clone());
        p.render_frame(0, false)?;
        pb.inc(1);
        let mut sum: Vec<(&'static str, f64)> = Vec::new();
        let mut total = 0.0;
        for f in 0..frames {
            let fo = p.render_frame(f, false)?;
            if sum.is_empty() {
                sum = fo.stages.iter().map(|&(n, _)| (n, 0.0)).collect();
            }
            for (acc, (_, t)) in sum.iter_mut().zip(&fo.stages) {
                acc.1 += t;
            }
            total += fo.seconds;
            pb.inc(1);
        }
        rows.push(BenchRow {
            vpls: c.vpls,
            size: c.size.to_string(),
            frames,
            seconds_per_frame: total / frames as f64,
            stages: sum
                .into_iter()
                .map(|(n, t)| (n, t / frames as f64))
                .collect(),
        });
    }
    pb.finish_and_clear();
    let Some(adapter) = adapter else {
        bail!("no bench configuration given")
    };
    println!("scene {spec}, adapter {adapter}, {} CPU threads, mean of {frames} frames after one warm-up", rayon::current_num_threads());
    print!("{:16}", "stage (ms)");
    for r in &rows {
        print!("{:>20}", format!("{} VPLs {}", r.vpls, r.size));
    }
    println!();
    for (i, (name, _)) in rows[0].stages.iter().enumerate() {
        print!("{name:16}");
        for r in &rows {
            print!("{:>20.2}", r.stages[i].1 * 1e3);
        }
        println!();
    }
    print!("{:16}", "frame");
    for r in &rows {
        print!("{:>20.2}", r.seconds_per_frame * 1e3);
    }
    println!();
    report::prepare_out_dir(&opts.out)?;
    report::write_json(
        &opts.out.join("bench.json"),
        &serde_json::json!({ "scene": spec, "adapter": adapter, "rows": rows }),
    )?;
    Ok(())
}

/// Writes per-frame metrics as CSV.
pub fn metrics_csv(m: &crate::metrics::SequenceMetrics) -> String {
    let mut s = String::from("frame,rel_mse,rmse,bias,rel_bias,flicker,flicker_rms,flip\n");
    for f in &m.frames {
        let o = |x: Option<f64>| x.map(|v| format!("{v:.8}")).unwrap_or_default();
        s += &format!(
            "{},{:.8},{:.8},{:.8},{:.8},{},{},{:.6}\n",
            f.frame,
            f.error.rel_mse,
            f.error.rmse,
            f.error.bias,
            f.error.rel_bias,
            o(f.flicker),
            o(f.flicker_rms),
            f.flip
        );
    }
    s
}

/// `irad metrics TEST REFERENCE`: error and flicker of one image sequence against another.
pub fn metrics(
    test: &Path,
    reference: &Path,
    out: Option<&Path>,
) -> Result<crate::metrics::SequenceMetrics> {
    let (numbers, t, r) = crate::metrics::read_pair(test, reference)?;
    let m = crate::metrics::sequence(&numbers, &t, &r)?;
    println!(
        "{:>6} {:>10} {:>10} {:>10} {:>10} {:>8}",
        "frame", "relMSE", "RMSE", "bias", "flicker", "FLIP"
    );
    for f in &m.frames {
        println!(
            "{:>6} {:>10.5} {:>10.5} {:>+10.5} {:>10} {:>8.4}",
            f.frame,
            f.error.rel_mse,
            f.error.rmse,
            f.error.bias,
            f.flicker
                .map(|v| format!("{v:.5}"))
                .unwrap_or_else(|| "-".into()),
            f.flip
        );
    }
    println!(
        "mean relMSE {:.5}, RMSE {:.5}, bias {:+.5}, FLIP {:.4}; flicker F1 {:.5} (RMS {:.5}); temporal variance {:.3e}, temporal bias^2 {:.3e}",
        m.mean_rel_mse, m.mean_rmse, m.mean_bias, m.mean_flip, m.flicker_f1, m.flicker_rms, m.temporal_variance, m.temporal_bias
    );
    let dir = out.unwrap_or(test);
    report::prepare_out_dir(dir)?;
    report::write_json(&dir.join("metrics.json"), &m)?;
    crate::image::write_bytes(&dir.join("metrics.csv"), metrics_csv(&m).as_bytes())?;
    println!("wrote {}/metrics.json and metrics.csv", dir.display());
    Ok(m)
}
