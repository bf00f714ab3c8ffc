//! `irad bench`: time per stage of whole frames, averaged after one warm-up frame, for
//! several VPL counts and image sizes, all on one device.

use super::render::{FrameRecord, StageMeans};
use crate::config;
use crate::frame::Pipeline;
use crate::gpu::Gpu;
use crate::report;
use anyhow::Result;
use serde::Serialize;
use std::sync::Arc;

#[derive(Serialize)]
struct BenchRow {
    case: config::BenchCase,
    frames: u32,
    seconds_per_frame: f64,
    stages: Vec<(String, f64)>,
}

/// `irad bench`.
pub fn bench(cfg: &config::Bench) -> Result<()> {
    cfg.validate()?;
    let spec = cfg.scene_name();
    let scene = cfg
        .render
        .sequence
        .load_scene(config::DEFAULT_STILL_SCENE)?;
    let gpu = Arc::new(Gpu::new(cfg.render.backend)?);
    let adapter = gpu.adapter.clone();
    report::prepare_out_dir(&cfg.render.out)?;
    let mut rows = Vec::new();
    let mut profiling = None;
    let pb = report::progress(cfg.cases.len() as u64 * (cfg.repeat as u64 + 1), "bench");
    for &c in &cfg.cases {
        let mut p = Pipeline::new(gpu.clone(), scene.clone(), &cfg.case(c))?;
        p.render_frame(0, false)?;
        pb.inc(1);
        let mut means = StageMeans::default();
        for f in 0..cfg.repeat {
            let record = FrameRecord::of(&p.render_frame(f, false)?);
            means.add(&record);
            profiling = Some(record.profiling);
            pb.inc(1);
        }
        let (seconds_per_frame, stages) = means.means();
        rows.push(BenchRow {
            case: c,
            frames: cfg.repeat,
            seconds_per_frame,
            stages,
        });
    }
    pb.finish_and_clear();
    crate::outln!(
        "scene {spec}, adapter {adapter}, {} CPU threads, mean of {} frames after one warm-up",
        rayon::current_num_threads(),
        cfg.repeat
    )?;
    let how = match profiling {
        Some(crate::gpu::Profiling::Timestamps) => "GPU timestamp queries, one submission a frame",
        Some(crate::gpu::Profiling::Serialized) => {
            "CPU wall time, a submission and a wait per pass"
        }
        _ => "not timed (--profiling off): one submission a frame",
    };
    crate::outln!("pass times: {how}")?;
    crate::out!("{:16}", "stage (ms)")?;
    for r in &rows {
        crate::out!("{:>20}", format!("{} VPLs {}", r.case.vpls, r.case.size))?;
    }
    crate::outln!()?;
    for (i, (name, _)) in rows[0].stages.iter().enumerate() {
        if rows.iter().all(|r| r.stages[i].1 == 0.0) {
            continue;
        }
        crate::out!("{name:16}")?;
        for r in &rows {
            crate::out!("{:>20.2}", r.stages[i].1 * 1e3)?;
        }
        crate::outln!()?;
    }
    crate::out!("{:16}", "frame")?;
    for r in &rows {
        crate::out!("{:>20.2}", r.seconds_per_frame * 1e3)?;
    }
    crate::outln!()?;
    report::write_json(
        &cfg.render.out.join("bench.json"),
        &serde_json::json!({ "scene": spec, "adapter": adapter, "settings": cfg, "rows": rows }),
    )?;
    Ok(())
}
