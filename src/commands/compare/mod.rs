//! `irad compare`: samplers x VPL counts on one animation, against a cached reference:
//! metrics.csv/json, charts (SVG and PNG) and a self-contained report.html. In four steps:
//! [`plan`] (scene, frames, every run's settings checked on the one device),
//! [`reference_cache`] (the path-traced frames, reused when their settings match), [`runs`]
//! (each sampler x VPL count rendered and measured) and [`outputs`] (tables, charts, page).

pub mod outputs;
pub mod plan;
pub mod reference_cache;
pub mod runs;

use crate::config;
use anyhow::Result;

/// `irad compare`, on one GPU device for all its runs.
pub fn compare(cfg: &config::Compare) -> Result<()> {
    let plan = plan::Plan::new(cfg)?;
    let pb = crate::report::progress(plan.work_units(), "compare");
    let reference = reference_cache::load_or_render(&plan, &|| pb.inc(1))?;
    let results = runs::run_all(&plan, &reference, &|| pb.inc(1))?;
    pb.finish_and_clear();
    outputs::write(&plan, &reference, &results)
}
