#!/usr/bin/env python3
"""Re-runs the measurements of docs/results.md and writes it, with its charts.

    python3 benches/results.py            # the full run (about 30-40 minutes on 2 cores)
    python3 benches/results.py --quick    # a smoke run: smaller sizes, fewer frames (2-4 min)

Every figure in docs/results.md comes from this script: edit the script, not the page. The
page is stamped with the commit (`git rev-parse HEAD`, "+ uncommitted changes" if the code,
shaders, scenes or benches differ from it), the machine (CPU model and cores from /proc/cpuinfo and nproc, the load average before
and after) and the adapters (`irad info`), and says which mode wrote it.

What it runs, in order (the irad binary is built first with `cargo build --release` unless
`--no-build`; `--irad PATH` or `$IRAD` names another binary):

1. `irad info --backend vulkan|gl`: the adapter each backend chooses, as irad prints it.
2. `irad render` with its defaults (cornell-orbit, 72 frames, 256x256, 256 VPLs), once per
   backend, `--backend vulkan` and `--backend gl`: wall time of the command and frames/s.
3. `irad bench cornell-orbit --configs 256@256x256`: per-stage and per-pass times at 256 VPLs,
   once per backend.
4. `irad compare cornell-orbit --size 96x96 --frames 0..24 --spp 256 --vpls 256 --samplers
   uniform,cdf,mh,smc,frozen`: the relMSE / flicker table and the report's charts, copied to
   docs/results/. The path-traced reference is cached in out/results/cache, so a second run
   only renders the samplers. Then the same for `cornell`, `cornell-light`, `cornell-box`,
   `two-rooms` and `atrium` (their tables with ratios to cdf's, the floor taken out, and
   each one's flicker-against-error chart).
5. With `--cargo` (off by default: it adds 15-30 minutes on 2 cores): the first build,
   `cargo build --release` into an empty target folder (out/results/fresh-target, removed
   after), then `cargo test --release --no-fail-fast` from there (building the tests, then
   running all of them; the failures are named and the log kept in out/results/).
6. benches/speed_vs_mitsuba.py, only if `python3 -c "import mitsuba"` works (else a line says
   it was skipped and how to enable it; see benches/README.md).

Scratch output goes to out/results/ (ignored by git).
"""

import argparse
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
FIGS = DOCS / "results"
WORK = ROOT / "out" / "results"
BACKENDS = ["vulkan", "gl"]


def sh(cmd, **kw):
    """Runs `cmd` (a list), returns (stdout, seconds); raises with its stderr on failure."""
    t0 = time.monotonic()
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, **kw)
    dt = time.monotonic() - t0
    if p.returncode != 0:
        raise RuntimeError(
            f"{' '.join(map(str, cmd))} failed ({p.returncode}):\n{p.stderr[-3000:]}"
        )
    return p.stdout, dt


def log(msg):
    print(f"[results {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def load():
    return open("/proc/loadavg").read().split()[0]


def machine():
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cores = subprocess.run(["nproc"], capture_output=True, text=True).stdout.strip()
    return model, cores


def commit():
    head = subprocess.run(
        ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    dirty = subprocess.run(
        # What makes the figures: the code, shaders, scenes and this script (not the docs).
        ["git", "status", "--porcelain", "--untracked-files=no", "--", "src", "shaders", "scenes",
         "assets", "Cargo.toml", "Cargo.lock", "benches"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    ).stdout.strip()
    return head + (" + uncommitted changes" if dirty else "")


def irad_path(args):
    if args.irad:
        return Path(args.irad)
    if os.environ.get("IRAD"):
        return Path(os.environ["IRAD"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "release" / "irad"


def adapter(irad, backend):
    """The adapter line `irad info --backend B` marks as chosen, as printed."""
    try:
        out, _ = sh([irad, "info", "--backend", backend])
    except RuntimeError as e:
        return None, str(e).splitlines()[-1]
    chosen = [l.split(":", 1)[1].strip() for l in out.splitlines() if l.startswith("chosen:")]
    return (chosen[-1] if chosen else out.strip().splitlines()[-1].strip()), out


def render(irad, backend, quick):
    out = WORK / f"render-{backend}"
    # The script's own scratch folder: emptied, so that a folder an older irad wrote (before
    # output folders had a manifest) is not refused.
    shutil.rmtree(out, ignore_errors=True)
    flags = ["--backend", backend] + (["--frames", "0..12"] if quick else [])
    _, wall = sh([irad, "render", *flags, "--out", out])
    run = json.loads((out / "run.json").read_text())
    frames = run.get("frames", [])
    secs = [f.get("seconds") for f in frames if isinstance(f, dict) and f.get("seconds") is not None]
    return {
        "cmd": " ".join(["irad render", *flags]),
        "frames": len(frames),
        "wall": wall,
        "fps": len(frames) / wall if wall > 0 else float("nan"),
        "median": statistics.median(secs[1:]) if len(secs) > 1 else float("nan"),
        "first": secs[0] if secs else float("nan"),
        "png": out / "frame_0000.png",
    }


def bench(irad, backend, quick):
    out = WORK / f"bench-{backend}"
    repeat = "2" if quick else "5"
    cmd = [irad, "bench", "cornell-orbit", "--configs", "256@256x256", "--repeat", repeat,
           "--backend", backend, "--out", out]
    stdout, wall = sh(cmd)
    data = json.loads((out / "bench.json").read_text())
    row = data["rows"][0]
    how = next((l.split(":", 1)[1].strip() for l in stdout.splitlines() if l.startswith("pass times:")), "")
    return {
        "repeat": repeat,
        "frame": row["seconds_per_frame"],
        "stages": [(n, s) for n, s in row["stages"]],
        "how": how,
        "wall": wall,
    }


# The other built-in scenes compared like cornell-orbit (issue 25: the five animated built-ins
# and the atrium, each sampler at irad render's defaults otherwise).
OTHER_SCENES = ["cornell", "cornell-light", "cornell-box", "two-rooms", "atrium"]


def compare(irad, quick, scene="cornell-orbit"):
    out = WORK / ("compare" if scene == "cornell-orbit" else f"compare-{scene}")
    if quick:
        flags = ["--size", "48x48", "--frames", "0..8", "--spp", "16", "--vpls", "64",
                 "--samplers", "uniform,cdf,mh,smc,frozen"]
    else:
        flags = ["--size", "96x96", "--frames", "0..24", "--spp", "256", "--vpls", "256",
                 "--samplers", "uniform,cdf,mh,smc,frozen"]
    cmd = [irad, "compare", scene, *flags, "--out", out, "--cache", WORK / "cache"]
    _, wall = sh(cmd)
    m = json.loads((out / "metrics.json").read_text())
    page = (out / "report.html").read_text()
    verdict = re.search(r'<p class="verdict">(.*?)</p>', page, re.S)
    return {
        "cmd": f"irad compare {scene} " + " ".join(map(str, flags)),
        "metrics": m,
        "verdict": verdict.group(1) if verdict else None,
        "wall": wall,
        "dir": out,
    }


def mitsuba(skip):
    """None where Mitsuba does not import; a string saying why it was not run or did not
    finish; else speed_vs_mitsuba.py's output and wall time."""
    if skip:
        return "Skipped: `--no-mitsuba` was given."
    ok = subprocess.run([sys.executable, "-c", "import mitsuba"], capture_output=True).returncode == 0
    if not ok:
        return None
    try:
        stdout, wall = sh([sys.executable, "benches/speed_vs_mitsuba.py"])
    except RuntimeError as e:
        why = next((l for l in str(e).splitlines() if "ERROR" in l or "Error" in l), str(e).splitlines()[0])
        return f"Not measured: `python3 benches/speed_vs_mitsuba.py` failed: `{why.strip()}` (benches/README.md says how to set up Dr.Jit's LLVM)."
    return stdout, wall


def cargo_costs():
    """Times a first build in an empty target folder and the test suite after it."""
    fresh = WORK / "fresh-target"
    shutil.rmtree(fresh, ignore_errors=True)
    env = dict(os.environ, CARGO_TARGET_DIR=str(fresh))
    res = {"load0": load()}
    _, res["build"] = sh(["cargo", "build", "--release"], env=env)
    res["load1"] = load()
    t0 = time.monotonic()
    p = subprocess.run(["cargo", "test", "--release", "--no-fail-fast"], cwd=ROOT, env=env, capture_output=True, text=True)
    res["test"] = time.monotonic() - t0
    res["load2"] = load()
    res["rc"] = p.returncode
    text = p.stdout + p.stderr
    res["passed"] = sum(int(n) for n in re.findall(r"test result: \w+\. (\d+) passed", text))
    res["failed"] = sum(int(n) for n in re.findall(r"test result: \w+\. \d+ passed; (\d+) failed", text))
    res["skipped"] = [l.strip() for l in text.splitlines() if l.startswith("SKIPPED")]
    res["failures"] = sorted({l.split()[1] for l in text.splitlines()
                              if l.startswith("test ") and l.rstrip().endswith("FAILED")})
    (WORK / "cargo-test.log").write_text(text)
    m = re.search(r"Finished `release` profile.* in (.+)", text)
    res["test_build"] = m.group(1) if m else None
    shutil.rmtree(fresh, ignore_errors=True)
    return res


def f(x, d=5):
    return "-" if x is None else f"{x:.{d}f}"


def html_unescape(s):
    return s.replace("&quot;", '"').replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a smoke run: smaller, fewer frames")
    ap.add_argument("--irad", help="the irad binary (default: target/release/irad)")
    ap.add_argument("--no-build", action="store_true", help="do not run cargo build --release first")
    ap.add_argument("--no-mitsuba", action="store_true",
                    help="do not run benches/speed_vs_mitsuba.py (its first run path-traces a 2048-spp reference: 5-6 minutes on 2 cores)")
    ap.add_argument("--cargo", action="store_true",
                    help="also time a first build (empty target folder) and cargo test --release")
    ap.add_argument("--out", default=str(DOCS / "results.md"), help="the page to write")
    args = ap.parse_args()

    t_start = time.monotonic()
    load_before = load()
    WORK.mkdir(parents=True, exist_ok=True)
    FIGS.mkdir(parents=True, exist_ok=True)
    if not args.no_build and not args.irad and not os.environ.get("IRAD"):
        log("cargo build --release")
        sh(["cargo", "build", "--release"])
    irad = irad_path(args)
    if not irad.exists():
        sys.exit(f"{irad}: no irad binary (cargo build --release, or --irad PATH)")

    mode = "quick (--quick: smoke run, not the figures to quote)" if args.quick else "full"
    model, cores = machine()
    adapters = {}
    for b in BACKENDS:
        log(f"irad info --backend {b}")
        adapters[b] = adapter(irad, b)

    renders, benches = {}, {}
    for b in BACKENDS:
        if adapters[b][0] is None:
            continue
        log(f"irad render --backend {b}")
        try:
            renders[b] = render(irad, b, args.quick)
        except RuntimeError as e:
            renders[b] = str(e).splitlines()[-1]
        log(f"irad bench --backend {b}")
        try:
            benches[b] = bench(irad, b, args.quick)
        except RuntimeError as e:
            benches[b] = str(e).splitlines()[-1]

    log("irad compare (the reference first, unless cached)")
    cmp = compare(irad, args.quick)
    for name in ["warped_flicker_error", "flicker_error", "speed_accuracy", "replaced"]:
        shutil.copyfile(cmp["dir"] / "charts" / f"{name}.png", FIGS / f"{name}.png")
    frame = next((r["png"] for r in renders.values() if isinstance(r, dict) and r["png"].exists()), None)
    if frame:
        shutil.copyfile(frame, FIGS / "frame.png")

    others = {}
    for scene in OTHER_SCENES:
        log(f"irad compare {scene}")
        try:
            others[scene] = compare(irad, args.quick, scene)
            shutil.copyfile(others[scene]["dir"] / "charts" / "warped_flicker_error.png",
                            FIGS / f"{scene}_warped_flicker_error.png")
        except RuntimeError as e:
            others[scene] = str(e).splitlines()[0]

    costs = None
    if args.cargo:
        log("cargo build --release into an empty target folder, then cargo test --release")
        costs = cargo_costs()

    log("Mitsuba 3?")
    mts = mitsuba(args.no_mitsuba)

    load_after = load()
    total = time.monotonic() - t_start

    L = []
    L.append("# Measured results")
    L.append("")
    L.append("Written by `python3 benches/results.py`: do not edit by hand, run the script again. "
             "Scratch output is under `out/results/`.")
    L.append("")
    L.append(f"- mode: **{mode}**; the script took {total / 60:.1f} minutes")
    L.append(f"- commit: `{commit()}`")
    L.append(f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    L.append(f"- machine: {model}, {cores} cores (nproc), {platform.system()} {platform.release()}; "
             f"load average {load_before} before, {load_after} after (other work on the same cores "
             "slows every figure here)")
    for b in BACKENDS:
        a, full = adapters[b]
        L.append(f"- `--backend {b}`: " + (f"`{a}`" if a else f"unavailable ({full})"))
    L.append("")

    L.append("## The first build and the test suite")
    L.append("")
    if costs is None:
        L.append("Not measured in this run: `python3 benches/results.py --cargo` times `cargo build "
                 "--release` into an empty target folder and then `cargo test --release` (15-30 "
                 "minutes more on 2 cores).")
    else:
        L.append("`cargo build --release` into an empty target folder (every dependency compiled), "
                 "then `cargo test --release --no-fail-fast` in the same folder (the tests, examples "
                 "and benches compiled, then every test run, past a failing one). Both depend on what else the cores are doing: "
                 "the load averages are the 1-minute figures at each start and end.")
        L.append("")
        L.append("| step | minutes | load average at start, end |")
        L.append("| --- | --- | --- |")
        L.append(f"| first `cargo build --release` | {costs['build'] / 60:.1f} | {costs['load0']}, {costs['load1']} |")
        tb = f" (compiling: {costs['test_build']})" if costs["test_build"] else ""
        L.append(f"| then `cargo test --release`{tb} | {costs['test'] / 60:.1f} | {costs['load1']}, {costs['load2']} |")
        L.append("")
        L.append(f"Tests: {costs['passed']} passed, {costs['failed']} failed (exit status {costs['rc']})"
                 + (": " + ", ".join(f"`{t}`" for t in costs["failures"]) if costs["failures"] else "")
                 + "; the whole log is in `out/results/cargo-test.log`.")
        for sk in costs["skipped"]:
            L.append(f"`{sk}`")
    L.append("")

    L.append("## The first command: `irad render`")
    L.append("")
    L.append("Its defaults: `cornell-orbit`, 256x256, 256 VPLs, `--aa 2`"
             + (" (here only frames 0..12: `--quick`)." if args.quick else ", all 72 frames."))
    L.append("Wall time is the whole command (adapter, scene, every frame, the files); "
             "frames/s is frames over that; the median frame leaves out the first.")
    L.append("")
    L.append("| command | frames | wall s | frames/s | first frame s | median frame s |")
    L.append("| --- | --- | --- | --- | --- | --- |")
    for b in BACKENDS:
        r = renders.get(b)
        if isinstance(r, dict):
            L.append(f"| `{r['cmd']}` | {r['frames']} | {r['wall']:.1f} | {r['fps']:.2f} | "
                     f"{r['first']:.3f} | {r['median']:.3f} |")
        else:
            L.append(f"| `--backend {b}` | - | - | - | - | {r or 'not run'} |")
    L.append("")
    if frame:
        L.append("![frame 0 of irad render](results/frame.png)")
        L.append("")

    L.append("## Per pass: `irad bench` at 256 VPLs")
    L.append("")
    ok = {b: r for b, r in benches.items() if isinstance(r, dict)}
    if ok:
        first = next(iter(ok.values()))
        L.append(f"`irad bench cornell-orbit --configs 256@256x256 --repeat {first['repeat']}`: "
                 "milliseconds per frame, the mean of the repeats after one warm-up frame.")
        for b, r in ok.items():
            L.append(f"Pass times on `{b}`: {r['how']}.")
        L.append("")
        L.append("| stage (ms) | " + " | ".join(f"`{b}`" for b in ok) + " |")
        L.append("| --- |" + " --- |" * len(ok))
        names = [n for n, _ in first["stages"]]
        for i, n in enumerate(names):
            vals = [r["stages"][i][1] for r in ok.values()]
            if all(v == 0 for v in vals):
                continue
            L.append(f"| {n} | " + " | ".join(f"{v * 1e3:.2f}" for v in vals) + " |")
        L.append("| **frame** | " + " | ".join(f"**{r['frame'] * 1e3:.1f}**" for r in ok.values()) + " |")
    for b, r in benches.items():
        if not isinstance(r, dict):
            L.append(f"`{b}`: bench failed: {r}")
    L.append("")

    m = cmp["metrics"]
    fl = m["floor"]
    L.append("## Samplers: flicker against error (`irad compare`)")
    L.append("")
    L.append(f"`{cmp['cmd']}` (seed 1; {cmp['wall'] / 60:.1f} minutes, the reference included "
             "unless it was cached). relMSE is the mean over frames; flicker F1 the mean over frame "
             "pairs of the mean |e_t - e_(t-1)|; warped F1 the same with the previous frame's error "
             "moved along the camera's motion (the one to read here: the camera orbits); replaced "
             "the mean fraction of VPL slots renewed a frame. The last row is the reference's own "
             "noise, what a perfect renderer would measure (docs/math.md, \"The floor of the "
             "measurement\").")
    L.append("")
    adapter_note = next((n for n in m.get("notes", []) if n.startswith("adapter:")), None)
    if adapter_note:
        L.append(adapter_note.split(";")[0].replace("adapter: ", "Adapter: ") + ".")
        L.append("")
    if cmp["verdict"]:
        L.append(html_unescape(cmp["verdict"]))
        L.append("")
    L.append("| run | s / frame | relMSE | FLIP | flicker F1 | warped F1 | replaced |")
    L.append("| --- | --- | --- | --- | --- | --- | --- |")
    for r in m["runs"]:
        label = f"{r['sampler']} {r['vpls']}" if r.get("method", "instant") == "instant" else r["method"]
        if r.get("knob") is not None:
            label += f" {r['knob']}={r['knob_value']:g}"
        mm = r["metrics"]
        L.append(f"| {label} | {r['mean_seconds']:.3f} | {f(mm['mean_rel_mse'])} | {f(mm['mean_flip'], 4)} | "
                 f"{f(mm['flicker_f1'])} | {f(r['warped']['f1'])} | {r['mean_replaced']:.3f} |")
    L.append(f"| reference floor ({fl['spp'][0]}+{fl['spp'][1]} spp) | - | {f(fl['rel_mse'])} | - | "
             f"{f(fl['flicker_f1'])} | {f(fl.get('warped_f1'))} | - |")
    L.append("")
    L.append("![warped flicker against error](results/warped_flicker_error.png)")
    L.append("![error against time](results/speed_accuracy.png)")
    L.append("![VPL slots replaced per frame](results/replaced.png)")
    L.append("")
    L.append("`results/flicker_error.png` is the same chart with plain F1.")
    L.append("")

    L.append("## The other built-in scenes")
    L.append("")
    L.append("Each compared as above (same flags, its own cached reference): flicker (warped F1 where "
             "the camera or an object moves, else F1) and relMSE, each also as a ratio to `cdf`'s, "
             "with the reference's floor taken out as docs/math.md defines it (relMSE less the "
             "floor's; flicker in quadrature, sqrt(F1^2 - floor^2)). Every sampler runs at `irad "
             "render`'s defaults otherwise (8 frames accumulated), so the `mh` row is the default.")
    L.append("")
    for scene, c in others.items():
        L.append(f"### `{scene}`")
        L.append("")
        if isinstance(c, str):
            L.append(f"Not measured: `{c}`")
            L.append("")
            continue
        m = c["metrics"]
        fl = m["floor"]
        moving = any(r["warped"]["frames"] for r in m["runs"])
        key = "warped F1" if moving else "F1"
        L.append(f"`{c['cmd']}` ({c['wall'] / 60:.1f} minutes).")
        L.append("")

        def own(r):
            f1 = r["warped"]["f1"] if moving else r["metrics"]["flicker_f1"]
            f0 = fl["warped_f1"] if moving else fl["flicker_f1"]
            return f1, max(f1 * f1 - f0 * f0, 0.0) ** 0.5, r["metrics"]["mean_rel_mse"] - fl["rel_mse"]

        base = next((own(r) for r in m["runs"] if r["sampler"] == "cdf"), None)
        L.append(f"| sampler | s / frame | relMSE | {key} | relMSE / cdf's | {key} / cdf's |")
        L.append("| --- | --- | --- | --- | --- | --- |")
        for r in m["runs"]:
            f1, fo, rel = own(r)
            ratio = (lambda x, y: f"{x / y:.2f}" if y and y > 0 else "-")
            L.append(f"| {r['sampler']} | {r['mean_seconds']:.3f} | {f(r['metrics']['mean_rel_mse'])} | "
                     f"{f(f1)} | {ratio(rel, base[2]) if base else '-'} | {ratio(fo, base[1]) if base else '-'} |")
        f0 = fl["warped_f1"] if moving else fl["flicker_f1"]
        L.append(f"| reference floor | - | {f(fl['rel_mse'])} | {f(f0)} | - | - |")
        L.append("")
        L.append(f"![{scene}: flicker against error](results/{scene}_warped_flicker_error.png)")
        L.append("")

    L.append("## irad against Mitsuba 3")
    L.append("")
    if mts is None:
        L.append("Skipped: `python3 -c \"import mitsuba\"` failed on this machine. To include it, install "
                 "Mitsuba 3 and Dr.Jit's LLVM as benches/README.md says and run this script again "
                 "(it then runs `python3 benches/speed_vs_mitsuba.py`, whose first run path-traces a "
                 "2048-spp reference: 5-6 minutes on 2 cores).")
    elif isinstance(mts, str):
        L.append(mts)
    else:
        stdout, wall = mts
        L.append(f"`python3 benches/speed_vs_mitsuba.py` ({wall / 60:.1f} minutes):")
        L.append("")
        L.append("```")
        L.append(stdout.strip())
        L.append("```")
    L.append("")

    Path(args.out).write_text("\n".join(L))
    log(f"wrote {args.out} and {FIGS}/ in {total / 60:.1f} minutes ({mode})")


if __name__ == "__main__":
    main()
