#!/usr/bin/env python3
"""Issue 25, item 1: resample-move SMC (`rmsmc`) against cdf, mh, smc and frozen. Runs
benches/default_sampler.py (the same runs: 96x96, 24 frames, 256 VPLs, seeds 1-4, 256-spp
references cached by `irad compare`) with rmsmc among the samplers, plain (no accumulation) and
with `--accumulate 8 --history gradient` (the default's), and writes its table, ratios of relMSE
and flicker to plain cdf's, min / median / max over the seeds, to docs/results/rmsmc.md.

    python3 benches/rmsmc.py [--irad PATH] [--seeds 1,2,3,4] [--scenes ...]
        [--samplers cdf,mh,smc,rmsmc,frozen] [--acc-samplers cdf,mh,rmsmc]

"""
import argparse
import os
import subprocess
import sys
import time

p = argparse.ArgumentParser()
p.add_argument("--irad", default=os.environ.get("IRAD", "target/release/irad"))
p.add_argument("--seeds", default="1,2,3,4")
p.add_argument("--scenes", default="cornell,cornell-light,cornell-box,cornell-orbit,two-rooms")
p.add_argument("--samplers", default="cdf,mh,smc,rmsmc,frozen")
p.add_argument("--acc-samplers", default="cdf,mh,rmsmc")
p.add_argument("--configs", default="plain,acc8")
p.add_argument("--out", default="out/rmsmc")
p.add_argument("--page", default="docs/results/rmsmc.md")
a = p.parse_args()

here = os.path.dirname(os.path.abspath(__file__))
t0 = time.time()
cmd = [sys.executable, os.path.join(here, "default_sampler.py"), "--irad", a.irad,
       "--seeds", a.seeds, "--scenes", a.scenes, "--samplers", a.samplers,
       "--acc-samplers", a.acc_samplers, "--configs", a.configs, "--out", a.out, "--page", ""]
subprocess.run(cmd, check=True)
summary = open(os.path.join(a.out, "summary.md")).read()


def sh(*c):
    return subprocess.run(c, capture_output=True, text=True).stdout.strip()


if a.page:
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
                if l.startswith("model name")), "?")
    dirty = " + uncommitted changes" if sh("git", "status", "--porcelain", "src") else ""
    head = [
        "# Resample-move SMC (`rmsmc`) against the other samplers",
        "",
        "Written by `python3 benches/rmsmc.py`: do not edit by hand, run the script again.",
        "",
        f"- commit: `{sh('git', 'rev-parse', 'HEAD')}`{dirty}",
        f"- machine: {cpu}, {os.cpu_count()} cores; load average "
        f"{open('/proc/loadavg').read().split()[0]} at the end ({time.time() - t0:.0f} s)",
        f"- command: `python3 benches/rmsmc.py --seeds {a.seeds} --scenes {a.scenes} "
        f"--samplers {a.samplers} --acc-samplers {a.acc_samplers} --configs {a.configs}`",
        "",
        "",
    ]
    open(a.page, "w").write("\n".join(head) + summary)
print(summary)
