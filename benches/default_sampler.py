#!/usr/bin/env python3
"""Which sampler and accumulation should `irad render` use by default? Runs `irad compare` on
the animated built-ins for several seeds, once per configuration (plain: every frame stands
alone; acc8: `--accumulate 8`, the history weighed by the light's gradient under a moving
light or object), and prints per scene, configuration and sampler the ratios of relMSE and
flicker to plain cdf's (each frame's VPLs drawn afresh by importance, no accumulation: the
classical VPL renderer), min / median / max over the seeds, with the reference's floor taken
out as docs/math.md ("The floor of the measurement") defines it: relMSE - floor, and
sqrt(F1^2 - floor^2) for the warped flicker F1 (the plain F1 where nothing moves).

    python3 benches/default_sampler.py [--irad PATH] [--seeds 1,2,3,4] [--spp 256]
        [--scenes cornell,cornell-light,cornell-box,cornell-orbit,two-rooms,atrium]
        [--configs plain,acc8,acc8-r05,acc8-r30] [--samplers cdf,mh,smc,frozen]
        [--acc-samplers cdf,mh]

Writes docs/results/default_sampler.md after every scene (stamped with the commit, the
machine and the adapter; `--page ''` to skip) and prints the table. 96x96, 24 frames, 256
VPLs as issue 25's table; the references are cached per scene and seed by `irad compare`.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.dont_write_bytecode = True  # no benches/__pycache__ in the work tree
import page_stamp  # noqa: E402

CONFIGS = {
    "plain": ["--accumulate", "0"],
    "acc8": ["--accumulate", "8", "--history", "gradient"],
    "acc8-keep": ["--accumulate", "8", "--history", "keep"],
    "acc8-drop": ["--accumulate", "8", "--history", "drop"],
    # mh's chains proposing at other rates where nothing moves (--mh-rate, default 0.15; 0.05
    # before: the 8 accumulated frames then held nearly one set of VPLs); mh only.
    "acc8-r05": ["--accumulate", "8", "--history", "gradient", "--mh-rate", "0.05"],
    "acc8-r30": ["--accumulate", "8", "--history", "gradient", "--mh-rate", "0.3"],
}
# The configurations that run mh alone (its own knob), whatever --acc-samplers says.
MH_ONLY = {"acc8-r05", "acc8-r30"}

p = argparse.ArgumentParser()
p.add_argument("--irad", default=os.environ.get("IRAD", "target/release/irad"))
p.add_argument("--seeds", default="1,2,3,4")
p.add_argument("--spp", type=int, default=256)
p.add_argument("--vpls", type=int, default=256)
p.add_argument("--samplers", default="cdf,mh,smc,frozen",
               help="the samplers of the plain configuration")
p.add_argument("--acc-samplers", default="cdf,mh",
               help="the samplers of the other configurations")
p.add_argument("--configs", default="plain,acc8,acc8-r05,acc8-r30")
p.add_argument("--scenes", default="cornell,cornell-light,cornell-box,cornell-orbit,two-rooms,atrium")
p.add_argument("--out", default="out/default_sampler")
p.add_argument("--page", default="docs/results/default_sampler.md")
a = p.parse_args()

seeds = [int(s) for s in a.seeds.split(",")]
scenes = a.scenes.split(",")
samplers = a.samplers.split(",")
acc_samplers = a.acc_samplers.split(",")
configs = a.configs.split(",")
assert "plain" in configs and "cdf" in samplers, "the ratios are to plain cdf's"
rows = {}  # (scene, config, sampler) -> list of (relmse ratio, flicker ratio)
t0 = time.time()


def mmm(xs):
    return f"{min(xs):.2f} / {statistics.median(xs):.2f} / {max(xs):.2f}"


def write(done):
    lines = [
        f"Ratios to plain cdf's (no accumulation), min / median / max over seeds "
        f"{','.join(map(str, seeds))}; 96x96, 24 frames, {a.vpls} VPLs, {a.spp}-spp references, "
        f"the reference's floor taken out. Flicker: warped F1 where the camera or objects move, "
        f"else F1. Configurations: "
        + "; ".join(f"{c}: `{' '.join(CONFIGS[c])}`" for c in configs) + ".",
        "",
        "| scene | configuration | sampler | relMSE / cdf | flicker / cdf |",
        "| --- | --- | --- | --- | --- |",
    ]
    for scene in done:
        for c in configs:
            for s in (samplers if c == "plain" else ["mh"] if c in MH_ONLY else acc_samplers):
                v = rows.get((scene, c, s))
                if v:
                    lines.append(f"| `{scene}` | {c} | {s} | {mmm([x[0] for x in v])} | "
                                 f"{mmm([x[1] for x in v])} |")
    lines += ["", f"({time.time() - t0:.0f} s)"]
    text = "\n".join(lines)
    os.makedirs(a.out, exist_ok=True)
    open(os.path.join(a.out, "summary.md"), "w").write(text + "\n")
    if a.page:
        head = page_stamp.head("Which sampler and accumulation by default",
                               "benches/default_sampler.py", a.irad)
        open(a.page, "w").write(head + text + "\n")
    return text


def figures(m, r):
    fl = m["floor"]
    moving = any(x["warped"]["frames"] for x in m["runs"])
    rel = r["metrics"]["mean_rel_mse"] - fl["rel_mse"]
    f1 = r["warped"]["f1"] if moving else r["metrics"]["flicker_f1"]
    ff = fl["warped_f1"] if moving else fl["flicker_f1"]
    return rel, math.sqrt(max(f1 * f1 - ff * ff, 0.0))


for i, scene in enumerate(scenes):
    for seed in seeds:
        by = {}
        for c in configs:
            out = os.path.join(a.out, f"{scene}-{seed}-{c}")
            these = a.samplers if c == "plain" else "mh" if c in MH_ONLY else a.acc_samplers
            cmd = [a.irad, "compare", scene, "--size", "96x96", "--frames", "0..24",
                   "--spp", str(a.spp), "--vpls", str(a.vpls), "--samplers", these,
                   "--seed", str(seed), "--out", out] + CONFIGS[c]
            print(f"[{time.time() - t0:6.0f} s] {' '.join(cmd[1:])}", file=sys.stderr, flush=True)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            m = json.load(open(os.path.join(out, "metrics.json")))
            for r in m["runs"]:
                by[(c, r["sampler"])] = figures(m, r)
        cdf = by[("plain", "cdf")]
        for (c, s), (rel, f1) in by.items():
            rows.setdefault((scene, c, s), []).append(
                (rel / cdf[0] if cdf[0] > 0 else float("nan"),
                 f1 / cdf[1] if cdf[1] > 0 else float("nan")))
    print(write(scenes[:i + 1]), flush=True)
