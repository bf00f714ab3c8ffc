//! Past one machine (issue 28): a study written as a plan of jobs (`--plan DIR`), each run by
//! `irad job DIR INDEX`, and merged by `--collect DIR`, gives the single-machine study's
//! reference and figures bit for bit; a finished job is skipped, a half-written one redone,
//! and a missing one named by `--collect`.

use crate::common::{fresh_dir, irad_command};
use std::path::{Path, PathBuf};
use std::process::Output;

/// `irad args` run in `dir`.
fn irad_in(dir: &Path, args: &[&str]) -> Output {
    irad_command().current_dir(dir).args(args).output().unwrap()
}

/// What `out` printed, after checking it succeeded.
fn ok(what: &str, out: Output) -> String {
    let (so, se) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "{what} failed:\n{so}\n{se}");
    so
}

/// What `out` said on stderr, after checking it failed.
fn fails(what: &str, out: Output) -> String {
    assert!(!out.status.success(), "{what} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A tiny study: moving geometry (so the reference's chunks walk a changing BVH), two runs.
const STUDY: &[&str] = &[
    "cornell-box",
    "--size",
    "16x16",
    "--frames",
    "0..5",
    "--spp",
    "4",
    "--samplers",
    "uniform,mh",
    "--vpls",
    "8",
];

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// A JSON value without the times measured (which no two runs share).
fn without_times(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Object(m) => Value::Object(
            m.into_iter()
                .filter(|(k, _)| k != "seconds" && k != "mean_seconds")
                .map(|(k, v)| (k, without_times(v)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.into_iter().map(without_times).collect()),
        v => v,
    }
}

/// metrics.csv without its seconds column.
fn csv_without_seconds(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "seconds").unwrap();
    text.lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.remove(col);
            f.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The whole cycle on one machine: plan, every job, the re-runs a cluster makes (a finished
/// job, a killed one), a collect with a job missing, the collect, and the single-machine
/// compare it must equal. Takes about 15 s on 2 cores (llvmpipe).
#[test]
fn a_planned_compare_collects_to_the_single_machine_compare() {
    let root = fresh_dir("cluster");
    std::fs::create_dir_all(&root).unwrap();
    let mut args = STUDY.to_vec();
    args.extend(["--out", "collected", "--cache", "cache-c"]);
    let mut plan_args = vec!["compare"];
    plan_args.extend(&args);
    plan_args.extend([
        "--plan",
        "plan",
        "--chunk-frames",
        "2",
        "--gres",
        "none",
        "--cpus-per-job",
        "1",
    ]);
    let said = ok("plan", irad_in(&root, &plan_args));
    assert!(said.contains("8 jobs (6 on CPUs, 2 on a GPU)"), "{said}");
    let dir = root.join("plan");
    assert!(!root.join("collected").exists(), "a plan renders nothing");
    let plan: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("plan.json")).unwrap()).unwrap();
    // The plan's arguments are the study on one machine, without the cluster's flags.
    let plan_args: Vec<&str> = plan["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    assert_eq!(plan_args, args);
    let jobs = plan["jobs"].as_array().unwrap();
    let names: Vec<&str> = jobs.iter().map(|j| j["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "reference a frames 0..2",
            "reference a frames 2..4",
            "reference a frames 4..5",
            "reference b frames 0..2",
            "reference b frames 2..4",
            "reference b frames 4..5",
            "run uniform 8",
            "run mh 8"
        ]
    );
    let gpu: Vec<bool> = jobs.iter().map(|j| j["gpu"].as_bool().unwrap()).collect();
    assert_eq!(gpu, [false, false, false, false, false, false, true, true]);
    // The halves' seed streams differ; a half's chunks share its stream.
    let seed = |i: usize| jobs[i]["work"]["seed"].as_u64().unwrap();
    assert_eq!(seed(0), seed(2));
    assert_ne!(seed(0), seed(3));
    assert_eq!(jobs[7]["work"]["seed"], 1);
    assert_eq!(
        jobs[1]["outputs"],
        serde_json::json!([
            "reference/a/frame_0002.exr",
            "reference/a/frame_0002.png",
            "reference/a/frame_0003.exr",
            "reference/a/frame_0003.png",
            "done/0001.json"
        ])
    );
    let cpu = std::fs::read_to_string(dir.join("cpu.sbatch")).unwrap();
    let gpu = std::fs::read_to_string(dir.join("gpu.sbatch")).unwrap();
    let submit = std::fs::read_to_string(dir.join("submit.sh")).unwrap();
    assert!(cpu.contains("#SBATCH --array=0-5%32\n"), "{cpu}");
    assert!(gpu.contains("#SBATCH --array=6-7%32\n"), "{gpu}");
    assert!(!gpu.contains("--gres"), "--gres none: {gpu}");
    assert!(
        submit.contains("--dependency=\"afterok$after\""),
        "{submit}"
    );

    // Before any job: every one named.
    let e = fails("collect", irad_in(&root, &["compare", "--collect", "plan"]));
    assert!(e.contains("8 of 8 jobs have not finished"), "{e}");
    assert!(e.contains("job 0 (reference a frames 0..2): no "), "{e}");

    // Every job, from another folder (a job runs in the folder the plan was written in).
    let elsewhere = std::env::temp_dir();
    let d = dir.to_str().unwrap();
    for i in 0..8 {
        let said = ok("job", irad_in(&elsewhere, &["job", d, &i.to_string()]));
        assert!(
            said.contains(&format!("job {i} (")) && said.contains("done in"),
            "{said}"
        );
    }
    let e = fails("job 8", irad_in(&root, &["job", "plan", "8"]));
    assert!(e.contains("there is no job 8"), "{e}");

    // A finished job is skipped: its files are left as they are.
    let frame = dir.join("reference/a/frame_0000.exr");
    let (bytes, when) = (
        std::fs::read(&frame).unwrap(),
        std::fs::metadata(&frame).unwrap().modified().unwrap(),
    );
    let said = ok("job 0 again", irad_in(&root, &["job", "plan", "0"]));
    assert!(said.contains("finished before; skipped"), "{said}");
    assert_eq!(std::fs::metadata(&frame).unwrap().modified().unwrap(), when);

    // A job killed half-way (no marker, a frame cut short, a temporary left) is redone, to
    // the same bytes.
    let killed = dir.join("reference/b/frame_0001.exr");
    let whole = std::fs::read(&killed).unwrap();
    std::fs::remove_file(dir.join("done/0003.json")).unwrap();
    std::fs::write(&killed, &whole[..10]).unwrap();
    let stray = dir.join("reference/b/.frame_0000.exr.tmp-4000000.exr");
    std::fs::write(&stray, b"half").unwrap();
    let said = ok("job 3 again", irad_in(&root, &["job", "plan", "3"]));
    assert!(said.contains("done in"), "{said}");
    assert_eq!(std::fs::read(&killed).unwrap(), whole);
    assert!(!stray.exists());
    assert_eq!(std::fs::read(&frame).unwrap(), bytes);
    // A run killed half-way, likewise.
    let run_frame = dir.join("runs/001/frame_0004.exr");
    let run_bytes = std::fs::read(&run_frame).unwrap();
    std::fs::remove_file(dir.join("done/0007.json")).unwrap();
    std::fs::remove_file(&run_frame).unwrap();
    ok("job 7 again", irad_in(&root, &["job", "plan", "7"]));
    assert_eq!(std::fs::read(&run_frame).unwrap(), run_bytes);

    // A missing chunk is named.
    let marker = dir.join("done/0004.json");
    std::fs::rename(&marker, root.join("aside.json")).unwrap();
    let e = fails("collect", irad_in(&root, &["compare", "--collect", "plan"]));
    assert!(e.contains("1 of 8 jobs has not finished"), "{e}");
    assert!(
        e.contains(&format!(
            "job 4 (reference b frames 2..4): no {}",
            marker.display()
        )),
        "{e}"
    );
    std::fs::rename(root.join("aside.json"), &marker).unwrap();
    // Flags besides --collect are refused (the study is the plan's).
    let e = fails(
        "collect --spp",
        irad_in(&root, &["compare", "--collect", "plan", "--spp", "8"]),
    );
    assert!(e.contains("--spp is not used with --collect"), "{e}");

    ok("collect", irad_in(&root, &["compare", "--collect", "plan"]));
    let mut single = vec!["compare"];
    single.extend(STUDY);
    single.extend(["--out", "single", "--cache", "cache-s"]);
    ok("single-machine compare", irad_in(&root, &single));

    // The same answer: the reference (both halves, every frame), the figures, the page's
    // images, bit for bit; only what measures time differs.
    let (c, s) = (root.join("collected"), root.join("single"));
    let outputs = files(&s);
    assert_eq!(files(&c), outputs);
    let timed = ["metrics.csv", "metrics.json", "report.html"];
    let mut same = 0;
    for f in &outputs {
        let name = f.to_string_lossy();
        if timed.contains(&name.as_ref()) || name.contains("speed_") {
            continue;
        }
        assert!(
            std::fs::read(c.join(f)).unwrap() == std::fs::read(s.join(f)).unwrap(),
            "{name} differs"
        );
        same += 1;
    }
    assert!(same >= 20, "only {same} files compared");
    let json = |d: &Path| -> serde_json::Value {
        without_times(
            serde_json::from_slice(&std::fs::read(d.join("metrics.json")).unwrap()).unwrap(),
        )
    };
    assert_eq!(json(&c), json(&s));
    assert_eq!(
        csv_without_seconds(&c.join("metrics.csv")),
        csv_without_seconds(&s.join("metrics.csv"))
    );
    let cache_of = |cache: &str| -> PathBuf {
        let r = root.join(cache).join("reference");
        std::fs::read_dir(&r)
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path()
    };
    let (cc, cs) = (cache_of("cache-c"), cache_of("cache-s"));
    assert_eq!(cc.file_name(), cs.file_name());
    for h in ["a", "b"] {
        for f in 0..5 {
            let name = format!("{h}/frame_{f:04}.exr");
            let single = std::fs::read(cs.join(&name)).unwrap();
            assert!(
                std::fs::read(dir.join("reference").join(&name)).unwrap() == single,
                "{name}"
            );
            // Collected into the cache too, for a later compare on this machine.
            assert!(std::fs::read(cc.join(&name)).unwrap() == single, "{name}");
        }
    }
    // Another study of the same reference: its chunks copy the cached frames.
    let mut other = vec!["compare"];
    other.extend(STUDY);
    other.extend(["--samplers", "cdf", "--out", "other", "--cache", "cache-c"]);
    other.extend(["--plan", "plan2", "--chunk-frames", "2"]);
    ok("plan 2", irad_in(&root, &other));
    let said = ok("plan 2 job 4", irad_in(&root, &["job", "plan2", "4"]));
    assert!(said.contains("2 frames from the reference cache"), "{said}");
    let name = "b/frame_0003.exr";
    assert!(
        std::fs::read(root.join("plan2/reference").join(name)).unwrap()
            == std::fs::read(cs.join(name)).unwrap()
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// `irad reference --plan` and `--collect`: the chunks merged are the frames of one trace.
#[test]
fn a_planned_reference_collects_to_the_single_machine_reference() {
    let root = fresh_dir("cluster-reference");
    std::fs::create_dir_all(&root).unwrap();
    let study = [
        "cornell-box",
        "--size",
        "12x12",
        "--frames",
        "2..7",
        "--spp",
        "3",
    ];
    let mut plan = vec!["reference"];
    plan.extend(study);
    plan.extend([
        "--out",
        "collected",
        "--plan",
        "plan",
        "--chunk-frames",
        "2",
    ]);
    let said = ok("plan", irad_in(&root, &plan));
    assert!(said.contains("3 jobs (3 on CPUs, 0 on a GPU)"), "{said}");
    assert!(!root.join("plan/gpu.sbatch").exists());
    for i in 0..3 {
        ok("job", irad_in(&root, &["job", "plan", &i.to_string()]));
    }
    ok(
        "collect",
        irad_in(&root, &["reference", "--collect", "plan"]),
    );
    let mut single = vec!["reference"];
    single.extend(study);
    single.extend(["--out", "single"]);
    ok("single", irad_in(&root, &single));
    for f in 2..7 {
        let name = format!("frame_{f:04}.exr");
        assert!(
            std::fs::read(root.join("collected").join(&name)).unwrap()
                == std::fs::read(root.join("single").join(&name)).unwrap(),
            "{name}"
        );
    }
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("collected/run.json")).unwrap()).unwrap();
    let frames: Vec<u64> = run["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["frame"].as_u64().unwrap())
        .collect();
    assert_eq!(frames, [2, 3, 4, 5, 6]);
    // A compare's collect refuses a reference's plan.
    let e = fails("collect", irad_in(&root, &["compare", "--collect", "plan"]));
    assert!(
        e.contains("collect it with `irad reference --collect`"),
        "{e}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// The default GPU job asks Slurm for a GPU; another plan in a folder holding one is refused.
#[test]
fn a_plan_asks_for_a_gpu_and_keeps_to_its_folder() {
    let root = fresh_dir("cluster-gres");
    std::fs::create_dir_all(&root).unwrap();
    let args = [
        "compare",
        "--size",
        "8x8",
        "--frames",
        "0..2",
        "--spp",
        "2",
        "--samplers",
        "mh",
        "--vpls",
        "8",
        "--plan",
        "plan",
    ];
    ok("plan", irad_in(&root, &args));
    let gpu = std::fs::read_to_string(root.join("plan/gpu.sbatch")).unwrap();
    assert!(gpu.contains("#SBATCH --gres=gpu:1\n"), "{gpu}");
    // The same plan again is fine (finished jobs are kept); another one is refused.
    ok("plan again", irad_in(&root, &args));
    let mut other = args.to_vec();
    other[6] = "4";
    let e = fails("another plan", irad_in(&root, &other));
    assert!(e.contains("holds another study's plan"), "{e}");
    // So is a folder whose plan this irad cannot read (its markers are not this plan's).
    std::fs::create_dir_all(root.join("old/done")).unwrap();
    std::fs::write(root.join("old/plan.json"), r#"{"irad": "0.0.1"}"#).unwrap();
    let mut old = args.to_vec();
    old[12] = "old";
    let e = fails("old plan", irad_in(&root, &old));
    assert!(e.contains("holds another study's plan"), "{e}");
    let e = fails(
        "bad gres",
        irad_in(&root, &["compare", "--plan", "p2", "--gres", "gpu;rm"]),
    );
    assert!(e.contains("--gres 'gpu;rm'"), "{e}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// A job killed (SIGKILL) after its first frame, then run again, writes the frames of one
/// uninterrupted trace. About 8 s on 2 cores.
#[test]
fn a_killed_job_is_redone_to_the_same_frames() {
    let root = fresh_dir("cluster-kill");
    std::fs::create_dir_all(&root).unwrap();
    let study = [
        "cornell-box",
        "--size",
        "48x48",
        "--frames",
        "0..3",
        "--spp",
        "256",
    ];
    let mut plan = vec!["reference"];
    plan.extend(study);
    plan.extend(["--plan", "plan", "--chunk-frames", "3"]);
    ok("plan", irad_in(&root, &plan));
    let mut job = irad_command()
        .current_dir(&root)
        .args(["job", "plan", "0"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let first = root.join("plan/reference/frame_0000.exr");
    let start = std::time::Instant::now();
    while !first.exists() {
        assert!(start.elapsed().as_secs() < 120, "no first frame");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    job.kill().unwrap();
    job.wait().unwrap();
    assert!(
        !root.join("plan/done/0000.json").exists(),
        "the job finished before it was killed: make it slower"
    );
    assert!(!root.join("plan/reference/frame_0002.exr").exists());
    let e = fails(
        "collect",
        irad_in(&root, &["reference", "--collect", "plan"]),
    );
    assert!(e.contains("job 0 (reference frames 0..3): no "), "{e}");
    let said = ok("job again", irad_in(&root, &["job", "plan", "0"]));
    assert!(said.contains("done in"), "{said}");
    let mut single = vec!["reference"];
    single.extend(study);
    single.extend(["--out", "single"]);
    ok("single", irad_in(&root, &single));
    for f in 0..3 {
        let name = format!("frame_{f:04}.exr");
        assert!(
            std::fs::read(root.join("plan/reference").join(&name)).unwrap()
                == std::fs::read(root.join("single").join(&name)).unwrap(),
            "{name}"
        );
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// `irad reference --rr-cap-depth`: in a furnace of albedo 0.99 (radiance 100) a reference
/// capped from bounce 4096 differs from one capped from 3 (the default) and comes out nearer
/// 100 on average; run.json records it; a plan's jobs trace with it (collected frames equal
/// the single-machine ones); out of range, the flag is named.
#[test]
fn the_roulettes_cap_depth_reaches_every_trace() {
    let root = fresh_dir("cluster-rr-cap-depth");
    std::fs::create_dir_all(&root).unwrap();
    let furnace =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/furnace.gltf"))
            .unwrap();
    let mut white: serde_json::Value = serde_json::from_str(&furnace).unwrap();
    white["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
        serde_json::json!([0.99, 0.99, 0.99, 1.0]);
    let white = white.to_string();
    std::fs::write(root.join("white.gltf"), white).unwrap();
    let study = ["white.gltf", "--size", "8x8", "--spp", "256"];
    let trace = |out: &str, extra: &[&str]| {
        let mut a = vec!["reference"];
        a.extend(study);
        a.extend(["--out", out]);
        a.extend(extra);
        ok(out, irad_in(&root, &a));
        std::fs::read(root.join(out).join("frame_0000.exr")).unwrap()
    };
    let late = trace("late", &["--rr-cap-depth", "4096"]);
    let early = trace("early", &[]);
    assert_ne!(late, early);
    let mean = |dir: &str| -> f64 {
        let run: serde_json::Value =
            serde_json::from_slice(&std::fs::read(root.join(dir).join("run.json")).unwrap())
                .unwrap();
        run["frames"][0]["mean_rgb"][0].as_f64().unwrap()
    };
    // Measured: 100.0 capped from 4096, 80.0 from 3.
    println!(
        "mean capped from 4096: {}, from 3: {}",
        mean("late"),
        mean("early")
    );
    assert!((mean("late") - 100.0).abs() < 3.0, "{}", mean("late"));
    assert!(
        (mean("early") - 100.0).abs() > (mean("late") - 100.0).abs(),
        "{} {}",
        mean("early"),
        mean("late")
    );
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("late/run.json")).unwrap()).unwrap();
    assert_eq!(run["settings"]["rr_cap_depth"], 4096);
    // Planned: one frame, one job, which traces capped from 4096.
    let mut plan = vec!["reference"];
    plan.extend(study);
    plan.extend([
        "--rr-cap-depth",
        "4096",
        "--out",
        "collected",
        "--plan",
        "plan",
    ]);
    ok("plan", irad_in(&root, &plan));
    ok("job", irad_in(&root, &["job", "plan", "0"]));
    ok(
        "collect",
        irad_in(&root, &["reference", "--collect", "plan"]),
    );
    assert!(std::fs::read(root.join("collected/frame_0000.exr")).unwrap() == late);
    let e = fails(
        "cap 2",
        irad_in(&root, &["reference", "white.gltf", "--rr-cap-depth", "2"]),
    );
    assert!(
        e.contains("--rr-cap-depth 2 is out of range: it must be 3 to 65536"),
        "{e}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}
