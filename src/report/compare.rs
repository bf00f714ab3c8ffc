//! `irad compare`: samplers x VPL counts on one animation, against a (cached) reference:
//! metrics.csv/json, charts (SVG and PNG) and a self-contained report.html.

use super::charts::{self, Chart, Kind, Series};
use super::html;
use crate::cli::SceneOpts;
use crate::commands::{load_scene, RenderOpts};
use crate::frame::{Pipeline, SamplerKind};
use crate::image::{write_bytes, Hdr};
use crate::metrics::{self, SequenceMetrics};
use anyhow::{bail, Context, Result};
use clap::Parser;
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Clone, Debug)]
pub struct CompareOpts {
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Samplers to compare
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "uniform,cdf,mh"
    )]
    pub samplers: Vec<SamplerKind>,
    /// VPL counts to compare
    #[arg(long, value_delimiter = ',', default_value = "64,256,1024")]
    pub vpls: Vec<u32>,
    /// Samples per pixel of the reference
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    /// Output folder
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Where reference frames are cached (keyed by scene, size, spp, fps and seed)
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Graphics backend
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: crate::gpu::BackendChoice,
    /// MH: probability that a chain proposes in a frame
    #[arg(long, default_value_t = 0.1)]
    pub mh_rate: f32,
    /// MH: extra proposals for a chain whose VPL no camera point sees
    #[arg(long, default_value_t = 8)]
    pub mh_escape: u32,
    /// The VPL count whose animations the report shows [default: the middle one]
    #[arg(long)]
    pub show_vpls: Option<u32>,
    /// Exposure of previews
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
}

#[derive(Parser)]
struct Defaults {
    #[command(flatten)]
    render: RenderOpts,
}

#[derive(Serialize)]
struct RunRecord {
    sampler: SamplerKind,
    vpls: u32,
    mean_seconds: f64,
    mean_replaced: f64,
    mean_acceptance: Option<f64>,
    metrics: SequenceMetrics,
    seconds: Vec<f64>,
    replaced: Vec<f32>,
    acceptance: Vec<Option<f32>>,
}

fn label(s: SamplerKind, v: u32) -> String {
    format!("{} {v}", format!("{s:?}").to_lowercase())
}

/// The cache folder of a reference.
fn cache_dir(o: &CompareOpts, spec: &str) -> PathBuf {
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
    o.cache.join("reference").join(format!(
        "{name}_{}_{}spp_{}fps_seed{}",
        o.scene.size, o.spp, o.scene.fps, o.scene.seed
    ))
}

/// Luminance error heat image (white = error of 0.25 or more), 8-bit.
fn error_image(t: &Hdr, r: &Hdr) -> image::RgbImage {
    let data = t
        .data
        .iter()
        .zip(&r.data)
        .flat_map(|(a, b)| {
            let e = ((crate::math::luminance(*a) - crate::math::luminance(*b)).abs() * 4.0)
                .clamp(0.0, 1.0);
            let v = (crate::image::srgb_oetf(e) * 255.0) as u8;
            [v, v, v]
        })
        .collect();
    image::RgbImage::from_raw(t.width, t.height, data).expect("sizes match")
}

fn gif_bytes(frames: &[image::RgbImage], fps: f32, dir: &Path, name: &str) -> Result<Vec<u8>> {
    let path = dir.join(name);
    super::write_gif(&path, frames, fps)?;
    std::fs::read(&path).with_context(|| format!("{}: cannot read back", path.display()))
}

pub fn compare(o: &CompareOpts) -> Result<()> {
    o.scene.validate()?;
    if o.samplers.is_empty() || o.vpls.is_empty() {
        bail!("--samplers and --vpls need at least one value each");
    }
    if o.spp == 0 || o.spp > 1 << 20 {
        bail!("--spp {} is out of range (1 to 1048576)", o.spp);
    }
    let spec = o.scene.scene_or("cornell-orbit");
    let scene = load_scene(spec)?;
    let frames = o.scene.frames_or_all(scene.duration());
    let numbers: Vec<u32> = frames.iter().collect();
    // Every run's settings are checked before anything renders.
    let mut defaults = Defaults::try_parse_from(["irad"])
        .expect("defaults parse")
        .render;
    defaults.scene = o.scene.clone();
    defaults.backend = o.backend;
    defaults.mh_rate = o.mh_rate;
    defaults.mh_escape = o.mh_escape;
    defaults.exposure = o.exposure;
    let gpu = crate::gpu::Gpu::new(o.backend)?;
    for &v in &o.vpls {
        let mut r = defaults.clone();
        r.vpls = v;
        r.settings(&scene)?;
        crate::gpu::renderer::check_config(&r.config(), &gpu.limits)?;
    }
    drop(gpu);
    super::prepare_out_dir(&o.out)?;
    let cache = cache_dir(o, spec);
    super::prepare_out_dir(&cache)?;
    let cached = |f: u32| cache.join(format!("{}.exr", super::frame_stem(f)));
    let missing = numbers.iter().filter(|&&f| !cached(f).exists()).count() as u64;
    let runs = (o.samplers.len() * o.vpls.len()) as u64;
    let pb = super::progress(
        missing * o.scene.size.height as u64 + runs * numbers.len() as u64,
        "compare",
    );

    // The reference, from the cache where its settings match.
    let settings = crate::reference::Settings {
        width: o.scene.size.width,
        height: o.scene.size.height,
        spp: o.spp,
        seed: o.scene.seed,
    };
    let mut reference = Vec::new();
    let mut tracer: Option<crate::trace::Tracer> = None;
    for &f in &numbers {
        let path = cached(f);
        let img = if path.exists() {
            let img = Hdr::read(&path)?;
            if (img.width, img.height) != (settings.width, settings.height) {
                bail!(
                    "{}: cached reference is {}x{}, not {}",
                    path.display(),
                    img.width,
                    img.height,
                    o.scene.size
                );
            }
            img
        } else {
            let frame = scene.at(o.scene.time(f));
            match &mut tracer {
                Some(t) => {
                    t.update(&frame);
                }
                None => tracer = Some(crate::trace::Tracer::new(&frame)),
            }
            let img =
                crate::reference::render(&frame, tracer.as_ref().expect("set"), &settings, &|| {
                    pb.inc(1)
                });
            super::write_frame(&cache, f, &img, o.exposure)?;
            img
        };
        reference.push(img);
    }

    // Every sampler x VPL count.
    let show = o.show_vpls.unwrap_or(o.vpls[o.vpls.len() / 2]);
    let mut records = Vec::new();
    let mut clips = vec![html::Clip {
        label: format!("reference ({} spp)", o.spp),
        gif: gif_bytes(
            &reference
                .iter()
                .map(|h| h.to_rgb_image(o.exposure))
                .collect::<Vec<_>>(),
            o.scene.fps,
            &o.out,
            "reference.gif",
        )?,
        error_gif: None,
    }];
    let mut adapter = String::new();
    for &s in &o.samplers {
        for &v in &o.vpls {
            let mut r = defaults.clone();
            r.vpls = v;
            r.sampler = s;
            let mut p = Pipeline::new(scene.clone(), r.settings(&scene)?, r.config(), o.backend)?;
            adapter = p.renderer.gpu.adapter.to_string();
            let (mut imgs, mut secs, mut repl, mut acc) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for &f in &numbers {
                let fo = p.render_frame(f, false)?;
                secs.push(fo.seconds);
                repl.push(fo.selection.replaced);
                acc.push(fo.selection.acceptance);
                imgs.push(fo.image.hdr);
                pb.inc(1);
            }
            let m = metrics::sequence(&numbers, &imgs, &reference)?;
            if v == show {
                let name = label(s, v).replace(' ', "-");
                clips.push(html::Clip {
                    label: label(s, v),
                    gif: gif_bytes(
                        &imgs
                            .iter()
                            .map(|h| h.to_rgb_image(o.exposure))
                            .collect::<Vec<_>>(),
                        o.scene.fps,
                        &o.out,
                        &format!("{name}.gif"),
                    )?,
                    error_gif: Some(gif_bytes(
                        &imgs
                            .iter()
                            .zip(&reference)
                            .map(|(a, b)| error_image(a, b))
                            .collect::<Vec<_>>(),
                        o.scene.fps,
                        &o.out,
                        &format!("{name}-error.gif"),
                    )?),
                });
            }
            let n = numbers.len() as f64;
            // Replacement from the second frame on (the first fills every slot).
            let later: Vec<f64> = repl.iter().skip(1).map(|&x| x as f64).collect();
            let acc_later: Vec<f64> = acc
                .iter()
                .skip(1)
                .filter_map(|a| a.map(|x| x as f64))
                .collect();
            records.push(RunRecord {
                sampler: s,
                vpls: v,
                mean_seconds: secs.iter().sum::<f64>() / n,
                mean_replaced: if later.is_empty() {
                    1.0
                } else {
                    later.iter().sum::<f64>() / later.len() as f64
                },
                mean_acceptance: (!acc_later.is_empty())
                    .then(|| acc_later.iter().sum::<f64>() / acc_later.len() as f64),
                metrics: m,
                seconds: secs,
                replaced: repl,
                acceptance: acc,
            });
        }
    }
    pb.finish_and_clear();

    // Tables.
    let mut csv = String::from(
        "scene,sampler,vpls,frame,seconds,rel_mse,rmse,bias,flip,flicker,replaced,acceptance\n",
    );
    for r in &records {
        for (i, fm) in r.metrics.frames.iter().enumerate() {
            csv += &format!(
                "{spec},{},{},{},{:.6},{:.8},{:.8},{:.8},{:.6},{},{:.4},{}\n",
                format!("{:?}", r.sampler).to_lowercase(),
                r.vpls,
                fm.frame,
                r.seconds[i],
                fm.error.rel_mse,
                fm.error.rmse,
                fm.error.bias,
                fm.flip,
                fm.flicker.map(|x| format!("{x:.8}")).unwrap_or_default(),
                r.replaced[i],
                r.acceptance[i]
                    .map(|x| format!("{x:.4}"))
                    .unwrap_or_default()
            );
        }
    }
    write_bytes(&o.out.join("metrics.csv"), csv.as_bytes())?;
    let notes = vec![
        format!("scene {spec}, frames {}..{} at {} fps, {}", frames.start, frames.end, o.scene.fps, o.scene.size),
        format!("reference: CPU path tracer, {} spp, seed {}", o.spp, o.scene.seed),
        format!("adapter: {adapter}; CPU threads: {}", rayon::current_num_threads()),
        format!("MH proposal rate {}, escape {}; flicker F1 = mean over frame pairs of mean |e_t - e_(t-1)|, e = lum(test) - lum(reference)", o.mh_rate, o.mh_escape),
    ];
    super::write_json(
        &o.out.join("metrics.json"),
        &serde_json::json!({ "scene": spec, "size": o.scene.size.to_string(), "frames": numbers, "spp": o.spp, "notes": notes, "runs": records }),
    )?;

    // Charts.
    let per_frame = |f: &dyn Fn(&RunRecord, usize) -> Option<f64>| -> Vec<Series> {
        records
            .iter()
            .map(|r| Series {
                label: label(r.sampler, r.vpls),
                points: numbers
                    .iter()
                    .enumerate()
                    .filter_map(|(i, &n)| f(r, i).map(|y| (n as f64, y)))
                    .collect(),
            })
            .collect()
    };
    let scatter: Vec<Series> = records
        .iter()
        .map(|r| Series {
            label: label(r.sampler, r.vpls),
            points: vec![(r.mean_seconds, r.metrics.mean_rel_mse)],
        })
        .collect();
    let flicker_scatter: Vec<Series> = records
        .iter()
        .map(|r| Series {
            label: label(r.sampler, r.vpls),
            points: vec![(r.mean_seconds, r.metrics.flicker_f1.max(1e-9))],
        })
        .collect();
    let flicker_lines = per_frame(&|r, i| r.metrics.frames[i].flicker);
    let relmse_lines = per_frame(&|r, i| Some(r.metrics.frames[i].error.rel_mse));
    let replaced_lines = per_frame(&|r, i| Some(r.replaced[i] as f64));
    let specs: Vec<(&str, Chart)> = vec![
        (
            "speed_accuracy",
            Chart {
                title: "Error against time (one point per run)",
                x: "seconds per frame",
                y: "mean relMSE",
                kind: Kind::Scatter,
                series: &scatter,
            },
        ),
        (
            "speed_flicker",
            Chart {
                title: "Flicker against time (one point per run)",
                x: "seconds per frame",
                y: "flicker F1",
                kind: Kind::Scatter,
                series: &flicker_scatter,
            },
        ),
        (
            "flicker",
            Chart {
                title: "Flicker per frame",
                x: "frame",
                y: "mean |e_t - e_(t-1)|",
                kind: Kind::Lines,
                series: &flicker_lines,
            },
        ),
        (
            "relmse",
            Chart {
                title: "relMSE per frame",
                x: "frame",
                y: "relMSE",
                kind: Kind::Lines,
                series: &relmse_lines,
            },
        ),
        (
            "replaced",
            Chart {
                title: "VPLs replaced per frame",
                x: "frame",
                y: "fraction of slots",
                kind: Kind::Lines,
                series: &replaced_lines,
            },
        ),
    ];
    let charts_dir = o.out.join("charts");
    super::prepare_out_dir(&charts_dir)?;
    let mut svgs = Vec::new();
    for (name, c) in &specs {
        let (svg, png) = charts::render(c)?;
        write_bytes(&charts_dir.join(format!("{name}.svg")), svg.as_bytes())?;
        crate::image::atomic_write(&charts_dir.join(format!("{name}.png")), |tmp| {
            png.save_with_format(tmp, image::ImageFormat::Png)
                .map_err(anyhow::Error::from)
        })?;
        svgs.push((c.title.to_string(), svg));
    }
    let rows: Vec<html::Row> = records
        .iter()
        .map(|r| html::Row {
            label: label(r.sampler, r.vpls),
            seconds: r.mean_seconds,
            rel_mse: r.metrics.mean_rel_mse,
            flip: r.metrics.mean_flip,
            flicker: r.metrics.flicker_f1,
            replaced: r.mean_replaced,
            acceptance: r.mean_acceptance,
        })
        .collect();
    let page = html::page(
        &format!("irad compare: {spec}"),
        &notes,
        &rows,
        &svgs,
        &clips,
    );
    write_bytes(&o.out.join("report.html"), page.as_bytes())?;

    println!("{}", notes.join("\n"));
    println!(
        "{:14} {:>10} {:>10} {:>8} {:>10} {:>10} {:>10}",
        "run", "s/frame", "relMSE", "FLIP", "flicker", "replaced", "accept"
    );
    for r in &rows {
        println!(
            "{:14} {:>10.3} {:>10.5} {:>8.4} {:>10.5} {:>10.3} {:>10}",
            r.label,
            r.seconds,
            r.rel_mse,
            r.flip,
            r.flicker,
            r.replaced,
            r.acceptance
                .map(|a| format!("{a:.3}"))
                .unwrap_or_else(|| "-".into())
        );
    }
    println!(
        "wrote {}/report.html, metrics.csv, metrics.json, charts/",
        o.out.display()
    );
    Ok(())
}
