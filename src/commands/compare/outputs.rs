//! A comparison's outputs: metrics.csv and metrics.json, charts (SVG and PNG), animations
//! (GIF) and the self-contained report.html, and the summary table on stdout.

use super::plan::Plan;
use super::runs::{Results, RunRecord};
use crate::image::{write_bytes, Hdr};
use crate::report::charts::{self, Chart, Kind, Series};
use crate::report::html;
use anyhow::{Context, Result};
use std::path::Path;

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
    crate::report::write_gif(&path, frames, fps)?;
    std::fs::read(&path).with_context(|| format!("{}: cannot read back", path.display()))
}

/// The animations the report shows: the reference, and each shown run with its error.
fn clips(plan: &Plan, reference: &[Hdr], results: &Results) -> Result<Vec<html::Clip>> {
    let cfg = &plan.cfg;
    let (fps, exposure) = (cfg.sequence.fps, cfg.render.exposure);
    let ldr = |imgs: &[Hdr]| -> Vec<image::RgbImage> {
        imgs.iter().map(|h| h.to_rgb_image(exposure)).collect()
    };
    let mut clips = vec![html::Clip {
        label: format!("reference ({} spp)", cfg.spp),
        gif: gif_bytes(&ldr(reference), fps, &cfg.out, "reference.gif")?,
        error_gif: None,
    }];
    for (label, imgs) in &results.shown {
        let name = label.replace(' ', "-");
        let errors: Vec<image::RgbImage> = imgs
            .iter()
            .zip(reference)
            .map(|(a, b)| error_image(a, b))
            .collect();
        clips.push(html::Clip {
            label: label.clone(),
            gif: gif_bytes(&ldr(imgs), fps, &cfg.out, &format!("{name}.gif"))?,
            error_gif: Some(gif_bytes(
                &errors,
                fps,
                &cfg.out,
                &format!("{name}-error.gif"),
            )?),
        });
    }
    Ok(clips)
}

/// metrics.csv: one row per run and frame.
fn write_csv(plan: &Plan, results: &Results) -> Result<()> {
    let spec = plan.spec.as_str();
    let mut csv = String::from(
        "scene,method,sampler,vpls,frame,seconds,rel_mse,rmse,bias,flip,flicker,replaced,acceptance\n",
    );
    for r in &results.records {
        for (i, fm) in r.metrics.frames.iter().enumerate() {
            csv += &format!(
                "{spec},{},{},{},{},{:.6},{:.8},{:.8},{:.8},{:.6},{},{:.4},{}\n",
                r.method.name(),
                r.sampler,
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
    write_bytes(&plan.cfg.out.join("metrics.csv"), csv.as_bytes())?;
    Ok(())
}

/// What the page, metrics.json and stdout say about the comparison's setting.
fn notes(plan: &Plan, results: &Results) -> Vec<String> {
    let cfg = &plan.cfg;
    let (spec, frames, adapter) = (&plan.spec, plan.frames, &results.adapter);
    vec![
        format!("scene {spec}, frames {}..{} at {} fps, {}", frames.start, frames.end, cfg.sequence.fps, cfg.sequence.size),
        format!("reference: CPU path tracer, {} spp, seed {}", cfg.spp, cfg.sequence.seed),
        format!("adapter: {adapter}; CPU threads: {}", rayon::current_num_threads()),
        format!("MH proposal rate {}, escape {}; flicker F1 = mean over frame pairs of mean |e_t - e_(t-1)|, e = lum(test) - lum(reference)", cfg.render.mh_rate, cfg.render.mh_escape),
    ]
}

/// The charts, written as SVG and PNG under charts/; returns (title, SVG) for the page.
fn write_charts(plan: &Plan, results: &Results) -> Result<Vec<(String, String)>> {
    let cfg = &plan.cfg;
    let numbers = &plan.numbers;
    let per_frame = |f: &dyn Fn(&RunRecord, usize) -> Option<f64>| -> Vec<Series> {
        results
            .records
            .iter()
            .map(|r| Series {
                label: r.label(),
                points: numbers
                    .iter()
                    .enumerate()
                    .filter_map(|(i, &n)| f(r, i).map(|y| (n as f64, y)))
                    .collect(),
            })
            .collect()
    };
    let scatter: Vec<Series> = results
        .records
        .iter()
        .map(|r| Series {
            label: r.label(),
            points: vec![(r.mean_seconds, r.metrics.mean_rel_mse)],
        })
        .collect();
    let flicker_scatter: Vec<Series> = results
        .records
        .iter()
        .map(|r| Series {
            label: r.label(),
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
    let charts_dir = cfg.out.join("charts");
    crate::report::prepare_out_dir(&charts_dir)?;
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
    Ok(svgs)
}

/// The summary table's rows, one per run.
fn rows(results: &Results) -> Vec<html::Row> {
    results
        .records
        .iter()
        .map(|r| html::Row {
            label: r.label(),
            seconds: r.mean_seconds,
            rel_mse: r.metrics.mean_rel_mse,
            flip: r.metrics.mean_flip,
            flicker: r.metrics.flicker_f1,
            replaced: r.mean_replaced,
            acceptance: r.mean_acceptance,
        })
        .collect()
}

/// Prints the setting and the summary table.
fn print_table(plan: &Plan, notes: &[String], rows: &[html::Row]) -> std::io::Result<()> {
    let cfg = &plan.cfg;
    crate::outln!("{}", notes.join("\n"))?;
    crate::outln!(
        "{:14} {:>10} {:>10} {:>8} {:>10} {:>10} {:>10}",
        "run",
        "s/frame",
        "relMSE",
        "FLIP",
        "flicker",
        "replaced",
        "accept"
    )?;
    for r in rows {
        crate::outln!(
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
        )?;
    }
    crate::outln!(
        "wrote {}/report.html, metrics.csv, metrics.json, charts/",
        cfg.out.display()
    )
}

/// Writes every output of the comparison and prints its table.
pub fn write(plan: &Plan, reference: &[Hdr], results: &Results) -> Result<()> {
    let cfg = &plan.cfg;
    let spec = plan.spec.as_str();
    let clips = clips(plan, reference, results)?;
    write_csv(plan, results)?;
    let notes = notes(plan, results);
    crate::report::write_json(
        &cfg.out.join("metrics.json"),
        &serde_json::json!({ "scene": spec, "size": cfg.sequence.size.to_string(), "frames": plan.numbers, "spp": cfg.spp, "notes": notes, "runs": results.records }),
    )?;

    let svgs = write_charts(plan, results)?;
    let rows = rows(results);
    let page = html::page(
        &format!("irad compare: {spec}"),
        &notes,
        &rows,
        &svgs,
        &clips,
    );
    write_bytes(&cfg.out.join("report.html"), page.as_bytes())?;

    print_table(plan, &notes, &rows)?;
    Ok(())
}
