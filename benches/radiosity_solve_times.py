#!/usr/bin/env python3
"""Seconds of the classical radiosity solves (issue 29 item 2; docs/radiosity.md): renders
frame 0 of each scene (default `cornell` and `atrium`) at 64x64 with each method
(progressive, hierarchical, stochastic) RUNS times (default 3) and writes the
`radiosity_solve` stage (frames.jsonl `stages.radiosity_solve`) as min / median / max to
docs/results/radiosity_solve_times.md, with the adapter, the CPU count and the machine's load.
A run past TIMEOUT seconds (default 120) is stopped and recorded as "over TIMEOUT s"; the
method's remaining runs on that scene are skipped.

    python3 benches/radiosity_solve_times.py [target/release/irad] [RUNS] [TIMEOUT] [SCENES...]
"""
import json, os, platform, statistics, subprocess, sys, tempfile

args = sys.argv[1:]
binary = args[0] if args else "target/release/irad"
runs = int(args[1]) if len(args) > 1 else 3
timeout = float(args[2]) if len(args) > 2 else 120.0
scenes = args[3:] or ["cornell", "atrium"]
methods = ["progressive", "hierarchical", "stochastic"]
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
tmp = tempfile.mkdtemp(prefix="irad-radiosity-times-")


def load():
    return " ".join(open("/proc/loadavg").read().split()[:3])


def cpu():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                        capture_output=True, text=True).stdout.strip()
before = load()
adapter = None
rows = []
for scene in scenes:
    for method in methods:
        times, over = [], False
        for r in range(runs):
            out = os.path.join(tmp, f"{scene}-{method}-{r}")
            cmd = [binary, "render", scene, "--method", method, "--frames", "0",
                   "--size", "64x64", "--out", out]
            try:
                subprocess.run(cmd, capture_output=True, check=True, timeout=timeout)
            except subprocess.TimeoutExpired:
                over = True
                break
            fr = json.loads(open(os.path.join(out, "frames.jsonl")).readline())
            times.append(fr["stages"]["radiosity_solve"])
            if adapter is None:
                a = json.load(open(os.path.join(out, "run.json")))["adapter"]
                adapter = f"{a.get('name')} ({a.get('backend')}, {a.get('device_type')})"
            print(f"{scene} {method} run {r}: {times[-1]:.2f} s", flush=True)
        if over:
            print(f"{scene} {method}: over {timeout:.0f} s", flush=True)
        v = sorted(times)
        if v:
            cell = f"{v[0]:.2f} / {statistics.median(v):.2f} / {v[-1]:.2f}"
        else:
            cell = "-"
        note = f"over {timeout:.0f} s (stopped)" if over else ""
        rows.append((scene, method, len(v), cell, note))

lines = [
    "# Classical radiosity solve seconds",
    "",
    "Written by `benches/radiosity_solve_times.py` (issue 29 item 2): the `radiosity_solve`",
    "stage of `irad render SCENE --method METHOD --frames 0 --size 64x64` (frames.jsonl",
    "`stages.radiosity_solve`), min / median / max over the runs that finished.",
    "",
    f"- binary: `{binary}` at commit {commit or 'unknown'}",
    f"- adapter: {adapter or 'unknown'}; CPU: {cpu()}, {os.cpu_count()} logical CPUs",
    f"- load average (1, 5, 15 min) before: {before}; after: {load()}",
    f"- timeout per run: {timeout:.0f} s",
    "",
    "| scene | method | runs | solve s (min / median / max) | note |",
    "| --- | --- | --- | --- | --- |",
]
lines += [f"| {s} | {m} | {n} | {c} | {note} |" for s, m, n, c, note in rows]
path = os.path.join(root, "docs", "results", "radiosity_solve_times.md")
os.makedirs(os.path.dirname(path), exist_ok=True)
open(path, "w").write("\n".join(lines) + "\n")
print(f"wrote {path}")
