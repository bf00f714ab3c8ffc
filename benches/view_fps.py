#!/usr/bin/env python3
"""`irad view`'s frame rate and each pass's time, and the GTX 980 budget (issue 26, item 5).

Runs, from the repository root:

1. `irad bench SCENE --configs VPLS@WxH --repeat N`: the renderer's stages (CPU) and passes
   (GPU) at the size asked, without a window (mean of N frames after a warm-up);
2. `xvfb-run -a irad view SCENE --screenshot ... --after FRAMES` once for one view and once
   for `--split cdf,mh` (skipped with `--no-view`, or where xvfb-run is missing): the frame
   rate, the rendering's share and the stages' medians over the last 15 frames, as the view
   prints them. With `--size` given the view renders at it (`--fixed-size`), else at the size
   its rule picks from the measured frame time (`--refine-after 0`: not refined while still);
3. the GTX 980 estimate: the GPU passes' times scaled by the ratio of the measured adapter's
   peak to the GTX 980's (FP32 4.98 TFLOPS at boost clock, 224 GB/s), the larger of the two
   ratios (the pessimistic one), plus the CPU stages unscaled; against 60 fps (16.7 ms).
   Peaks of a few adapters are below; others take `--tflops T --gbps B`. A software adapter
   (llvmpipe, lavapipe) gets no estimate: its passes run on the CPU.

    python3 benches/view_fps.py --size 1920x1080            # on a GPU machine
    python3 benches/view_fps.py --bench-size 256x256        # here (llvmpipe): the size it picks

The binary is target/release/irad unless --irad or $IRAD says otherwise.
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys

# FP32 TFLOPS (non-tensor, boost) and memory GB/s, from the vendors' data sheets.
PEAKS = {
    "GTX 980": (4.98, 224.0),
    "H200": (67.0, 4800.0),
    "H100": (67.0, 3350.0),
    "A100": (19.5, 2039.0),
    "L40S": (91.6, 864.0),
    "RTX 4090": (82.6, 1008.0),
    "RTX 3090": (35.6, 936.0),
    "GTX 1080": (8.9, 320.0),
}
GTX980 = PEAKS["GTX 980"]
# Stages that run on the CPU (frame.rs, gpu/renderer: `upload` is the CPU's writes).
CPU_STAGES = {
    "scene", "bvh", "importance", "vpls", "light_samples", "ism_near", "gradient", "upload",
    "emitter_edges", "compensation", "radiosity_solve",
}


def run(cmd, **kw):
    print("$", " ".join(cmd), flush=True)
    return subprocess.run(cmd, capture_output=True, text=True, **kw)


def bench(irad, scene, vpls, size, repeat, out):
    p = run([irad, "bench", scene, "--configs", f"{vpls}@{size}", "--repeat", str(repeat),
             "--out", out])
    if p.returncode != 0:
        sys.exit(f"irad bench failed:\n{p.stderr}")
    with open(os.path.join(out, "bench.json")) as f:
        b = json.load(f)
    row = b["rows"][0]
    ad = b["adapter"]
    return ad, row["seconds_per_frame"], [(n, t) for n, t in row["stages"]]


def view(irad, scene, vpls, size, frames, split, out):
    shot = os.path.join(out, f"view{'_split' if split else ''}.png")
    cmd = ["xvfb-run", "-a", "-s", "-screen 0 2000x1300x24", irad, "view", scene,
           "--vpls", str(vpls), "--after", str(frames), "--screenshot", shot,
           "--refine-after", "0"]
    if size:
        w, h = size.split("x")
        cmd += ["--size", size, "--fixed-size", "--window", f"{int(w) + 360}x{int(h) + 240}"]
    if split:
        cmd += ["--split", "cdf,mh"]
    p = run(cmd, env={k: v for k, v in os.environ.items() if k != "WAYLAND_DISPLAY"})
    text = p.stdout + p.stderr
    m = re.search(r"render size (\d+x\d+): ([\d.]+) fps, (\d+) ms a frame of which (\d+) ms", text)
    s = re.search(r"stages, median of the last (\d+) frames.*?\(ms\): (.*)", text)
    if p.returncode != 0 or not m:
        print(f"  the view did not run ({p.returncode}):\n{text.strip()[-800:]}")
        return None
    stages = []
    if s:
        for part in s.group(2).split(", "):
            n, t = part.rsplit(" ", 1)
            stages.append((n, float(t) / 1e3))
    return {"size": m.group(1), "fps": float(m.group(2)), "frame_ms": int(m.group(3)),
            "render_ms": int(m.group(4)), "stages": stages, "shot": shot}


def peaks(adapter, tflops, gbps):
    if tflops and gbps:
        return tflops, gbps
    for name, p in PEAKS.items():
        if name.lower() in adapter.lower() and name != "GTX 980":
            return p
    return None


def estimate(stages, peak):
    ratio = max(peak[0] / GTX980[0], peak[1] / GTX980[1])
    cpu = sum(t for n, t in stages if n in CPU_STAGES)
    gpu = sum(t for n, t in stages if n not in CPU_STAGES)
    return ratio, cpu, gpu, cpu + gpu * ratio


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--irad", default=os.environ.get("IRAD", "target/release/irad"))
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--vpls", type=int, default=256)
    ap.add_argument("--size", help="the view's render size WxH (default: the size it picks)")
    ap.add_argument("--bench-size", help="irad bench's size (default: --size, else 1920x1080)")
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--frames", type=int, default=60, help="frames the view renders")
    ap.add_argument("--tflops", type=float)
    ap.add_argument("--gbps", type=float)
    ap.add_argument("--no-view", action="store_true")
    ap.add_argument("--out", default="out/bench/view_fps")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    bsize = a.bench_size or a.size or "1920x1080"
    adapter, spf, stages = bench(a.irad, a.scene, a.vpls, bsize, a.repeat,
                                 os.path.join(a.out, "bench"))
    print(f"\nadapter: {adapter['name']} ({adapter['backend']}, {adapter['device_type']})")
    print(f"irad bench {a.scene} {a.vpls}@{bsize}: {spf * 1e3:.1f} ms a frame ({1 / spf:.1f} fps)")
    software = adapter["device_type"] == "Cpu"
    peak = None if software else peaks(adapter["name"], a.tflops, a.gbps)
    print(f"{'stage':16} {'ms':>9}" + ("   GTX 980 est. ms" if peak else ""))
    for n, t in stages:
        scale = 1.0 if (n in CPU_STAGES or not peak) else estimate([(n, t)], peak)[0]
        est = f"   {t * scale * 1e3:9.2f}" if peak else ""
        print(f"{n:16} {t * 1e3:9.2f}{est}{'  (CPU)' if n in CPU_STAGES else ''}")
    if peak:
        ratio, cpu, gpu, est = estimate(stages, peak)
        verdict = "within" if est <= 1 / 60 else "over"
        print(f"\nGTX 980 estimate: CPU stages {cpu * 1e3:.2f} ms + GPU passes {gpu * 1e3:.2f} ms"
              f" x {ratio:.1f} (peak ratio: {peak[0]}/{GTX980[0]} TFLOPS,"
              f" {peak[1]}/{GTX980[1]} GB/s, the larger) = {est * 1e3:.1f} ms,"
              f" {verdict} the 60 fps budget (16.7 ms)")
    elif software:
        print("\nsoftware adapter: no GTX 980 estimate (its passes run on the CPU)")
    else:
        print("\nunknown adapter: give --tflops and --gbps for the GTX 980 estimate")
    if a.no_view or not shutil.which("xvfb-run"):
        return
    for split in (False, True):
        v = view(a.irad, a.scene, a.vpls, a.size, a.frames, split, a.out)
        if not v:
            continue
        label = "split cdf,mh" if split else "one view"
        print(f"\nirad view ({label}) at {v['size']}: {v['fps']:.1f} fps, {v['frame_ms']} ms a frame,"
              f" of which {v['render_ms']} ms rendering; screenshot {v['shot']}")
        print("  stages (median, ms): " + ", ".join(f"{n} {t * 1e3:.2f}" for n, t in v["stages"]))


if __name__ == "__main__":
    main()
