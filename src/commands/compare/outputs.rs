//! A comparison's outputs: metrics.csv and metrics.json, charts (SVG and PNG), animations
//! (GIF) and the self-contained report.html, and the summary table on stdout.

use super::plan::Plan;
use super::runs::{Results, RunRecord};
use crate::config::Method;
use crate::image::{write_bytes, Hdr};
use crate::metrics::floor::Floor;
use crate::report::charts::{self, Chart, Guide, Kind, Series, Shape};
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

/// The flicker heat maps of the shown runs, on one scale, written under flicker/ (a sheet of
/// every frame pair and the largest one per run, and the colour bar) for the page.
fn heat_maps(plan: &Plan, results: &Results) -> Result<Option<html::Heat>> {
    use crate::report::heatmap;
    let (w, h) = (plan.cfg.sequence.size.width, plan.cfg.sequence.size.height);
    if results.flicker.iter().all(|(_, maps)| maps.is_empty()) {
        return Ok(None);
    }
    let dir = plan.cfg.out.join("flicker");
    crate::report::prepare_out_dir(&dir)?;
    let top = heatmap::shared_scale(
        results
            .flicker
            .iter()
            .flat_map(|(_, maps)| maps.iter().map(|m| m.as_slice())),
    );
    let cols = 8;
    let mut maps = Vec::new();
    for (label, frames) in &results.flicker {
        let name = label.replace(' ', "-");
        let f1: Vec<f64> = frames
            .iter()
            .map(|m| {
                let (s, n) = m
                    .iter()
                    .flatten()
                    .fold((0.0, 0usize), |(s, n), &v| (s + v as f64, n + 1));
                s / n.max(1) as f64
            })
            .collect();
        let worst = (0..f1.len())
            .max_by(|&a, &b| f1[a].total_cmp(&f1[b]))
            .unwrap_or(0);
        let (sheet_file, worst_file) = (
            format!("flicker/{name}.png"),
            format!("flicker/{name}-largest.png"),
        );
        let sheet = heatmap::write_png(
            &plan.cfg.out.join(&sheet_file),
            &heatmap::sheet(frames, w, h, top, cols),
        )?;
        let worst_png = match frames.get(worst) {
            Some(m) => heatmap::write_png(
                &plan.cfg.out.join(&worst_file),
                &heatmap::image(m, w, h, top),
            )?,
            None => continue,
        };
        maps.push(html::HeatMap {
            label: label.clone(),
            sheet,
            sheet_file,
            worst_frame: plan.numbers[worst + 1],
            worst_f1: f1[worst],
            worst: worst_png,
            worst_file,
        });
    }
    let legend = heatmap::write_png(&dir.join("scale.png"), &heatmap::legend())?;
    Ok(Some(html::Heat {
        top: top as f64,
        legend,
        frames: plan.numbers[1..].to_vec(),
        cols: cols.min(plan.numbers.len().saturating_sub(1) as u32).max(1),
        maps,
    }))
}

/// metrics.csv: one row per run and frame.
fn write_csv(plan: &Plan, results: &Results) -> Result<()> {
    let spec = plan.spec.as_str();
    let mut csv = String::from(
        "scene,method,sampler,vpls,knob,knob_value,frame,seconds,rel_mse,rmse,bias,flip,flicker,warped_flicker,replaced,acceptance\n",
    );
    for r in &results.records {
        for (i, fm) in r.metrics.frames.iter().enumerate() {
            let warped = i
                .checked_sub(1)
                .and_then(|j| r.warped.frames.get(j))
                .map(|w| format!("{:.8}", w.0))
                .unwrap_or_default();
            csv += &format!(
                "{spec},{},{},{},{},{},{},{:.6},{:.8},{:.8},{:.8},{:.6},{},{warped},{:.4},{}\n",
                r.method.name(),
                r.sampler,
                r.vpls,
                r.knob.map(|k| k.to_string()).unwrap_or_default(),
                r.knob_value.map(|v| v.to_string()).unwrap_or_default(),
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
fn notes(plan: &Plan, floor: &Floor, results: &Results) -> Vec<String> {
    let cfg = &plan.cfg;
    let (spec, frames, adapter) = (&plan.spec, plan.frames, &results.adapter);
    let sweeps: Vec<String> = cfg.sweep.iter().map(|s| s.to_string()).collect();
    let mut notes = vec![
        format!("scene {spec}, frames {}..{} at {} fps, {}", frames.start, frames.end, cfg.sequence.fps, cfg.sequence.size),
        format!("reference: CPU path tracer, {} spp (two independent halves of {} and {} spp), seed {}", cfg.spp, floor.spp[0], floor.spp[1], cfg.sequence.seed),
        format!(
            "reference noise floor (what a perfect renderer would measure; from the halves' difference): flicker F1 {:.5}, warped F1 {}, relMSE {:.5}",
            floor.flicker_f1,
            floor.warped_f1.map(|w| format!("{w:.5}")).unwrap_or_else(|| "-".into()),
            floor.rel_mse
        ),
        format!("adapter: {adapter}; CPU threads: {}", rayon::current_num_threads()),
        format!("MH proposal rate {}, escape {}; flicker F1 = mean over frame pairs of mean |e_t - e_(t-1)|, e = lum(test) - lum(reference); warped F1 reads e_(t-1) where the pixel's surface was (disoccluded pixels left out)", cfg.render.knobs.mh_rate, cfg.render.knobs.mh_escape),
    ];
    if !sweeps.is_empty() {
        notes.push(format!("sweeps: {}", sweeps.join("; ")));
    }
    notes
}

/// A curve of the flicker-against-error charts: the runs of one sampler with its knob swept
/// (at one VPL count), or over --vpls when nothing is swept; a classical method is one point.
struct Curve {
    label: String,
    /// (knob value or VPL count, record index).
    runs: Vec<(f64, usize)>,
}

fn curves(results: &Results) -> Vec<Curve> {
    let mut keys: Vec<(String, Curve)> = Vec::new();
    for (i, r) in results.records.iter().enumerate() {
        let (key, label, x) = match (r.method, r.knob, r.knob_value) {
            (Method::Instant, Some(k), Some(v)) => (
                format!("{} {} {k}", r.sampler, r.vpls),
                format!("{} {}", r.sampler, r.vpls),
                v,
            ),
            (Method::Instant, _, _) => {
                (r.sampler.to_string(), r.sampler.to_string(), r.vpls as f64)
            }
            (m, _, _) => (m.name().to_string(), m.name().to_string(), 0.0),
        };
        match keys.iter_mut().find(|(k, _)| *k == key) {
            Some((_, c)) => c.runs.push((x, i)),
            None => keys.push((
                key,
                Curve {
                    label,
                    runs: vec![(x, i)],
                },
            )),
        }
    }
    keys.into_iter()
        .map(|(_, mut c)| {
            c.runs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (lo, hi) = (c.runs[0].0, c.runs[c.runs.len() - 1].0);
            let r = &results.records[c.runs[0].1];
            let what = match r.knob {
                Some(k) => Some(k.to_string()),
                None if r.method == Method::Instant => Some("VPLs".to_string()),
                None => None,
            };
            if let Some(what) = what {
                c.label = match (r.knob, c.runs.len()) {
                    (Some(_), 1) | (None, 1) => format!("{} ({what} {lo})", c.label),
                    _ => format!("{} ({what} {lo}..{hi})", c.label),
                };
            }
            c
        })
        .collect()
}

/// The charts, written as SVG and PNG under charts/; returns (title, SVG) for the page.
fn write_charts(plan: &Plan, floor: &Floor, results: &Results) -> Result<Vec<(String, String)>> {
    let cfg = &plan.cfg;
    let numbers = &plan.numbers;
    let per_frame = |f: &dyn Fn(&RunRecord, usize) -> Option<f64>| -> Vec<Series> {
        results
            .records
            .iter()
            .map(|r| {
                Series::new(
                    r.label(),
                    numbers
                        .iter()
                        .enumerate()
                        .filter_map(|(i, &n)| f(r, i).map(|y| (n as f64, y)))
                        .collect(),
                )
            })
            .collect()
    };
    let one_point = |f: &dyn Fn(&RunRecord) -> (f64, f64)| -> Vec<Series> {
        results
            .records
            .iter()
            .map(|r| Series::new(r.label(), vec![f(r)]))
            .collect()
    };
    let scatter = one_point(&|r| (r.mean_seconds, r.metrics.mean_rel_mse));
    let flicker_scatter = one_point(&|r| (r.mean_seconds, r.metrics.flicker_f1.max(1e-9)));
    let flicker_lines = per_frame(&|r, i| r.metrics.frames[i].flicker);
    let warped_lines = per_frame(&|r, i| {
        i.checked_sub(1)
            .and_then(|j| r.warped.frames.get(j))
            .map(|w| w.0)
    });
    let relmse_lines = per_frame(&|r, i| Some(r.metrics.frames[i].error.rel_mse));
    let replaced_lines = per_frame(&|r, i| Some(r.replaced[i] as f64));
    let curves = curves(results);
    let against_error = |y: &dyn Fn(&RunRecord) -> f64| -> Vec<Series> {
        curves
            .iter()
            .map(|c| {
                let recs: Vec<&RunRecord> =
                    c.runs.iter().map(|&(_, i)| &results.records[i]).collect();
                Series {
                    label: c.label.clone(),
                    points: recs
                        .iter()
                        .map(|r| (r.metrics.mean_rel_mse, y(r)))
                        .collect(),
                    tags: if c.runs.len() > 1 {
                        c.runs.iter().map(|(x, _)| x.to_string()).collect()
                    } else {
                        Vec::new()
                    },
                }
            })
            .collect()
    };
    let flicker_error = against_error(&|r| r.metrics.flicker_f1);
    let warped_error = against_error(&|r| r.warped.f1);

    let spp = format!("{}+{} spp", floor.spp[0], floor.spp[1]);
    let band = |what: &str, y: f64| Guide {
        label: format!("reference noise floor: {what} {y:.2e} ({spp} halves)"),
        shape: Shape::BandBelow(y),
    };
    let relmse_line = Guide {
        label: format!("reference noise floor: relMSE {:.2e}", floor.rel_mse),
        shape: Shape::VLine(floor.rel_mse),
    };
    let per_frame_floor = |f: &dyn Fn(&crate::metrics::floor::FloorFrame) -> Option<f64>| Guide {
        label: format!("reference noise floor ({spp} halves)"),
        shape: Shape::Dashed(
            floor
                .frames
                .iter()
                .filter_map(|fr| f(fr).map(|y| (fr.frame as f64, y)))
                .collect(),
        ),
    };
    let g_relmse = [band("relMSE", floor.rel_mse)];
    let g_f1 = [band("F1", floor.flicker_f1)];
    let g_flicker_frames = [per_frame_floor(&|fr| fr.flicker)];
    let g_warped_frames = [per_frame_floor(&|fr| fr.warped_flicker)];
    let g_relmse_frames = [per_frame_floor(&|fr| Some(fr.rel_mse))];
    let g_fe = [band("F1", floor.flicker_f1), relmse_line];
    let warped_floor = floor.warped_f1.unwrap_or(floor.flicker_f1);
    let g_we = [
        band("warped F1", warped_floor),
        Guide {
            label: format!("reference noise floor: relMSE {:.2e}", floor.rel_mse),
            shape: Shape::VLine(floor.rel_mse),
        },
    ];
    let specs: Vec<(&str, Chart)> = vec![
        (
            "flicker_error",
            Chart {
                title: "Flicker against error (a curve per sampler, its knob swept)",
                x: "mean relMSE",
                y: "flicker F1",
                kind: Kind::Curves,
                series: &flicker_error,
                guides: &g_fe,
                log_x: true,
            },
        ),
        (
            "warped_flicker_error",
            Chart {
                title: "Warped flicker against error (camera and objects' motion compensated)",
                x: "mean relMSE",
                y: "warped flicker F1",
                kind: Kind::Curves,
                series: &warped_error,
                guides: &g_we,
                log_x: true,
            },
        ),
        (
            "speed_accuracy",
            Chart {
                title: "Error against time (one point per run)",
                x: "seconds per frame",
                y: "mean relMSE",
                kind: Kind::Scatter,
                series: &scatter,
                guides: &g_relmse,
                log_x: false,
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
                guides: &g_f1,
                log_x: false,
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
                guides: &g_flicker_frames,
                log_x: false,
            },
        ),
        (
            "warped_flicker",
            Chart {
                title: "Warped flicker per frame",
                x: "frame",
                y: "mean |e_t - warped e_(t-1)|",
                kind: Kind::Lines,
                series: &warped_lines,
                guides: &g_warped_frames,
                log_x: false,
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
                guides: &g_relmse_frames,
                log_x: false,
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
                guides: &[],
                log_x: false,
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
            warped: r.warped.f1,
            replaced: r.mean_replaced,
            acceptance: r.mean_acceptance,
        })
        .collect()
}

/// The table's last row: the reference's noise floor.
fn floor_row(floor: &Floor) -> html::FloorRow {
    html::FloorRow {
        label: format!(
            "reference noise floor ({}+{} spp halves)",
            floor.spp[0], floor.spp[1]
        ),
        rel_mse: floor.rel_mse,
        flicker: floor.flicker_f1,
        warped: floor.warped_f1,
    }
}

/// Prints the setting and the summary table.
fn print_table(
    plan: &Plan,
    notes: &[String],
    rows: &[html::Row],
    floor: &html::FloorRow,
) -> std::io::Result<()> {
    let cfg = &plan.cfg;
    crate::outln!("{}", notes.join("\n"))?;
    let width = rows
        .iter()
        .map(|r| r.label.len())
        .chain([14, "reference floor".len()])
        .max()
        .unwrap_or(14);
    crate::outln!(
        "{:width$} {:>10} {:>10} {:>8} {:>10} {:>10} {:>10} {:>10}",
        "run",
        "s/frame",
        "relMSE",
        "FLIP",
        "flicker",
        "warped",
        "replaced",
        "accept"
    )?;
    for r in rows {
        crate::outln!(
            "{:width$} {:>10.3} {:>10.5} {:>8.4} {:>10.5} {:>10.5} {:>10.3} {:>10}",
            r.label,
            r.seconds,
            r.rel_mse,
            r.flip,
            r.flicker,
            r.warped,
            r.replaced,
            r.acceptance
                .map(|a| format!("{a:.3}"))
                .unwrap_or_else(|| "-".into())
        )?;
    }
    crate::outln!(
        "{:width$} {:>10} {:>10.5} {:>8} {:>10.5} {:>10} {:>10} {:>10}",
        "reference floor",
        "-",
        floor.rel_mse,
        "-",
        floor.flicker,
        floor
            .warped
            .map(|w| format!("{w:.5}"))
            .unwrap_or_else(|| "-".into()),
        "-",
        "-"
    )?;
    crate::outln!(
        "wrote {}/report.html, metrics.csv, metrics.json, charts/, flicker/",
        cfg.out.display()
    )
}

/// Writes every output of the comparison and prints its table.
pub fn write(plan: &Plan, reference: &[Hdr], floor: &Floor, results: &Results) -> Result<()> {
    let cfg = &plan.cfg;
    let spec = plan.spec.as_str();
    let clips = clips(plan, reference, results)?;
    write_csv(plan, results)?;
    let notes = notes(plan, floor, results);
    crate::report::write_json(
        &cfg.out.join("metrics.json"),
        &serde_json::json!({
            "scene": spec,
            "size": cfg.sequence.size.to_string(),
            "frames": plan.numbers,
            "spp": cfg.spp,
            "sweeps": cfg.sweep,
            "notes": notes,
            "floor": floor,
            "runs": results.records,
        }),
    )?;

    let svgs = write_charts(plan, floor, results)?;
    let rows = rows(results);
    let floor_row = floor_row(floor);
    let heat = heat_maps(plan, results)?;
    let page = html::page(
        &format!("irad compare: {spec}"),
        &notes,
        &rows,
        Some(&floor_row),
        &svgs,
        &clips,
        heat.as_ref(),
    );
    write_bytes(&cfg.out.join("report.html"), page.as_bytes())?;

    print_table(plan, &notes, &rows, &floor_row)?;
    Ok(())
}
