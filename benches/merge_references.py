#!/usr/bin/env python3
"""A reference of more samples from cached ones: averages the `irad compare` reference cache
entries of several seeds into one entry of their summed samples, for each of those seeds.

Where a run's own warped flicker is a few percent of the reference's noise floor (the
classical methods on `cornell-orbit`: warped F1 0.00106 against a floor of 0.00101 at 2048
spp), sqrt(F1^2 - floor^2) is the difference of two nearly equal numbers, and it scattered
0.13-0.22x of cdf's over four seeds for a view-independent solution. Four 2048-spp references
of the same frames (seeds 1-4, independent paths) average to one of 8192 spp, whose floor is
half as high.

    python3 benches/merge_references.py cornell-orbit_085a53651ac1b0ae_96x96_2048spp_24fps \\
        [--seeds 1,2,3,4] [--cache out/cache/reference]

takes CACHE/PREFIX_seed{S}_halves{A}+{B} for each seed S (each with its halves in a/ and b/,
the same frames and sample counts) and writes CACHE/PREFIX'_seed{S}_halves{H}+{H} for each S,
PREFIX' being PREFIX with the summed samples (8192spp above) and H half of them: half a is
the mean of the first half of the seeds' images (both halves of each), half b that of the
rest. `irad compare ... --spp 8192 --seed S` then finds it (its folder name is the one
`compare` looks for). Needs the Python package (`pip install ./python`) and an even number of
seeds. An existing output folder is refused unless --overwrite.
"""
import argparse
import os
import re
import shutil
import sys

import numpy as np


def die(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(1)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("prefix", help="cache folder name up to _seed, e.g. "
                   "cornell-orbit_085a53651ac1b0ae_96x96_2048spp_24fps")
    p.add_argument("--seeds", default="1,2,3,4")
    p.add_argument("--cache", default="out/cache/reference")
    p.add_argument("--overwrite", action="store_true")
    a = p.parse_args()
    try:
        import irad
    except ImportError as e:
        die(f"the Python package is needed (pip install ./python): {e}")
    seeds = [int(s) for s in a.seeds.split(",") if s.strip()]
    if len(seeds) < 2 or len(seeds) % 2:
        die(f"--seeds {a.seeds}: need an even number of seeds, at least 2")
    m = re.fullmatch(r"(.+_)(\d+)spp(_.+)", a.prefix)
    if not m:
        die(f"{a.prefix}: expected a cache name prefix with <N>spp in it")
    spp = int(m.group(2))
    total = spp * len(seeds)
    sources = []
    for s in seeds:
        found = [d for d in sorted(os.listdir(a.cache))
                 if d.startswith(f"{a.prefix}_seed{s}_halves")] if os.path.isdir(a.cache) else []
        if len(found) != 1:
            die(f"{a.cache}: expected one folder {a.prefix}_seed{s}_halves*, found {found or 'none'}")
        h = re.fullmatch(r".*_halves(\d+)\+(\d+)", found[0])
        if not h or h.group(1) != h.group(2) or int(h.group(1)) * 2 != spp:
            die(f"{found[0]}: expected two halves of {spp // 2} samples")
        sources.append(os.path.join(a.cache, found[0]))
    frames = sorted(f for f in os.listdir(os.path.join(sources[0], "a")) if f.endswith(".exr"))
    if not frames:
        die(f"{sources[0]}/a: no frames")
    for src in sources:
        for h in "ab":
            have = sorted(f for f in os.listdir(os.path.join(src, h)) if f.endswith(".exr"))
            if have != frames:
                die(f"{src}/{h}: its frames differ from {sources[0]}/a's")
    name = f"{m.group(1)}{total}spp{m.group(3)}"
    groups = {"a": sources[: len(sources) // 2], "b": sources[len(sources) // 2:]}
    for s in seeds:
        out = os.path.join(a.cache, f"{name}_seed{s}_halves{total // 2}+{total // 2}")
        if os.path.exists(out):
            if not a.overwrite:
                die(f"{out} exists (--overwrite to replace it)")
            shutil.rmtree(out)
        # Written beside it and renamed when whole: a half-written entry is never found.
        tmp = out + ".partial"
        shutil.rmtree(tmp, ignore_errors=True)
        for h, srcs in groups.items():
            os.makedirs(os.path.join(tmp, h))
            for f in frames:
                imgs = [irad.read_image(os.path.join(src, x, f)) for src in srcs for x in "ab"]
                irad.write_exr(os.path.join(tmp, h, f), np.mean(imgs, axis=0).astype(np.float32))
        os.rename(tmp, out)
        print(f"wrote {out} ({len(frames)} frames, {total} spp from seeds {a.seeds})")


if __name__ == "__main__":
    main()
