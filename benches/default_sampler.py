#!/usr/bin/env python3
"""Which sampler should `irad render` use by default? Runs `irad compare` on the animated
built-ins for several seeds and prints, per scene and sampler, the ratios of relMSE and
flicker to cdf's (min / median / max over the seeds), with the reference's floor taken out
as docs/math.md ("The floor of the measurement") defines it: relMSE - floor, and
sqrt(F1^2 - floor^2) for the warped flicker F1 (the plain F1 where nothing moves).

    python3 benches/default_sampler.py [--irad PATH] [--seeds 1,2,3,4] [--spp 256]
        [--scenes cornell,cornell-light,cornell-box,cornell-orbit,two-rooms]

Writes docs/results/default_sampler.md (stamped with the commit, the machine and the
adapter; `--page ''` to skip) and prints the table. 96x96, 24 frames, 256 VPLs as the issue's
table; the references are cached per scene and seed under out/default_sampler/cache.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

p = argparse.ArgumentParser()
p.add_argument("--irad", default=os.environ.get("IRAD", "target/release/irad"))
p.add_argument("--seeds", default="1,2,3,4")
p.add_argument("--spp", type=int, default=256)
p.add_argument("--vpls", type=int, default=256)
p.add_argument("--samplers", default="uniform,cdf,mh,smc,frozen")
p.add_argument("--scenes", default="cornell,cornell-light,cornell-box,cornell-orbit,two-rooms")
p.add_argument("--out", default="out/default_sampler")
p.add_argument("--page", default="docs/results/default_sampler.md")
a = p.parse_args()

seeds = [int(s) for s in a.seeds.split(",")]
scenes = a.scenes.split(",")
samplers = a.samplers.split(",")
rows = {}  # (scene, sampler) -> list of (relmse ratio, flicker ratio, relmse, flicker)
t0 = time.time()
for scene in scenes:
    for seed in seeds:
        out = os.path.join(a.out, f"{scene}-{seed}")
        cmd = [a.irad, "compare", scene, "--size", "96x96", "--frames", "0..24",
               "--spp", str(a.spp), "--vpls", str(a.vpls), "--samplers", a.samplers,
               "--seed", str(seed), "--out", out]
        print(f"[{time.time() - t0:6.0f} s] {' '.join(cmd[1:])}", file=sys.stderr, flush=True)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        m = json.load(open(os.path.join(out, "metrics.json")))
        fl = m["floor"]
        moving = any(r["warped"]["frames"] for r in m["runs"])

        def figures(r):
            rel = r["metrics"]["mean_rel_mse"] - fl["rel_mse"]
            f1 = r["warped"]["f1"] if moving else r["metrics"]["flicker_f1"]
            ff = fl["warped_f1"] if moving else fl["flicker_f1"]
            return rel, math.sqrt(max(f1 * f1 - ff * ff, 0.0))

        by = {r["sampler"]: figures(r) for r in m["runs"]}
        cdf = by["cdf"]
        for s, (rel, f1) in by.items():
            rows.setdefault((scene, s), []).append(
                (rel / cdf[0] if cdf[0] > 0 else float("nan"),
                 f1 / cdf[1] if cdf[1] > 0 else float("nan"), rel, f1))


def mmm(xs):
    return f"{min(xs):.2f} / {statistics.median(xs):.2f} / {max(xs):.2f}"


lines = [
    f"Ratios to cdf, min / median / max over seeds {a.seeds}; 96x96, 24 frames, {a.vpls} VPLs, "
    f"{a.spp}-spp references, the reference's floor taken out. Flicker: warped F1 where the "
    f"camera or objects move, else F1.",
    "",
    "| scene | sampler | relMSE / cdf | flicker / cdf |",
    "| --- | --- | --- | --- |",
]
for scene in scenes:
    for s in samplers:
        v = rows.get((scene, s))
        if v:
            lines.append(f"| `{scene}` | {s} | {mmm([x[0] for x in v])} | {mmm([x[1] for x in v])} |")
lines.append("")
lines.append(f"({time.time() - t0:.0f} s)")
text = "\n".join(lines)
os.makedirs(a.out, exist_ok=True)
open(os.path.join(a.out, "summary.md"), "w").write(text + "\n")
print(text)
if a.page:
    def sh(*c):
        return subprocess.run(c, capture_output=True, text=True).stdout.strip()

    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    dirty = " + uncommitted changes" if sh("git", "status", "--porcelain", "src", "shaders", "scenes") else ""
    adapter = next((l for l in sh(a.irad, "info").splitlines() if "chosen" in l.lower() or "adapter" in l.lower()), "?")
    head = [
        "# Which sampler by default",
        "",
        "Written by `python3 benches/default_sampler.py`: do not edit by hand, run the script again.",
        "",
        f"- commit: `{sh('git', 'rev-parse', 'HEAD')}`{dirty}",
        f"- machine: {cpu}, {os.cpu_count()} cores; load average {open('/proc/loadavg').read().split()[0]} at the end",
        f"- adapter: {adapter}",
        "",
        "",
    ]
    open(a.page, "w").write("\n".join(head) + text + "\n")
