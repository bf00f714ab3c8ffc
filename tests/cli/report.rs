//! `irad compare` end to end, and its report.html in a real browser (headless Chromium).

use crate::common;
use base64::Engine;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    common::fresh_dir(&format!("report-{name}"))
}

/// The browsers tried: `$IRAD_CHROMIUM` if set, else the usual names of Chromium.
fn browsers() -> Vec<String> {
    match std::env::var("IRAD_CHROMIUM") {
        Ok(b) => vec![b],
        Err(_) => ["chromium", "chromium-browser", "google-chrome"]
            .map(String::from)
            .to_vec(),
    }
}

fn chromium() -> Option<String> {
    browsers().into_iter().find(|c| {
        Command::new(c)
            .arg("--version")
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false)
    })
}

/// Whether this is a CI run: CI=true (GitHub Actions, GitLab and most others set it).
fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

fn headless(browser: &str, profile: &Path, extra: &[&str], page: &Path) -> std::process::Output {
    Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap()
}

/// `irad compare cornell-box` on 4 small frames with a 4-spp reference, plus `extra`.
fn compare(extra: &[&str], out: &Path, cache: &Path) -> std::process::Output {
    common::irad_command()
        .args([
            "compare",
            "cornell-box",
            "--size",
            "32x32",
            "--frames",
            "0..4",
            "--spp",
            "4",
        ])
        .args(extra)
        .args([
            "--out",
            out.to_str().unwrap(),
            "--cache",
            cache.to_str().unwrap(),
        ])
        .output()
        .unwrap()
}

/// `--sweep` and `--spp` are checked before anything renders, with errors naming the flag.
#[test]
fn compare_refuses_bad_sweeps_naming_the_flag() {
    let out = tmp("bad-sweep");
    let cache = tmp("bad-sweep-cache");
    for (args, expect) in [
        (&["--sweep", "mh:mh-rate"][..], "--sweep"),
        (&["--sweep", "mh-rate=0.1"], "names no sampler"),
        (&["--sweep", "mx:mh-rate=0.1"], "'mx' in 'mx:mh-rate=0.1' is not a sampler"),
        (&["--sweep", "mh:speed=1"], "'speed' in 'mh:speed=1' is not a knob"),
        (&["--sweep", "mh:mh-rate=0.1,x"], "'x' in 'mh:mh-rate=0.1,x' is not a number"),
        (&["--sweep", "mh:candidates=2.5"], "candidates takes whole numbers"),
        (&["--sweep", "mh:mh-rate=0.1,2"], "--sweep mh:mh-rate=0.1,2: --mh-rate 2 is out of range"),
        (&["--sweep", "cdf:mh-rate=0.1"], "--sweep cdf:mh-rate=0.1: cdf does not use --mh-rate (it uses --eps, --candidates, --camera-points)"),
        (&["--sweep", "uniform:eps=0.1", "--samplers", "uniform"], "uniform does not use --eps (it uses none of the knobs; sweep --vpls instead)"),
        (&["--sweep", "rejection:eps=0.1"], "rejection is not one of --samplers uniform,cdf,mh"),
    ] {
        let o = compare(args, &out, &cache);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} was accepted");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!cache.join("reference").exists(), "{args:?} traced a reference");
    }
    let o = common::irad_command()
        .args(["compare", "--spp", "1", "--cache", cache.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("--spp 1: the reference is traced as two independent halves"),
        "{err}"
    );
    assert!(!cache.join("reference").exists());
}

#[test]
fn compare_writes_tables_charts_and_a_report_that_loads_in_a_browser() {
    let out = tmp("out");
    let cache = tmp("cache");
    let o = compare(&["--vpls", "16,32"], &out, &cache);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // One CSV row per run and frame: 3 samplers x 2 VPL counts x 4 frames.
    let csv = std::fs::read_to_string(out.join("metrics.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 3 * 2 * 4, "{csv}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(json["runs"].as_array().unwrap().len(), 6);
    // The reference's noise floor: in metrics.json, the table, the page and the flicker
    // charts. cornell-box's moving block changes the reference's light paths, so its noise
    // changes from frame to frame there: the F1 floor is positive, and below the runs'.
    let floor = &json["floor"];
    let f1 = floor["flicker_f1"].as_f64().unwrap();
    let rel = floor["rel_mse"].as_f64().unwrap();
    assert_eq!(floor["spp"], serde_json::json!([2, 2]));
    assert!(f1 > 0.0 && rel > 0.0, "{floor}");
    assert!(floor["warped_f1"].as_f64().unwrap() > 0.0, "{floor}");
    for run in json["runs"].as_array().unwrap() {
        assert!(run["metrics"]["flicker_f1"].as_f64().unwrap() > f1, "{run}");
        assert!(run["warped"]["kept"].as_f64().unwrap() > 0.9, "{run}");
    }
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.lines().any(|l| l.starts_with("reference floor")
            && l.contains(&format!(" {rel:.5} "))
            && l.contains(&format!(" {f1:.5} "))),
        "{stdout}"
    );
    let page_text = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(page_text.contains("reference noise floor (2+2 spp halves)"));
    for chart in [
        "flicker",
        "speed_flicker",
        "flicker_error",
        "warped_flicker",
    ] {
        let svg = std::fs::read_to_string(out.join("charts").join(format!("{chart}.svg"))).unwrap();
        assert!(
            svg.contains("reference noise floor"),
            "{chart}.svg has no floor"
        );
        assert!(page_text.contains(&svg), "{chart}.svg is not on the page");
    }
    // Flicker heat maps: one sheet of every frame pair and the largest pair per shown run
    // (the 32-VPL runs, the middle of --vpls), on one scale, written under flicker/ and linked and embedded.
    assert!(page_text.contains("Flicker heat maps"));
    assert!(out.join("flicker/scale.png").exists());
    for run in ["uniform-32", "cdf-32", "mh-32"] {
        for file in [
            format!("flicker/{run}.png"),
            format!("flicker/{run}-largest.png"),
        ] {
            let bytes = std::fs::read(out.join(&file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert!(
                page_text.contains(&format!("href=\"{file}\"")),
                "{file} is not linked"
            );
            let b64 = base64::engine::general_purpose::STANDARD.encode(&bytes);
            assert!(page_text.contains(&b64), "{file} is not embedded");
            let img = image::load_from_memory(&bytes).unwrap();
            // frames 1..3 are three 32x32 tiles in a row (2-pixel gaps); the largest alone.
            let expect = if file.ends_with("-largest.png") {
                (32, 32)
            } else {
                (3 * 32 + 2 * 2, 32)
            };
            assert_eq!((img.width(), img.height()), expect, "{file}");
        }
    }
    // The constant floor is drawn at its value, written in the legend.
    let svg = std::fs::read_to_string(out.join("charts/flicker_error.svg")).unwrap();
    assert!(
        svg.contains(&format!("F1 {f1:.2e}")),
        "no F1 {f1:.2e} in flicker_error.svg"
    );
    for chart in [
        "flicker_error",
        "warped_flicker_error",
        "speed_accuracy",
        "speed_flicker",
        "flicker",
        "warped_flicker",
        "relmse",
        "replaced",
    ] {
        for ext in ["svg", "png"] {
            let p = out.join("charts").join(format!("{chart}.{ext}"));
            assert!(
                p.metadata().map(|m| m.len() > 1000).unwrap_or(false),
                "{} missing or empty",
                p.display()
            );
        }
    }
    // The reference is cached: a second run with the same settings renders no reference frame.
    let folders: Vec<PathBuf> = std::fs::read_dir(cache.join("reference"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(folders.len(), 1);
    let frame = folders[0].join("a/frame_0002.exr");
    assert!(folders[0].join("b/frame_0002.exr").exists());
    let before = frame.metadata().unwrap().modified().unwrap();
    let again_out = tmp("again");
    // With a sweep: mh once per rate, one curve on the flicker-against-error chart.
    let again = compare(
        &[
            "--vpls",
            "16",
            "--samplers",
            "uniform,mh",
            "--sweep",
            "mh:mh-rate=0.1,1",
        ],
        &again_out,
        &cache,
    );
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(again_out.join("metrics.json")).unwrap()).unwrap();
    let runs: Vec<(String, Option<f64>)> = json["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                format!("{} {}", r["sampler"].as_str().unwrap(), r["knob"]),
                r["knob_value"].as_f64(),
            )
        })
        .collect();
    assert_eq!(
        runs,
        [
            ("uniform null".to_string(), None),
            ("mh \"mh-rate\"".to_string(), Some(0.1)),
            ("mh \"mh-rate\"".to_string(), Some(1.0)),
        ]
    );
    let svg = std::fs::read_to_string(again_out.join("charts/flicker_error.svg")).unwrap();
    assert!(
        svg.contains("mh 16 (mh-rate 0.1..1)"),
        "no mh curve in flicker_error.svg"
    );
    assert_eq!(
        frame.metadata().unwrap().modified().unwrap(),
        before,
        "the cached reference was rendered again"
    );

    let page = out.join("report.html");
    let Some(browser) = chromium() else {
        let tried = browsers().join(", ");
        // In CI a missing browser fails the test; elsewhere the skip is written straight to
        // stderr, past the test harness's capture, so that it shows in a plain `cargo test`.
        assert!(
            !in_ci(),
            "no Chromium (tried {tried}): CI must run the browser check (.ci/run installs it)"
        );
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the browser check of report.html: no Chromium (tried {tried}; \
             apt-get install chromium, or set IRAD_CHROMIUM)"
        );
        return;
    };
    let profile = tmp("profile");
    let dom = headless(&browser, &profile, &["--dump-dom"], &page);
    let dom = String::from_utf8_lossy(&dom.stdout);
    let check = dom
        .split("id=\"check\">")
        .nth(1)
        .and_then(|s| s.split('<').next())
        .unwrap_or("");
    assert!(
        check.starts_with("report-ok"),
        "the page's own check says: '{check}'"
    );
    assert!(
        check.contains("broken=0") && check.contains("charts=8"),
        "{check}"
    );
    // 1 reference + 3 samplers x (frames + error) = 7 animations, and the flicker heat
    // maps: the colour bar + 3 samplers x (sheet + largest pair) = 7 images.
    assert!(check.contains("images=14"), "{check}");
    let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-screenshot.png");
    let s = headless(
        &browser,
        &profile,
        &[
            "--window-size=1400,2400",
            &format!("--screenshot={}", shot.display()),
        ],
        &page,
    );
    assert!(
        s.status.success() && shot.exists(),
        "no screenshot: {}",
        String::from_utf8_lossy(&s.stderr)
    );
    println!("screenshot: {}", shot.display());
    let _ = std::fs::remove_dir_all(&profile);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&cache);
    let _ = std::fs::remove_dir_all(&again_out);
}

/// Issue 24 item 8: a list that names an entry twice is refused naming the flag and the
/// entry, before any reference is traced.
#[test]
fn compare_refuses_duplicate_entries_naming_them() {
    let out = tmp("dupes");
    let cache = tmp("dupes-cache");
    for (args, expect) in [
        (
            &["--samplers", "uniform,mh,uniform"][..],
            "--samplers lists uniform twice",
        ),
        (
            &["--methods", "instant,instant"],
            "--methods lists instant twice",
        ),
        (&["--vpls", "16,32,16"], "--vpls lists 16 twice"),
        (
            &["--sweep", "mh:mh-rate=0.1,1,0.10"],
            "--sweep mh:mh-rate=0.1,1,0.1 lists 0.1 twice",
        ),
    ] {
        let o = compare(args, &out, &cache);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} was accepted");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(
            !cache.join("reference").exists(),
            "{args:?} traced a reference"
        );
    }
}

/// Issue 24 item 8: a cached reference frame cut short (a full disk, a kill) is traced again
/// with a note, and the comparison goes on.
#[test]
fn a_truncated_cached_reference_frame_is_traced_again() {
    let out = tmp("truncated");
    let cache = tmp("truncated-cache");
    let args = ["--samplers", "uniform", "--vpls", "8"];
    let o = compare(&args, &out, &cache);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frame = std::fs::read_dir(cache.join("reference"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path()
        .join("a/frame_0002.exr");
    let whole = std::fs::read(&frame).unwrap();
    std::fs::write(&frame, &whole[..whole.len() / 2]).unwrap();
    let o = compare(&args, &out, &cache);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("frame_0002.exr: the cached reference frame is unusable")
            && err.contains("tracing it again"),
        "{err}"
    );
    // Traced again with the same seed: the same bytes as the first time.
    assert_eq!(std::fs::read(&frame).unwrap(), whole);
}
