//! Every sampler x VPL count of a comparison, rendered on the plan's device and measured
//! against the reference.

use super::plan::{label, Plan, RunSpec};
use crate::config::Method;
use crate::config::{self, Knob};
use crate::frame::Pipeline;
use crate::image::Hdr;
use crate::metrics::warp::{flicker_maps, summarize, WarpedFlicker};
use crate::metrics::{self, SequenceMetrics};
use crate::vpl::sampler::SamplerKind;
use anyhow::Result;
use serde::Serialize;

/// Per-pixel warped flicker of each frame pair, None where the warp left the pixel out.
pub type FlickerMaps = Vec<Vec<Option<f32>>>;

/// One run's measurements.
#[derive(Serialize)]
pub struct RunRecord {
    pub method: Method,
    pub sampler: SamplerKind,
    pub vpls: u32,
    /// The swept knob of this run (None: the shared settings).
    pub knob: Option<&'static Knob>,
    pub knob_value: Option<f64>,
    pub mean_seconds: f64,
    /// Mean fraction of slots replaced, from the second frame on (the first fills them all).
    pub mean_replaced: f64,
    pub mean_acceptance: Option<f64>,
    pub metrics: SequenceMetrics,
    /// Motion-compensated flicker (the previous frame's error warped along the scene's
    /// motion).
    pub warped: WarpedFlicker,
    pub seconds: Vec<f64>,
    pub replaced: Vec<f32>,
    pub acceptance: Vec<Option<f32>>,
}

impl RunRecord {
    /// `mh 256` (`mh 256 mh-rate=0.1` in a sweep) for instant radiosity, the method's name
    /// for a classical one.
    pub fn label(&self) -> String {
        match self.method {
            Method::Instant => label(self.sampler, self.vpls, self.knob.zip(self.knob_value)),
            m => m.name().to_string(),
        }
    }
}

/// What the runs give: their records, and the frames of the runs the report shows.
pub struct Results {
    pub records: Vec<RunRecord>,
    /// (label, HDR frames) of the runs at the shown VPL count.
    pub shown: Vec<(String, Vec<Hdr>)>,
    /// (label, per-pixel warped flicker of each frame pair, None where the warp left the
    /// pixel out) of the same runs, for the report's heat maps.
    pub flicker: Vec<(String, FlickerMaps)>,
    pub adapter: String,
}

fn mean(xs: impl Iterator<Item = f64>) -> Option<f64> {
    let (n, s) = xs.fold((0usize, 0.0), |(n, s), x| (n + 1, s + x));
    (n > 0).then(|| s / n as f64)
}

/// What rendering one run gives, before it is measured: its frames and, per frame, the
/// seconds, the share of VPL slots replaced and the acceptance rate.
#[derive(Clone, Debug, Default, Serialize, serde::Deserialize)]
pub struct Rendered {
    #[serde(skip)]
    pub images: Vec<Hdr>,
    pub seconds: Vec<f64>,
    pub replaced: Vec<f32>,
    pub acceptance: Vec<Option<f32>>,
}

/// Renders one run's frames on the plan's device.
pub fn render(plan: &Plan, spec: RunSpec, progress: &crate::report::Progress) -> Result<Rendered> {
    let cfg = config::Render {
        method: spec.method,
        ..plan.cfg.run_with(spec.sampler, spec.vpls, spec.knob)
    };
    let gpu = plan
        .gpu
        .clone()
        .ok_or_else(|| anyhow::anyhow!("a run renders on a device, and this plan has none"))?;
    let mut p = Pipeline::new(gpu, plan.scene.clone(), &cfg)?;
    let label = match spec.method {
        Method::Instant => label(spec.sampler, spec.vpls, spec.knob),
        m => m.name().to_string(),
    };
    progress.set_detail(label.clone());
    let bar = progress.clone();
    p.on_solve_progress(move |s| bar.set_detail(format!("{label}: {s}")));
    let mut out = Rendered::default();
    for &f in &plan.numbers {
        let fo = p.render_frame(f, false)?;
        out.seconds.push(fo.seconds);
        out.replaced.push(fo.selection.replaced);
        out.acceptance.push(fo.selection.acceptance);
        out.images.push(fo.image.hdr);
        progress.inc(1);
    }
    Ok(out)
}

/// Measures one rendered run against the reference: its record and warped flicker maps.
pub fn measure(
    plan: &Plan,
    reference: &[Hdr],
    motion: &[Vec<Option<crate::metrics::warp::Warp>>],
    spec: RunSpec,
    rendered: Rendered,
) -> Result<(RunRecord, Vec<Hdr>, FlickerMaps)> {
    let Rendered {
        images: imgs,
        seconds,
        replaced,
        acceptance,
    } = rendered;
    let metrics = metrics::sequence(&plan.numbers, &imgs, reference)?;
    let maps = flicker_maps(&imgs, reference, motion)?;
    let warped = summarize(&maps);
    let maps = maps
        .into_iter()
        .map(|m| m.into_iter().map(|v| v.map(|v| v as f32)).collect())
        .collect();
    let record = RunRecord {
        method: spec.method,
        sampler: spec.sampler,
        vpls: spec.vpls,
        knob: spec.knob.map(|k| k.0),
        knob_value: spec.knob.map(|k| k.1),
        mean_seconds: mean(seconds.iter().copied()).unwrap_or(0.0),
        mean_replaced: mean(replaced.iter().skip(1).map(|&x| x as f64)).unwrap_or(1.0),
        mean_acceptance: mean(
            acceptance
                .iter()
                .skip(1)
                .filter_map(|a| a.map(|x| x as f64)),
        ),
        metrics,
        warped,
        seconds,
        replaced,
        acceptance,
    };
    Ok((record, imgs, maps))
}

impl Results {
    /// No runs yet, rendered on `adapter`.
    pub fn new(adapter: String) -> Results {
        Results {
            records: Vec::new(),
            shown: Vec::new(),
            flicker: Vec::new(),
            adapter,
        }
    }

    /// Adds a measured run.
    pub fn push(
        &mut self,
        spec: RunSpec,
        (record, imgs, maps): (RunRecord, Vec<Hdr>, FlickerMaps),
    ) {
        if spec.shown {
            self.shown.push((record.label(), imgs));
            self.flicker.push((record.label(), maps));
        }
        self.records.push(record);
    }
}

/// Every run of the plan, in order.
pub fn run_all(
    plan: &Plan,
    reference: &[Hdr],
    motion: &[Vec<Option<crate::metrics::warp::Warp>>],
    progress: &crate::report::Progress,
) -> Result<Results> {
    let adapter = plan
        .gpu
        .as_ref()
        .map(|g| g.adapter.to_string())
        .unwrap_or_default();
    let mut results = Results::new(adapter);
    for spec in plan.runs() {
        let rendered = render(plan, spec, progress)?;
        results.push(spec, measure(plan, reference, motion, spec, rendered)?);
    }
    Ok(results)
}
