#!/usr/bin/env python3
"""The thin-gap sweep's box below 1 mm: irad's reference against Mitsuba 3.

Issue 23 item 1's closed gaps checked against an independent renderer. The box is the one of
tests/gpu/thin_gap.rs `cornell_with_gap` (a 2 m room of 2 cm thick walls, white of albedo 1,
the lamp a closed 50 x 6 x 40 cm cube of radiance 10 whose top lies `gap` under the
ceiling, every material double-sided), written here as a glTF file for `irad reference` and
as Mitsuba `cube` shapes with `twosided` `diffuse` BSDFs and an `area` emitter on the lamp
(the `path` integrator without a depth limit, a box filter: a pixel is the mean radiance over
its area, as irad's reference defines it). Both renderers close a gap thinner than their
resolution: Mitsuba by its ray offset, $(1 + |p|_\\infty) \\cdot 1500 \\cdot 2^{-24}$, 0.18 mm at
this ceiling; irad by its seal, 1e-4 of the scene's size, 0.2 mm (docs/math.md, "Gaps
thinner than the scene resolves"). Over the 1 mm gap neither path tracer's default roulette
converges (the gap's light needs thousands of bounces), so the sweep stops below it. For each
gap it prints both means, the relative bias of irad's mean and the relMSE of irad's image
against Mitsuba's (irad's `metrics::frame_error` formula, mean of (I-R)^2/(R^2+0.01)).

Needs (nothing is installed by this script), as benches/mitsuba_cornell.py:
    pip install mitsuba numpy openexr   # Mitsuba 3.9.1 / Dr.Jit 1.5.0 were used
    libLLVM-19 for Dr.Jit's llvm_ad_rgb # DRJIT_LIBLLVM_PATH or /usr/lib/*/libLLVM-19.so
    cargo build --release               # target/release/irad, or --irad PATH

Usage:
    python3 benches/thin_gap_vs_mitsuba.py [--size 32] [--spp 16384] [--mitsuba-spp 32768]
        [--irad target/release/irad] [--out out/bench/thin_gap_vs_mitsuba]
"""

import argparse
import base64
import glob
import json
import math
import os
import struct
import subprocess

import numpy as np

T = 0.02
WHITE, RED, GREEN = [1.0, 1.0, 1.0], [0.57, 0.043, 0.044], [0.105, 0.378, 0.076]


def boxes(gap):
    """(name, lo, hi, material index) of the box with the lamp's top `gap` under the ceiling."""
    t = T
    return [
        ("floor", [-1 - t, -1 - t, -1 - t], [1 + t, -1, 1], 0),
        ("ceiling", [-1 - t, 1, -1 - t], [1 + t, 1 + t, 1], 0),
        ("back", [-1 - t, -1, -1 - t], [1 + t, 1, -1], 0),
        ("left", [-1 - t, -1, -1], [-1, 1, 1], 1),
        ("right", [1, -1, -1], [1 + t, 1, 1], 2),
        ("light", [-0.25, 0.94 - gap, -0.2], [0.25, 1 - gap, 0.2], 3),
        ("box", [-0.3, -1, -0.3], [0.3, -0.2, 0.3], 0),
    ]


def gltf(gap):
    """The box as glTF, as tests/gpu/thin_gap.rs writes it (faces outward, double-sided)."""
    data, views, accessors, meshes, nodes = bytearray(), [], [], [], []

    def accessor(b, count, ty, comp):
        while len(data) % 4:
            data.append(0)
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(b)})
        data.extend(b)
        accessors.append({"bufferView": len(views) - 1, "count": count, "type": ty, "componentType": comp})
        return len(accessors) - 1

    for name, (x0, y0, z0), (x1, y1, z1), m in boxes(gap):
        faces = [
            [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]],
            [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],
            [[x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]],
            [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
            [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
            [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]],
        ]
        p = [c for f in faces for v in f for c in v]
        i = [4 * f + k for f in range(6) for k in [0, 1, 2, 0, 2, 3]]
        pa = accessor(struct.pack("<%df" % len(p), *p), 24, "VEC3", 5126)
        accessors[pa]["min"], accessors[pa]["max"] = [x0, y0, z0], [x1, y1, z1]
        ia = accessor(struct.pack("<%dI" % len(i), *i), 36, "SCALAR", 5125)
        meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pa}, "indices": ia, "material": m}]})
        nodes.append({"name": name, "mesh": len(meshes) - 1})
    nodes.append({"name": "camera", "camera": 0, "translation": [0, 0, 3.9]})

    def mat(name, rgb, emit=False):
        m = {"name": name, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorFactor": rgb + [1.0], "metallicFactor": 0.0}}
        if emit:
            m["emissiveFactor"] = [1, 1, 1]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}}
        return m

    return {
        "asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_emissive_strength"], "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
        "materials": [mat("white", WHITE), mat("red", RED), mat("green", GREEN), mat("light", WHITE, True)],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(39.3), "znear": 0.1}}],
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(data)).decode()}],
    }


def mitsuba(gap, size, spp):
    """Mitsuba 3's image of the box (rows top to bottom, linear RGB)."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        found = glob.glob("/usr/lib/*/libLLVM-19.so") + glob.glob("/usr/lib/*/libLLVM.so.19*")
        if found:
            os.environ["DRJIT_LIBLLVM_PATH"] = found[0]
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    tf = mi.ScalarTransform4f

    def bsdf(rgb):
        return {"type": "twosided", "material": {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}}

    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {
            "type": "perspective", "fov": 39.3, "fov_axis": "y",
            "to_world": tf().look_at(origin=[0, 0, 3.9], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": 1024},
        },
    }
    for name, lo, hi, m in boxes(gap):
        lo, hi = np.array(lo, float), np.array(hi, float)
        shape = {"type": "cube", "to_world": tf().translate(((lo + hi) / 2).tolist()) @ tf().scale(((hi - lo) / 2).tolist()),
                 "bsdf": bsdf([WHITE, RED, GREEN, WHITE][m])}
        if name == "light":
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [10.0, 10.0, 10.0]}}
        scene[name] = shape
    s = mi.load_dict(scene)
    passes = max(1, spp // 1024)
    return sum(np.array(mi.render(s, spp=1024, seed=k), dtype=np.float64) for k in range(passes)) / passes


def read_exr(path):
    import OpenEXR

    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, dtype=np.float64)
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], -1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=32)
    ap.add_argument("--spp", type=int, default=16384, help="irad's samples a pixel")
    ap.add_argument("--mitsuba-spp", type=int, default=32768)
    ap.add_argument("--irad", default="target/release/irad")
    ap.add_argument("--out", default="out/bench/thin_gap_vs_mitsuba")
    ap.add_argument("--gaps", default="0.0001,0.00001,0", help="gaps in metres, comma-separated")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    print("| gap | irad mean | Mitsuba mean | bias | relMSE |")
    print("| --- | --- | --- | --- | --- |")
    for gap in [float(g) for g in a.gaps.split(",")]:
        tag = f"{gap * 1e3:g}mm"
        scene = os.path.join(a.out, f"gap-{tag}.gltf")
        with open(scene, "w") as f:
            json.dump(gltf(gap), f)
        ref = os.path.join(a.out, f"irad-{tag}")
        subprocess.run([a.irad, "reference", scene, "--size", f"{a.size}x{a.size}", "--spp", str(a.spp),
                        "--seed", "1", "--out", ref, "--overwrite"], check=True, capture_output=True)
        i = read_exr(os.path.join(ref, "frame_0000.exr"))
        m = mitsuba(gap, a.size, a.mitsuba_spp)
        np.save(os.path.join(a.out, f"mitsuba-{tag}.npy"), m)
        rel = float(np.mean((i - m) ** 2 / (m * m + 0.01)))
        print(f"| {tag} | {i.mean():.4f} | {m.mean():.4f} | {100 * (i.mean() / m.mean() - 1):+.2f}% | {rel:.4f} |")


if __name__ == "__main__":
    main()
