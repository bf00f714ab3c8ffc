#!/usr/bin/env python3
"""The first render a newcomer sees, frames 10-13, beside the reference's (issue 25 item 5).

    python3 benches/default_frames.py [--irad PATH] [--spp 1024] [--out out/default_frames]

Renders `irad render` with the default settings (cornell-orbit, 256x256, 256 VPLs, mh, 8
frames accumulated) from frame 0 to 14 (so frames 10-13 carry the history a newcomer's
frames carry), the path-traced reference of frames 10-13 (`irad reference --spp N`), and
writes docs/results/default_frames.png: the default's PNG previews in the top row, the
reference's below, frames 10 to 13 from left to right. Needs Pillow. The reference is traced again
only when OUT/reference holds no finished one at --spp (remove it after changing the path tracer).
"""
import argparse
import json
import os
import subprocess

from PIL import Image

p = argparse.ArgumentParser()
p.add_argument("--irad", default=os.environ.get("IRAD", "target/release/irad"))
p.add_argument("--spp", type=int, default=1024)
p.add_argument("--out", default="out/default_frames")
p.add_argument("--page", default="docs/results/default_frames.png")
a = p.parse_args()

render = os.path.join(a.out, "render")
reference = os.path.join(a.out, "reference")
subprocess.run([a.irad, "render", "--frames", "0..14", "--out", render], check=True)


def same_reference():
    """Whether `reference` already holds frames 10-13 at --spp (the reference does not change
    with the renderer's settings: it is traced again only when asked for another one)."""
    try:
        with open(os.path.join(reference, "run.json")) as f:
            r = json.load(f)
    except (OSError, ValueError):
        return False
    s = r.get("settings", {})
    return (r.get("scene") == "cornell-orbit" and s.get("spp") == a.spp
            and s.get("sequence", {}).get("frames") == {"start": 10, "end": 14}
            and not r.get("interrupted"))


if not same_reference():
    subprocess.run([a.irad, "reference", "cornell-orbit", "--frames", "10..14", "--spp",
                    str(a.spp), "--out", reference], check=True)


def frame(folder, f):
    names = sorted(n for n in os.listdir(folder) if n.endswith(".png") and f"{f:04}" in n)
    if not names:
        raise SystemExit(f"no PNG of frame {f} in {folder}")
    return Image.open(os.path.join(folder, names[0])).convert("RGB")


rows = [[frame(render, f) for f in range(10, 14)], [frame(reference, f) for f in range(10, 14)]]
w, h = rows[0][0].size
strip = Image.new("RGB", (4 * w + 3 * 4, 2 * h + 4), (255, 255, 255))
for j, row in enumerate(rows):
    for i, img in enumerate(row):
        strip.paste(img, (i * (w + 4), j * (h + 4)))
strip.save(a.page)
print(f"wrote {a.page}: default frames 10-13 (top) and the {a.spp}-spp reference (bottom)")
