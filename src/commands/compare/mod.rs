//! `irad compare`: samplers x VPL counts (and swept sampler knobs) on one animation, against a
//! cached reference: metrics.csv/json, charts (SVG and PNG), per-frame flicker heat maps
//! (flicker/) and a self-contained report.html.
//! In four steps: [`plan`] (scene, frames, every run's settings checked on the one device),
//! [`reference_cache`] (the path-traced frames, two independent halves reused when their
//! settings match, whose difference gives the reference's own noise floor), [`runs`] (each
//! run rendered and measured, plain and warped flicker) and [`outputs`] (tables, charts with
//! the floor drawn on them, page).

pub mod outputs;
pub mod plan;
pub mod reference_cache;
pub mod runs;

use crate::config;
use anyhow::Result;

/// `irad compare`, on one GPU device for all its runs.
pub fn compare(cfg: &config::Compare) -> Result<()> {
    compare_with(plan::Plan::new(cfg)?)
}

/// [`compare`] on a device the caller holds (the Python package's one per process).
pub fn compare_on(gpu: std::sync::Arc<crate::gpu::Gpu>, cfg: &config::Compare) -> Result<()> {
    let plan = plan::Plan::open_with(cfg, Some(&|| Ok(gpu.clone())), true)?;
    compare_with(plan)
}

fn compare_with(plan: plan::Plan) -> Result<()> {
    let pb = crate::report::progress(work_units(&plan), "compare");
    pb.set_detail("reference");
    let reference = reference_cache::load_or_render(&plan, &|| pb.inc(1))?;
    let motion = plan.motion();
    let floor = reference.floor(&plan, &motion)?;
    let results = runs::run_all(&plan, &reference.frames, &motion, &pb)?;
    pb.finish_and_clear();
    outputs::write(&plan, &reference.frames, &floor, &results)
}

/// The progress bar's length: reference rows still to trace, plus every run's frames.
fn work_units(plan: &plan::Plan) -> u64 {
    // Each missing image of either half is traced row by row.
    let missing = reference_cache::missing(plan) as u64;
    let runs = plan.runs().len() as u64;
    missing * plan.cfg.sequence.size.height as u64 + runs * plan.numbers.len() as u64
}
