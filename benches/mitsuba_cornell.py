#!/usr/bin/env python3
"""Mitsuba 3's Cornell box on this machine: seconds and relMSE at several sample counts.

The baseline of issue 9's speed comparison (see speed_vs_mitsuba.py, which uses this file's
CSV). It renders `mitsuba.cornell_box()` (the scene irad's built-in `cornell` copies:
src/scene/builtin.rs, checked by tests/scenes.rs `cornell_is_mitsubas_box`) with the
`llvm_ad_rgb` variant (Dr.Jit's LLVM JIT on the CPU, all cores), the default `path`
integrator of that dictionary (max_depth 8), and a box reconstruction filter, so that a
pixel is the plain mean of the radiance over its area, as irad's reference defines it.

For each sample count it does one timed render per repeat (with distinct seeds), after a
warm-up render that JIT-compiles the kernels; the time is `mi.render` up to the image
being in a numpy array (Dr.Jit evaluates lazily: converting forces the work), so scene
loading and compilation are left out. relMSE is the mean over the repeats of

    mean over pixels and channels of (I - R)^2 / (R^2 + 0.01)

which is the formula of irad's `metrics::frame_error` (src/metrics/mod.rs), written again
here with numpy. R is Mitsuba's own image at --ref-spp samples (default 2048, as irad's
reference in the comparison), rendered once in passes of 256 samples with seeds unused by
the timed renders, and cached in the output folder. Its noise adds about c/ref_spp to
every measured relMSE (c = relMSE x spp of the test renders), as the 2048-spp reference
does to irad's.

With --irad-ref DIR (a folder from `irad reference cornell --spp N --out DIR`), the CSV
also gets each render's relMSE against irad's frame 0: a check that both programs draw
the same box (what is left at high spp is the bias between the two renderers).

Needs (nothing is installed by this script):
    pip install mitsuba numpy           # Mitsuba 3.9.1 / Dr.Jit 1.5.0 were used
    apt-get install -y libllvm19        # Dr.Jit's LLVM backend
    export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
                                        # (dpkg -L libllvm19 | grep so; found there if unset)

Writes OUT/mitsuba_cornell.csv (spp, seconds, rel_mse, ...), OUT/reference_<N>spp.exr and
OUT/spp_<N>.exr (the first repeat of each sample count). Usage:

    python3 benches/mitsuba_cornell.py [--spp 4,8,...,512] [--repeat 3] [--out out/bench/mitsuba]
"""

import argparse
import csv
import glob
import json
import os
import statistics
import sys
import time

DEFAULT_SPP = [4, 8, 16, 32, 64, 128, 256, 512]
REF_PASS_SPP = 256
REF_SEED_BASE = 1_000_000

INSTALL_HELP = """\
Mitsuba 3 with its LLVM backend is needed for this benchmark (nothing is installed for you):
    pip install mitsuba numpy             # into a venv if the system pip refuses
    apt-get install -y libllvm19          # Debian 12: bookworm's libllvm19 package
    export DRJIT_LIBLLVM_PATH=$(dpkg -L libllvm19 | grep 'libLLVM-19.so$')
then run this script again."""


def die(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(1)


def import_numpy():
    try:
        import numpy as np
    except ImportError:
        die("numpy is missing.\n" + INSTALL_HELP)
    return np


def load_mitsuba():
    """Imports Mitsuba and selects llvm_ad_rgb, or exits with instructions."""
    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        found = sorted(glob.glob("/usr/lib/*/libLLVM-19.so")) + sorted(
            glob.glob("/usr/lib/llvm-19/lib/libLLVM*.so*")
        )
        if found:
            os.environ["DRJIT_LIBLLVM_PATH"] = found[0]
    elif not os.path.exists(os.environ["DRJIT_LIBLLVM_PATH"]):
        die(f"DRJIT_LIBLLVM_PATH={os.environ['DRJIT_LIBLLVM_PATH']}: no such file.\n" + INSTALL_HELP)
    try:
        import mitsuba as mi
    except ImportError as e:
        die(f"cannot import mitsuba ({e}).\n" + INSTALL_HELP)
    try:
        mi.set_variant("llvm_ad_rgb")
    except (ImportError, AttributeError, RuntimeError) as e:
        die(f"Mitsuba's llvm_ad_rgb variant does not start ({e}).\n" + INSTALL_HELP)
    return mi


def rel_mse(test, ref):
    """irad's relMSE (src/metrics/mod.rs frame_error), in numpy: mean of (I-R)^2/(R^2+0.01)."""
    np = import_numpy()
    t = np.asarray(test, dtype=np.float64)[..., :3]
    r = np.asarray(ref, dtype=np.float64)[..., :3]
    if t.shape != r.shape:
        die(f"image sizes differ: {t.shape[1]}x{t.shape[0]} against {r.shape[1]}x{r.shape[0]}")
    return float(np.mean((t - r) ** 2 / (r * r + 0.01)))


def read_exr(mi, path):
    np = import_numpy()
    try:
        return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB,
                                                 mi.Struct.Type.Float32, False))
    except Exception as e:  # noqa: BLE001 - Mitsuba raises RuntimeError and others
        die(f"{path}: cannot read as EXR ({e})")


def write_exr(mi, path, arr):
    np = import_numpy()
    mi.Bitmap(np.ascontiguousarray(arr, dtype=np.float32)).write(path)


def cornell_scene(mi, size):
    d = mi.cornell_box()
    film = d["sensor"]["film"]
    film["width"] = size
    film["height"] = size
    film["rfilter"] = {"type": "box"}
    return mi.load_dict(d)


def render(mi, scene, spp, seed):
    """One render; returns (seconds, image as numpy array)."""
    np = import_numpy()
    t = time.perf_counter()
    img = np.array(mi.render(scene, spp=spp, seed=seed))
    return time.perf_counter() - t, img


def reference(mi, scene, size, spp, out):
    """Mitsuba's own high-spp image, cached as OUT/reference_<spp>spp.exr."""
    np = import_numpy()
    path = os.path.join(out, f"reference_{spp}spp.exr")
    meta_path = path + ".json"
    meta = {"size": size, "spp": spp, "mitsuba": mi.__version__, "variant": mi.variant()}
    if os.path.exists(path) and os.path.exists(meta_path):
        with open(meta_path) as f:
            if json.load(f) == meta:
                print(f"reference: cached {path}")
                return read_exr(mi, path)
    passes = max(1, -(-spp // REF_PASS_SPP))
    acc, total, t0 = None, 0, time.perf_counter()
    for i in range(passes):
        n = min(REF_PASS_SPP, spp - total)
        _, img = render(mi, scene, n, REF_SEED_BASE + i)
        acc = img * n if acc is None else acc + img * n
        total += n
        print(f"reference: {total}/{spp} spp, {time.perf_counter() - t0:.1f} s", flush=True)
    ref = acc / total
    write_exr(mi, path, ref)
    with open(meta_path, "w") as f:
        json.dump(meta, f)
    return ref


def parse_list(s, name):
    try:
        v = [int(x) for x in s.split(",") if x.strip()]
    except ValueError:
        die(f"--{name} '{s}': expected comma-separated positive integers")
    if not v or min(v) <= 0:
        die(f"--{name} '{s}': expected comma-separated positive integers")
    return v


def run(spp_list, repeat=3, size=256, ref_spp=2048, out="out/bench/mitsuba", irad_ref=None):
    """Runs the benchmark; returns rows (dicts) and writes OUT/mitsuba_cornell.csv."""
    np = import_numpy()
    mi = load_mitsuba()
    import drjit as dr

    os.makedirs(out, exist_ok=True)
    scene = cornell_scene(mi, size)
    print(f"Mitsuba {mi.__version__} (Dr.Jit {dr.__version__}), variant {mi.variant()}, "
          f"{dr.thread_count()} threads, LLVM {os.environ.get('DRJIT_LIBLLVM_PATH', '(default search)')}")
    print(f"scene mitsuba.cornell_box() at {size}x{size}, box filter, path max_depth 8")
    iref = None
    if irad_ref:
        p = os.path.join(irad_ref, "frame_0000.exr")
        if not os.path.exists(p):
            die(f"--irad-ref {irad_ref}: no frame_0000.exr (make it with `irad reference cornell "
                f"--size {size}x{size} --spp 2048 --out {irad_ref}`)")
        iref = read_exr(mi, p)
    # Warm-up: JIT-compiles the render kernels (Dr.Jit also caches them on disk).
    t, _ = render(mi, scene, min(spp_list), 7)
    print(f"warm-up render ({min(spp_list)} spp): {t:.2f} s")
    ref = reference(mi, scene, size, ref_spp, out)
    print(f"reference mean RGB {np.round(ref.reshape(-1, 3).mean(0), 4).tolist()}")
    if iref is not None:
        print(f"irad reference ({irad_ref}) mean RGB {np.round(iref.reshape(-1, 3).mean(0), 4).tolist()}, "
              f"relMSE of Mitsuba's reference against it {rel_mse(ref, iref):.5f}")
    rows = []
    path = os.path.join(out, "mitsuba_cornell.csv")
    print(f"{'spp':>6} {'s min':>8} {'s median':>9} {'s max':>8} {'relMSE':>9} {'relMSE x s':>11} {'load':>5}"
          + ("  relMSE vs irad ref" if iref is not None else ""))
    for spp in spp_list:
        secs, errs, ierrs = [], [], []
        for r in range(repeat):
            s, img = render(mi, scene, spp, 1000 * spp + r)
            secs.append(s)
            errs.append(rel_mse(img, ref))
            if iref is not None:
                ierrs.append(rel_mse(img, iref))
            if r == 0:
                write_exr(mi, os.path.join(out, f"spp_{spp}.exr"), img)
        row = {
            "spp": spp,
            "size": size,
            "seconds": statistics.median(secs),
            "rel_mse": statistics.mean(errs),
            "seconds_min": min(secs),
            "seconds_max": max(secs),
            "rel_mse_min": min(errs),
            "rel_mse_max": max(errs),
            "repeats": repeat,
            "load_1min": os.getloadavg()[0],
        }
        if iref is not None:
            row["rel_mse_vs_irad_ref"] = statistics.mean(ierrs)
        rows.append(row)
        print(f"{spp:>6} {min(secs):>8.3f} {row['seconds']:>9.3f} {max(secs):>8.3f} "
              f"{row['rel_mse']:>9.5f} {row['rel_mse'] * row['seconds']:>11.5f} {row['load_1min']:>5.1f}"
              + (f"  {row['rel_mse_vs_irad_ref']:.5f}" if iref is not None else ""), flush=True)
        write_csv(path, rows)
    print(f"wrote {path}")
    return rows


def write_csv(path, rows):
    """Writes the rows so far (after each sample count: an interrupted run keeps them)."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        for row in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})


def read_csv(path):
    """Rows of a CSV written by run(), as dicts of numbers."""
    try:
        with open(path, newline="") as f:
            rows = [{k: float(v) for k, v in row.items() if v != ""} for row in csv.DictReader(f)]
    except (OSError, ValueError) as e:
        die(f"{path}: cannot read Mitsuba's CSV ({e})")
    if not rows or any(k not in rows[0] for k in ("spp", "seconds", "rel_mse")):
        die(f"{path}: expected columns spp, seconds, rel_mse")
    return rows


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--spp", default=",".join(map(str, DEFAULT_SPP)),
                   help="sample counts to time (default %(default)s)")
    p.add_argument("--repeat", type=int, default=3, help="timed renders per sample count")
    p.add_argument("--size", type=int, default=256, help="image side in pixels")
    p.add_argument("--ref-spp", type=int, default=2048, help="samples of Mitsuba's reference")
    p.add_argument("--out", default="out/bench/mitsuba", help="output folder")
    p.add_argument("--irad-ref", help="folder of `irad reference cornell` (frame_0000.exr) to compare with")
    a = p.parse_args(argv)
    if a.repeat < 1 or a.size < 1 or a.ref_spp < 1:
        die("--repeat, --size and --ref-spp must be positive")
    run(parse_list(a.spp, "spp"), a.repeat, a.size, a.ref_spp, a.out, a.irad_ref)


if __name__ == "__main__":
    main()
