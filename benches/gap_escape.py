"""How many bounces light takes to leave a gap between two parallel white surfaces (issue 23
item 1; docs/math.md, "Light that cannot get out"), for the lamp of tests/gpu/thin_gap.rs: a
50 x 40 cm top face `gap` under an albedo-1 ceiling. Nothing in the gap absorbs, so all of the
light the top face sends into it leaves through its mouth; the question is when.

A model, not irad: walkers start uniformly on the top face and bounce between the two planes
with cosine-distributed directions; between two bounces a walker moves gap * tan(theta)
sideways in a uniform azimuth (a Levy flight: P(step > s) = gap^2 / (gap^2 + s^2)). A walker
has left when it is outside the face. Writes docs/results/gap_escape.md.

    python3 benches/gap_escape.py [--page docs/results/gap_escape.md] [--seed 1]
"""
import argparse
import os
import subprocess

import numpy as np

HALF = (0.25, 0.2)  # the lamp's top face: 50 x 40 cm
CASES = [(0.01, 20000, 100_000), (0.001, 4000, 400_000), (0.0001, 400, 5_000_000)]


def escape_bounces(gap, walkers, cap, rng):
    """Bounces each walker takes to leave (-1: not within `cap`)."""
    x = rng.uniform(-HALF[0], HALF[0], walkers)
    z = rng.uniform(-HALF[1], HALF[1], walkers)
    out = np.full(walkers, -1, dtype=np.int64)
    alive = np.arange(walkers)
    for b in range(1, cap + 1):
        if alive.size == 0:
            break
        u = rng.random(alive.size)
        phi = rng.random(alive.size) * 2 * np.pi
        s = gap * np.sqrt(u / (1 - u))  # cosine-distributed: sin^2(theta) = u
        x[alive] += s * np.cos(phi)
        z[alive] += s * np.sin(phi)
        gone = (np.abs(x[alive]) > HALF[0]) | (np.abs(z[alive]) > HALF[1])
        out[alive[gone]] = b
        alive = alive[~gone]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--page", default="docs/results/gap_escape.md", help="'' to print only")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    rows = []
    for gap, walkers, cap in CASES:
        b = escape_bounces(gap, walkers, cap, rng)
        left = b[b > 0]
        med = float(np.median(left))
        rows.append(
            f"| {gap * 1e3:g} mm | {walkers} | {left.size / walkers:.3f} | {med:.0f} | "
            f"{left.mean():.0f} | {np.percentile(left, 90):.0f} | "
            f"{(left <= 256).sum() / walkers:.3f} | {(left <= 1024).sum() / walkers:.3f} | "
            f"{0.95 ** max(med - 3, 0):.2g} |")
        print(rows[-1], flush=True)
    sh = lambda *c: subprocess.run(c, capture_output=True, text=True).stdout.strip()
    page = "\n".join([
        "# Bounces to leave a thin gap",
        "",
        "Written by `python3 benches/gap_escape.py`: do not edit by hand, run the script again.",
        "",
        f"- commit: `{sh('git', 'rev-parse', 'HEAD')}`; seed {a.seed}; a model of the gap, "
        "not irad (the script's docstring)",
        "",
        "The lamp of `tests/gpu/thin_gap.rs`: a 50 x 40 cm top face under an albedo-1 ceiling. "
        "Walkers start uniformly on the face; *left* is the share that left within the step "
        "limit; the bounce counts are over those. The last column is the chance that a path "
        "whose roulette is capped at 0.95 from bounce 3 (irad's reference by default, and "
        "Mitsuba 3's path tracer) is still alive after the median count: the weight it then "
        "carries is its inverse.",
        "",
        "| gap | walkers | left | bounces: median | mean | 90th percentile | "
        "left within 256 | within 1024 | 0.95^(median - 3) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        *rows,
        "",
    ])
    if a.page:
        os.makedirs(os.path.dirname(a.page), exist_ok=True)
        with open(a.page + ".tmp", "w") as f:
            f.write(page)
        os.replace(a.page + ".tmp", a.page)
        print("wrote", a.page)
    else:
        print(page)


if __name__ == "__main__":
    main()
