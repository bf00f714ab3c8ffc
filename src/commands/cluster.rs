//! Past one machine: a study written as a plan of independent jobs (`--plan DIR`), one job run
//! anywhere (`irad job DIR INDEX`), and the jobs' outputs merged into what the same study on
//! one machine writes (`--collect DIR`). See docs/cluster.md.
//!
//! A compare's jobs are the reference's chunks (frames A..B of one half, traced with that
//! half's seed: each pixel's random stream depends only on the seed and the pixel, and a chunk
//! walks the tracer from the sequence's first frame, so its frames are bit-identical to the
//! same frames of a trace of the whole sequence) and its runs (one sampler, knob value and VPL
//! count over every frame, as on one machine: a run's frames depend on the ones before). A
//! job writes into DIR with each file moved into place whole, and a marker `done/NNNN.json`
//! last: a job with its marker is skipped, one without is redone from the start.

use crate::commands::compare::{outputs, plan::Plan, reference_cache, runs};
use crate::config;
use crate::image::Hdr;
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The plan's file in its folder.
pub const PLAN_FILE: &str = "plan.json";

/// A study written as independent jobs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlanFile {
    /// The irad version that wrote the plan (a job run by another one is refused).
    pub irad: String,
    /// `compare` or `reference`.
    pub command: String,
    /// The command's arguments: `irad COMMAND ARGS...` is the same study on one machine;
    /// `irad job` and `--collect` read the study's settings from them.
    pub args: Vec<String>,
    /// The folder the arguments were given in: their relative paths (scene, --out, --cache)
    /// are relative to it, and jobs run in it.
    pub cwd: PathBuf,
    /// The irad binary the Slurm scripts run (the environment variable IRAD overrides it).
    pub binary: PathBuf,
    /// The frame indices of the study.
    pub frames: Vec<u32>,
    /// Frames per reference job (`--chunk-frames`).
    pub chunk_frames: u32,
    pub jobs: Vec<Job>,
}

/// One job of a plan.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Job {
    pub index: usize,
    /// What it does, in words: `reference a frames 0..4`, `run mh 256`.
    pub name: String,
    pub work: Work,
    /// Whether the job renders on a GPU (a run) or traces on CPUs only (a reference chunk).
    pub gpu: bool,
    /// The command that runs it.
    pub args: Vec<String>,
    /// What it reads: the scene (and environment map) files, or the built-in scene's name.
    pub inputs: Vec<String>,
    /// What it writes, relative to the plan's folder (its marker last).
    pub outputs: Vec<String>,
}

/// The work of a job.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Work {
    /// Reference frames `start..end` (half-open) of one half (`a` or `b`; none for `irad
    /// reference`), at `spp` samples a pixel, traced with `seed` (each pixel's stream is
    /// derived from it and the pixel, the same in every frame).
    Reference {
        half: Option<String>,
        start: u32,
        end: u32,
        spp: u32,
        seed: u64,
    },
    /// Run `run` of the compare (in the order the report lists runs), over every frame.
    Run {
        run: usize,
        method: String,
        sampler: String,
        vpls: u32,
        knob: Option<String>,
        knob_value: Option<f64>,
        seed: u64,
    },
}

/// The settings of the study a plan was written from, as `irad job` and `--collect` parse
/// them from its arguments.
pub enum Study {
    Compare(Box<config::Compare>),
    Reference(Box<config::Reference>),
}

/// What a finished job records in its marker.
#[derive(Serialize, Deserialize)]
struct Done {
    job: usize,
    name: String,
    host: String,
    seconds: f64,
    /// A reference chunk's frames, for `irad reference --collect`'s run.json.
    #[serde(default)]
    frames: Vec<crate::commands::reference::ReferenceFrame>,
}

const HALVES: [&str; 2] = ["a", "b"];

fn done_path(dir: &Path, index: usize) -> PathBuf {
    dir.join("done").join(format!("{index:04}.json"))
}

fn run_folder(run: usize) -> String {
    format!("runs/{run:03}")
}

fn reference_folder(half: Option<&str>) -> String {
    match half {
        Some(h) => format!("reference/{h}"),
        None => "reference".to_string(),
    }
}

fn frame_files(folder: &str, frames: impl IntoIterator<Item = u32>) -> Vec<String> {
    frames
        .into_iter()
        .flat_map(|f| {
            let stem = crate::report::frame_stem(f);
            [
                format!("{folder}/{stem}.exr"),
                format!("{folder}/{stem}.png"),
            ]
        })
        .collect()
}

/// What a job reads: the scene's file (or the built-in's name) and the environment map.
fn inputs(seq: &config::Sequence, spec: &str) -> Vec<String> {
    let mut v = vec![if crate::scene::builtin::generate(spec).is_some() {
        format!("built-in scene {spec}")
    } else {
        absolute(Path::new(spec)).display().to_string()
    }];
    if let Some(config::EnvironmentChoice::File(p)) = &seq.environment {
        v.push(absolute(p).display().to_string());
    }
    v
}

fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// The frames `numbers` in chunks of at most `n` (the numbers are consecutive).
fn chunks(numbers: &[u32], n: u32) -> Vec<(u32, u32)> {
    numbers
        .chunks(n as usize)
        .map(|c| (c[0], c[c.len() - 1] + 1))
        .collect()
}

/// The jobs of a compare's plan: the reference's chunks, half a then half b, then its runs.
fn compare_work(plan: &Plan) -> Vec<(String, Work, bool)> {
    let cfg = &plan.cfg;
    let spp = crate::commands::compare::plan::halves(cfg.spp);
    let mut jobs = Vec::new();
    for (h, name) in HALVES.iter().enumerate() {
        for (start, end) in chunks(&plan.numbers, cfg.cluster.chunk_frames) {
            jobs.push((
                format!("reference {name} frames {start}..{end}"),
                Work::Reference {
                    half: Some(name.to_string()),
                    start,
                    end,
                    spp: spp[h],
                    seed: reference_cache::half_seed(cfg.sequence.seed, h),
                },
                false,
            ));
        }
    }
    for (i, r) in plan.runs().iter().enumerate() {
        let label = match r.method {
            config::Method::Instant => {
                crate::commands::compare::plan::label(r.sampler, r.vpls, r.knob)
            }
            m => m.name().to_string(),
        };
        jobs.push((
            format!("run {label}"),
            Work::Run {
                run: i,
                method: r.method.name().to_string(),
                sampler: r.sampler.to_string(),
                vpls: r.vpls,
                knob: r.knob.map(|k| k.0.to_string()),
                knob_value: r.knob.map(|k| k.1),
                seed: cfg.sequence.seed,
            },
            true,
        ));
    }
    jobs
}

/// The jobs of a reference's plan: its chunks.
fn reference_work(cfg: &config::Reference) -> Vec<(String, Work, bool)> {
    let numbers: Vec<u32> = cfg.sequence.frames_or_first().iter().collect();
    chunks(&numbers, cfg.cluster.chunk_frames)
        .into_iter()
        .map(|(start, end)| {
            (
                format!("reference frames {start}..{end}"),
                Work::Reference {
                    half: None,
                    start,
                    end,
                    spp: cfg.spp,
                    seed: cfg.sequence.seed,
                },
                false,
            )
        })
        .collect()
}

fn outputs_of(work: &Work, frames: &[u32], index: usize) -> Vec<String> {
    let mut out = match work {
        Work::Reference {
            half, start, end, ..
        } => frame_files(&reference_folder(half.as_deref()), *start..*end),
        Work::Run { run, .. } => {
            let folder = run_folder(*run);
            let mut v = frame_files(&folder, frames.iter().copied());
            v.push(format!("{folder}/rendered.json"));
            v
        }
    };
    out.push(format!("done/{index:04}.json"));
    out
}

/// Single-quoted for sh.
fn sh(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// Writes the plan of a study into `dir`: plan.json, the Slurm scripts and submit.sh. `args`
/// are the study's arguments without the cluster's flags. A folder already holding the same
/// plan keeps its finished jobs; one holding another plan is refused.
fn write_plan(
    dir: &Path,
    command: &str,
    args: Vec<String>,
    cluster: &config::Cluster,
    frames: Vec<u32>,
    work: Vec<(String, Work, bool)>,
    inputs: Vec<String>,
) -> Result<PlanFile> {
    crate::report::prepare_out_dir(dir)?;
    let dir = dir
        .canonicalize()
        .with_context(|| format!("{}: cannot resolve the plan's folder", dir.display()))?;
    let binary = std::env::current_exe().context("cannot find the irad binary's path")?;
    let jobs: Vec<Job> = work
        .into_iter()
        .enumerate()
        .map(|(index, (name, work, gpu))| Job {
            index,
            outputs: outputs_of(&work, &frames, index),
            name,
            work,
            gpu,
            args: vec![
                "irad".into(),
                "job".into(),
                dir.display().to_string(),
                index.to_string(),
            ],
            inputs: inputs.clone(),
        })
        .collect();
    let plan = PlanFile {
        irad: env!("CARGO_PKG_VERSION").to_string(),
        command: command.to_string(),
        args,
        cwd: std::env::current_dir().context("cannot read the current folder")?,
        binary,
        frames,
        chunk_frames: cluster.chunk_frames,
        jobs,
    };
    // The same plan again keeps its finished jobs; another one would take their markers
    // for its own.
    if dir.join(PLAN_FILE).exists() {
        let same = read_plan(&dir)
            .is_ok_and(|old| old.jobs == plan.jobs && old.args == plan.args && old.cwd == plan.cwd);
        if !same {
            bail!(
                "{}: holds another study's plan (or one of another irad); name an empty folder, or remove this one",
                dir.join(PLAN_FILE).display()
            );
        }
    }
    for sub in ["done", "logs"] {
        crate::report::prepare_out_dir(&dir.join(sub))?;
    }
    crate::report::write_json(&dir.join(PLAN_FILE), &plan)?;
    write_slurm(&dir, &plan, cluster)?;
    let gpu = plan.jobs.iter().filter(|j| j.gpu).count();
    crate::outln!(
        "wrote {}: {} ({} on CPUs, {} on a GPU); submit them to Slurm with `sh {}`, or run each with `irad job {} INDEX` and then `irad {command} --collect {}`",
        dir.join(PLAN_FILE).display(),
        crate::report::count(plan.jobs.len() as u64, "job", "jobs"),
        plan.jobs.len() - gpu,
        gpu,
        dir.join("submit.sh").display(),
        dir.display(),
        dir.display(),
    )?;
    Ok(plan)
}

/// The Slurm scripts: `cpu.sbatch` (the CPU jobs as one array), `gpu.sbatch` (the GPU jobs as
/// another, each with `--gres`), `collect.sbatch`, and `submit.sh`, which submits the arrays
/// and the collection depending on both (`--dependency=afterok:...`). A job array's tasks all
/// ask for the same resources, so the CPU and the GPU jobs are two arrays; the array indices
/// are the plan's job indices (the CPU jobs come first).
fn write_slurm(dir: &Path, plan: &PlanFile, cluster: &config::Cluster) -> Result<()> {
    // An #SBATCH line ends its value at white space, and has no quoting.
    for (what, p) in [
        ("plan's folder", dir),
        ("current folder", plan.cwd.as_path()),
    ] {
        let text = p.display().to_string();
        if text
            .chars()
            .any(|c| c.is_whitespace() || c == '"' || c == '\'')
        {
            bail!(
                "{text}: the {what} has a space or quote in its path, which Slurm's #SBATCH lines cannot hold; choose another"
            );
        }
    }
    let irad = format!("\"${{IRAD:-{}}}\"", plan.binary.display());
    let d = dir.display().to_string();
    let header = |name: &str, what: &str| {
        format!(
            "#!/bin/bash\n#SBATCH --job-name=irad-{name}\n#SBATCH --cpus-per-task={}\n#SBATCH --chdir={}\n#SBATCH --output={}/logs/{name}-%A_%a.out\n# {what}\n# Written by `irad {} --plan`; see docs/cluster.md. Run from {}.\nexport RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-{}}}\"\n",
            cluster.cpus_per_job,
            plan.cwd.display(),
            d,
            plan.command,
            sh(&plan.cwd.display().to_string()),
            cluster.cpus_per_job,
        )
    };
    let mut submit = format!(
        "#!/bin/sh\n# Submits the plan in {d} to Slurm: its job arrays, then the collection once every\n# task of them has succeeded. Prints the Slurm job ids.\nset -eu\nafter=\"\"\n"
    );
    for (gpu, name) in [(false, "cpu"), (true, "gpu")] {
        let idx: Vec<usize> = plan
            .jobs
            .iter()
            .filter(|j| j.gpu == gpu)
            .map(|j| j.index)
            .collect();
        let (Some(first), Some(last)) = (idx.first(), idx.last()) else {
            let _ = std::fs::remove_file(dir.join(format!("{name}.sbatch")));
            continue;
        };
        let what = if gpu {
            "The plan's GPU jobs (its runs), one array task each."
        } else {
            "The plan's CPU jobs (its reference chunks), one array task each."
        };
        let mut s = header(name, what);
        s = s.replacen(
            "#SBATCH --cpus-per-task",
            &format!(
                "#SBATCH --array={first}-{last}%{}\n#SBATCH --cpus-per-task",
                cluster.max_running
            ),
            1,
        );
        if gpu {
            if let Some(g) = cluster.gpu_gres() {
                s = s.replacen(
                    "#SBATCH --cpus-per-task",
                    &format!("#SBATCH --gres={g}\n#SBATCH --cpus-per-task"),
                    1,
                );
            }
        }
        s += &format!("exec {irad} job {} \"$SLURM_ARRAY_TASK_ID\"\n", sh(&d));
        write_script(&dir.join(format!("{name}.sbatch")), &s)?;
        submit += &format!(
            "id=$(sbatch --parsable {})\nid=${{id%%;*}}\necho \"{name} array: $id\"\nafter=\"$after:$id\"\n",
            sh(&dir.join(format!("{name}.sbatch")).display().to_string())
        );
    }
    let collect = header(
        "collect",
        "Merges the finished jobs into the study's outputs (what the study writes on one machine).",
    )
    .replace("%A_%a.out", "%j.out")
        + &format!("exec {irad} {} --collect {}\n", plan.command, sh(&d));
    write_script(&dir.join("collect.sbatch"), &collect)?;
    submit += &format!(
        "id=$(sbatch --parsable --dependency=\"afterok$after\" {})\necho \"collect: ${{id%%;*}}\"\n",
        sh(&dir.join("collect.sbatch").display().to_string())
    );
    write_script(&dir.join("submit.sh"), &submit)
}

fn write_script(path: &Path, text: &str) -> Result<()> {
    crate::image::write_bytes(path, text.as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))
            .with_context(|| format!("{}: cannot make it executable", path.display()))?;
    }
    Ok(())
}

/// `irad compare ... --plan DIR`: the compare as jobs; nothing is rendered.
pub fn plan_compare(cfg: &config::Compare, dir: &Path, args: Vec<String>) -> Result<PlanFile> {
    let plan = Plan::open(cfg, false, false)?;
    let inputs = inputs(&cfg.sequence, &plan.spec);
    write_plan(
        dir,
        "compare",
        args,
        &cfg.cluster,
        plan.numbers.clone(),
        compare_work(&plan),
        inputs,
    )
}

/// `irad reference ... --plan DIR`: the reference as chunks of frames; nothing is traced.
pub fn plan_reference(cfg: &config::Reference, dir: &Path, args: Vec<String>) -> Result<PlanFile> {
    cfg.validate()?;
    let spec = cfg.sequence.scene_or(config::DEFAULT_STILL_SCENE);
    // Loaded to check it now rather than in every job.
    cfg.sequence.load_scene(config::DEFAULT_STILL_SCENE)?;
    write_plan(
        dir,
        "reference",
        args,
        &cfg.cluster,
        cfg.sequence.frames_or_first().iter().collect(),
        reference_work(cfg),
        inputs(&cfg.sequence, spec),
    )
}

/// Reads `DIR/plan.json`.
pub fn read_plan(dir: &Path) -> Result<PlanFile> {
    let path = dir.join(PLAN_FILE);
    let bytes = std::fs::read(&path).with_context(|| {
        format!(
            "{}: cannot read the plan (write one with `irad compare ... --plan DIR`)",
            path.display()
        )
    })?;
    let plan: PlanFile = serde_json::from_slice(&bytes)
        .with_context(|| format!("{}: not a plan irad can read", path.display()))?;
    if plan.irad != env!("CARGO_PKG_VERSION") {
        bail!(
            "{}: written by irad {}, and this is irad {}: plan the study again with this one (another version may not give the same answer)",
            path.display(),
            plan.irad,
            env!("CARGO_PKG_VERSION")
        );
    }
    Ok(plan)
}

/// Whether a job ran to its end.
pub fn finished(dir: &Path, index: usize) -> bool {
    done_path(dir, index).is_file()
}

/// What `irad job` did.
#[derive(Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The job had finished before: nothing was done.
    Skipped,
    /// The job ran (from its start) to its end.
    Ran,
}

/// The job `index` of the plan, checked against what the study's settings plan now (an
/// edited plan.json, or one of another study, is refused rather than run).
fn job_of(dir: &Path, plan: &PlanFile, study: &Study, index: usize) -> Result<(Job, Option<Plan>)> {
    let Some(job) = plan.jobs.get(index) else {
        bail!(
            "{}: the plan has {} (0 to {}): there is no job {index}",
            dir.join(PLAN_FILE).display(),
            crate::report::count(plan.jobs.len() as u64, "job", "jobs"),
            plan.jobs.len().saturating_sub(1)
        );
    };
    let (work, compare) = match study {
        Study::Compare(c) => {
            let p = Plan::open(c, false, false)?;
            (compare_work(&p), Some(p))
        }
        Study::Reference(r) => (reference_work(r), None),
    };
    if work.get(index).map(|w| &w.1) != Some(&job.work) {
        bail!(
            "{}: job {index} ({}) is not what the plan's arguments plan: the file was edited; plan the study again",
            dir.join(PLAN_FILE).display(),
            job.name
        );
    }
    Ok((job.clone(), compare))
}

/// `irad job DIR INDEX`: runs job `index` of the plan in `dir` unless it has finished,
/// writing into `dir`. A job cut short (killed, out of time) left no marker and is redone
/// from its start.
pub fn run_job(dir: &Path, plan: &PlanFile, study: &Study, index: usize) -> Result<Outcome> {
    let (job, compare) = job_of(dir, plan, study, index)?;
    if finished(dir, index) {
        crate::outln!("job {index} ({}): finished before; skipped", job.name)?;
        return Ok(Outcome::Skipped);
    }
    let start = std::time::Instant::now();
    let mut frames = Vec::new();
    match (&job.work, study) {
        (
            Work::Reference {
                half,
                start: a,
                end: b,
                spp,
                seed,
            },
            study,
        ) => {
            let folder = dir.join(reference_folder(half.as_deref()));
            crate::report::prepare_out_dir(&folder)?;
            remove_temporaries(&folder, *a..*b);
            let (scene, seq, exposure, numbers, rr_cap_depth) = match (study, &compare) {
                (Study::Compare(c), Some(p)) => (
                    p.scene.clone(),
                    c.sequence.clone(),
                    c.render.exposure,
                    p.numbers.clone(),
                    crate::reference::RR_CAP_DEPTH,
                ),
                (Study::Reference(r), _) => (
                    r.sequence.load_scene(config::DEFAULT_STILL_SCENE)?,
                    r.sequence.clone(),
                    r.exposure,
                    r.sequence.frames_or_first().iter().collect(),
                    r.rr_cap_depth,
                ),
                _ => unreachable!("a compare has its plan"),
            };
            let seq = config::Sequence { seed: *seed, ..seq };
            // A compare's frames already in its reference cache (seen from this machine) are
            // copied, as a compare on one machine reuses them.
            let cached: Vec<u32> = match (&compare, half) {
                (Some(p), Some(h)) => (*a..*b)
                    .filter(|&f| copy_cached(&p.cache.join(h), &folder, f, seq.size))
                    .collect(),
                _ => Vec::new(),
            };
            if !cached.is_empty() {
                crate::outln!(
                    "job {index}: {} from the reference cache",
                    crate::report::count(cached.len() as u64, "frame", "frames")
                )?;
            }
            let todo = (b - a) as usize - cached.len();
            let pb = crate::report::progress(todo as u64 * seq.size.height as u64, &job.name);
            let mut t = std::time::Instant::now();
            crate::commands::reference::trace_walking(
                &scene,
                &seq,
                crate::reference::Sampling {
                    spp: *spp,
                    rr_cap_depth,
                },
                numbers.iter().copied().take_while(|&f| f < *b && todo > 0),
                &|f| (*a..*b).contains(&f) && !cached.contains(&f),
                &|| pb.inc(1),
                &mut |f, time, img| {
                    crate::report::write_frame(&folder, f, &img, exposure)?;
                    frames.push(crate::commands::reference::ReferenceFrame {
                        frame: f,
                        time,
                        seconds: t.elapsed().as_secs_f64(),
                        mean_rgb: img.mean().to_array(),
                    });
                    t = std::time::Instant::now();
                    Ok(())
                },
            )?;
            pb.finish_and_clear();
        }
        (Work::Run { run, .. }, Study::Compare(c)) => {
            let folder = dir.join(run_folder(*run));
            if folder.exists() {
                std::fs::remove_dir_all(&folder).with_context(|| {
                    format!("{}: cannot clear the run's folder", folder.display())
                })?;
            }
            crate::report::prepare_out_dir(&folder)?;
            let plan = Plan::open(c, true, false)?;
            let spec = plan.runs()[*run];
            let pb = crate::report::progress(plan.numbers.len() as u64, &job.name);
            let rendered = runs::render(&plan, spec, &pb)?;
            pb.finish_and_clear();
            for (&f, img) in plan.numbers.iter().zip(&rendered.images) {
                crate::report::write_frame(&folder, f, img, c.render.exposure)?;
            }
            let adapter = plan.gpu.as_ref().map(|g| g.adapter.to_string());
            crate::report::write_json(
                &folder.join("rendered.json"),
                &serde_json::json!({ "adapter": adapter, "rendered": rendered }),
            )?;
        }
        (Work::Run { .. }, Study::Reference(_)) => unreachable!("checked by job_of"),
    }
    let done = Done {
        job: index,
        name: job.name.clone(),
        host: hostname(),
        seconds: start.elapsed().as_secs_f64(),
        frames,
    };
    // Written last: it says every output above is in place.
    crate::report::write_json(&done_path(dir, index), &done)?;
    crate::outln!("job {index} ({}): done in {:.1} s", job.name, done.seconds)?;
    Ok(Outcome::Ran)
}

/// Copies reference frame `f` from the cache folder `from` into `to` when the cache holds it
/// whole and of `size` (its EXR and PNG); whether it did.
fn copy_cached(from: &Path, to: &Path, f: u32, size: config::Size) -> bool {
    let stem = crate::report::frame_stem(f);
    let (exr, png) = (
        from.join(format!("{stem}.exr")),
        from.join(format!("{stem}.png")),
    );
    let usable = png.is_file()
        && Hdr::read(&exr).is_ok_and(|i| (i.width, i.height) == (size.width, size.height));
    usable
        && [exr, png].iter().all(|src| {
            let dst = to.join(src.file_name().expect("a file"));
            crate::image::atomic_write(&dst, |tmp| {
                std::fs::copy(src, tmp)
                    .map(|_| ())
                    .map_err(anyhow::Error::from)
            })
            .is_ok()
        })
}

/// Removes what an earlier try of a job left half-written: the temporaries of its frames.
fn remove_temporaries(folder: &Path, frames: std::ops::Range<u32>) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    let stems: Vec<String> = frames
        .map(|f| format!("{}.", crate::report::frame_stem(f)))
        .collect();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some((file, _)) = crate::report::parse_temporary(&name) else {
            continue;
        };
        if stems.iter().any(|s| file.starts_with(s.as_str())) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

fn hostname() -> String {
    std::env::var("HOSTNAME")
        .ok()
        .or_else(|| std::fs::read_to_string("/etc/hostname").ok())
        .map(|h| h.trim().to_string())
        .unwrap_or_default()
}

/// Refuses to collect before every job finished, naming each missing one.
fn check_finished(dir: &Path, plan: &PlanFile) -> Result<()> {
    let missing: Vec<&Job> = plan
        .jobs
        .iter()
        .filter(|j| !finished(dir, j.index))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let list: Vec<String> = missing
        .iter()
        .take(10)
        .map(|j| {
            format!(
                "job {} ({}): no {}",
                j.index,
                j.name,
                done_path(dir, j.index).display()
            )
        })
        .collect();
    let more = if missing.len() > 10 {
        format!("\n  and {} more", missing.len() - 10)
    } else {
        String::new()
    };
    bail!(
        "{}: {} of {} jobs {} not finished:\n  {}{more}\nrun each with `irad job {} INDEX` (or submit the plan again: finished jobs are skipped), then collect",
        dir.display(),
        missing.len(),
        plan.jobs.len(),
        if missing.len() == 1 { "has" } else { "have" },
        list.join("\n  "),
        dir.display()
    )
}

fn read_frame(dir: &Path, job: &Job, file: String) -> Result<Hdr> {
    let path = dir.join(file);
    Hdr::read(&path).with_context(|| format!("job {} ({})", job.index, job.name))
}

/// The job that wrote reference frame `f` of half `half`.
fn reference_job<'a>(plan: &'a PlanFile, half: Option<&str>, f: u32) -> Result<&'a Job> {
    plan.jobs
        .iter()
        .find(|j| {
            matches!(&j.work, Work::Reference { half: h, start, end, .. }
                if h.as_deref() == half && (*start..*end).contains(&f))
        })
        .with_context(|| format!("the plan has no job for reference frame {f}"))
}

/// `irad compare --collect DIR`: merges the plan's finished jobs into the outputs the same
/// study writes on one machine (the reference's halves are also copied into the cache, for
/// a later compare of the same reference on this machine).
pub fn collect_compare(cfg: &config::Compare, dir: &Path, plan_file: &PlanFile) -> Result<()> {
    check_finished(dir, plan_file)?;
    let plan = Plan::open(cfg, false, true)?;
    let spp = crate::commands::compare::plan::halves(cfg.spp);
    let mut halves: [Vec<Hdr>; 2] = [Vec::new(), Vec::new()];
    for (h, name) in HALVES.iter().enumerate() {
        let folder = reference_folder(Some(name));
        let cache = plan.cache.join(name);
        crate::report::prepare_out_dir(&cache)?;
        for &f in &plan.numbers {
            let job = reference_job(plan_file, Some(name), f)?;
            let stem = crate::report::frame_stem(f);
            halves[h].push(read_frame(dir, job, format!("{folder}/{stem}.exr"))?);
            for ext in ["exr", "png"] {
                let to = cache.join(format!("{stem}.{ext}"));
                if !to.exists() {
                    let from = dir.join(format!("{folder}/{stem}.{ext}"));
                    crate::image::atomic_write(&to, |tmp| {
                        std::fs::copy(&from, tmp)
                            .map(|_| ())
                            .with_context(|| format!("{}: cannot copy", from.display()))
                    })?;
                }
            }
        }
    }
    let [a, b] = halves;
    let reference = reference_cache::from_halves(a, b, spp);
    let motion = plan.motion();
    let floor = reference.floor(&plan, &motion)?;
    let mut adapters: Vec<String> = Vec::new();
    // Each run measured as it is read: one run's frames in memory at a time (besides the
    // shown runs', which the page needs).
    let mut results = runs::Results::new(String::new());
    for (i, spec) in plan.runs().into_iter().enumerate() {
        let job = plan_file
            .jobs
            .iter()
            .find(|j| matches!(j.work, Work::Run { run, .. } if run == i))
            .with_context(|| format!("the plan has no job for run {i}"))?;
        let folder = run_folder(i);
        let path = dir.join(format!("{folder}/rendered.json"));
        #[derive(Deserialize)]
        struct File {
            adapter: Option<String>,
            rendered: runs::Rendered,
        }
        let file: File = std::fs::read(&path)
            .map_err(anyhow::Error::from)
            .and_then(|b| serde_json::from_slice(&b).map_err(anyhow::Error::from))
            .with_context(|| {
                format!(
                    "{}: cannot read job {} ({})",
                    path.display(),
                    job.index,
                    job.name
                )
            })?;
        let mut rendered = file.rendered;
        for &f in &plan.numbers {
            let stem = crate::report::frame_stem(f);
            rendered
                .images
                .push(read_frame(dir, job, format!("{folder}/{stem}.exr"))?);
        }
        if let Some(a) = file.adapter {
            if !adapters.contains(&a) {
                adapters.push(a);
            }
        }
        results.push(
            spec,
            runs::measure(&plan, &reference.frames, &motion, spec, rendered)?,
        );
    }
    results.adapter = adapters.join("; ");
    outputs::write(&plan, &reference.frames, &floor, &results)
}

/// `irad reference --collect DIR`: the plan's chunks into `--out` as `irad reference` writes
/// it (frames and run.json).
pub fn collect_reference(cfg: &config::Reference, dir: &Path, plan_file: &PlanFile) -> Result<()> {
    check_finished(dir, plan_file)?;
    let seq = &cfg.sequence;
    let spec = seq.scene_or(config::DEFAULT_STILL_SCENE);
    let scene = seq.load_scene(config::DEFAULT_STILL_SCENE)?;
    let frames = seq.frames_or_first();
    let mut planned = crate::report::run_files(frames.iter(), false);
    planned.retain(|f| f != "preview.gif" && f != "frames.jsonl");
    let out = crate::report::prepare_run_dir(&cfg.out, planned, cfg.overwrite)?;
    let mut records = Vec::new();
    for job in &plan_file.jobs {
        let path = done_path(dir, job.index);
        let done: Done = std::fs::read(&path)
            .map_err(anyhow::Error::from)
            .and_then(|b| serde_json::from_slice(&b).map_err(anyhow::Error::from))
            .with_context(|| format!("{}: cannot read", path.display()))?;
        records.extend(done.frames);
    }
    records.sort_by_key(|r| r.frame);
    for f in frames.iter() {
        let job = reference_job(plan_file, None, f)?;
        let stem = crate::report::frame_stem(f);
        for ext in ["exr", "png"] {
            let from = dir.join(format!("reference/{stem}.{ext}"));
            crate::image::atomic_write(&cfg.out.join(format!("{stem}.{ext}")), |tmp| {
                std::fs::copy(&from, tmp).map(|_| ()).with_context(|| {
                    format!(
                        "{}: cannot copy job {} ({})",
                        from.display(),
                        job.index,
                        job.name
                    )
                })
            })?;
        }
    }
    let record = crate::commands::reference::ReferenceRun {
        command: "reference",
        scene: spec,
        environment: scene.environment.as_deref().map(|e| e.name.clone()),
        settings: cfg,
        frames: records,
        threads: rayon::current_num_threads(),
        interrupted: false,
    };
    crate::report::write_json(&cfg.out.join("run.json"), &record)?;
    out.finish()?;
    crate::outln!(
        "wrote {} to {}",
        crate::report::count(frames.len() as u64, "frame", "frames"),
        cfg.out.display()
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_the_frames_once_in_order() {
        let n: Vec<u32> = (3..13).collect();
        assert_eq!(chunks(&n, 4), vec![(3, 7), (7, 11), (11, 13)]);
        assert_eq!(chunks(&n, 100), vec![(3, 13)]);
        assert_eq!(chunks(&[5], 1), vec![(5, 6)]);
    }

    #[test]
    fn shell_quoting_survives_quotes() {
        assert_eq!(sh("a b"), "'a b'");
        assert_eq!(sh("it's"), r"'it'\''s'");
    }
}
