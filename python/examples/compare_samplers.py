"""CDF sampling against irad's coherent default sampler (mh) on a built-in animation: error
and flicker of each against irad's path-traced reference, per frame, plotted with matplotlib.

    python python/examples/compare_samplers.py [--scene cornell-orbit] [--frames 0..48]
        [--size 128x128] [--vpls 128] [--spp 64] [--out compare_samplers.png]

IRAD_EXAMPLE_TINY=1 runs it at a size that only shows it works (the tests use it).
"""

import argparse
import os
import time

import matplotlib

matplotlib.use("Agg")  # no display needed: the figure goes to a file
import matplotlib.pyplot as plt

import irad

TINY = bool(os.environ.get("IRAD_EXAMPLE_TINY"))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="cornell-orbit")
    p.add_argument("--frames", default="0..6" if TINY else "0..48")
    p.add_argument("--size", default="16x16" if TINY else "128x128")
    p.add_argument("--vpls", type=int, default=16 if TINY else 128)
    p.add_argument("--spp", type=int, default=4 if TINY else 64)
    p.add_argument("--out", default="compare_samplers.png")
    a = p.parse_args()

    scene = irad.Scene.load(a.scene)
    t = time.time()
    reference = irad.reference(scene, frames=a.frames, spp=a.spp, size=a.size)
    numbers = [f.index for f in reference]
    truth = [f.image for f in reference]
    print(f"reference: {len(truth)} frames at {a.spp} spp in {time.time() - t:.1f} s")

    fig, (flicker_ax, error_ax) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for sampler in ["cdf", "mh"]:
        t = time.time()
        frames = irad.render(scene, frames=a.frames, sampler=sampler, vpls=a.vpls, size=a.size)
        seconds = time.time() - t
        images = [f.image for f in frames]
        m = irad.metrics.sequence(images, truth, frames=numbers)
        w = irad.metrics.warped(images, truth, scene, frames=numbers)
        print(
            f"{sampler:4} {seconds / len(frames):6.3f} s/frame  relMSE {m['mean_rel_mse']:.4f}  "
            f"flicker F1 {m['flicker_f1']:.5f}  warped F1 {w['f1']:.5f}"
        )
        per_frame = m["frames"]
        flicker_ax.plot(numbers[1:], [f["flicker"] for f in per_frame[1:]], label=sampler)
        error_ax.plot(numbers, [f["rel_mse"] for f in per_frame], label=sampler)
    flicker_ax.set_ylabel("flicker |e_t - e_(t-1)|")
    error_ax.set_ylabel("relMSE")
    error_ax.set_xlabel("frame")
    flicker_ax.set_title(f"{a.scene}, {a.vpls} VPLs, {a.size}, reference {a.spp} spp")
    flicker_ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
