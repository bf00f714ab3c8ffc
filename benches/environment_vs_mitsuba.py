#!/usr/bin/env python3
"""A model without lights under the default sky: irad's reference against Mitsuba 3's `constant`.

Issue 23 item 4's check against an independent renderer. The model is the one of
tests/common/quads.rs `lightless_model` (a grey floor, a white cube, a taller dark box and a
leaning panel; no emitter, no punctual light), written here as a glTF file (every material
double-sided, so that the two renderers' one-sided conventions cannot differ) and handed to
`irad reference`, which lights it with its default environment: a uniform sky of radiance 1
(docs/math.md, "The environment"). Mitsuba renders the same triangles with `twosided`
`diffuse` BSDFs of the same albedos under a `constant` emitter of radiance 1, the `path`
integrator without a depth limit and a box filter (a pixel is the mean radiance over its
area, as irad's reference defines it). It prints both means, the relMSE of irad's image
against Mitsuba's (irad's `metrics::frame_error` formula, mean of (I-R)^2/(R^2+0.01)) and
the relative bias of the mean luminance, and writes both images.

Needs (nothing is installed by this script), as benches/mitsuba_cornell.py:
    pip install mitsuba numpy           # Mitsuba 3.9.1 / Dr.Jit 1.5.0 were used
    libLLVM-19 for Dr.Jit's llvm_ad_rgb # DRJIT_LIBLLVM_PATH or /usr/lib/*/libLLVM-19.so;
                                        # without it the scalar_rgb variant (slower) is used
    cargo build --release               # target/release/irad, or --irad PATH

Usage:
    python3 benches/environment_vs_mitsuba.py [--size 128] [--spp 1024] [--out out/bench/environment]
"""

import argparse
import base64
import glob
import json
import os
import struct
import subprocess
import sys

# (name, albedo, triangles as a flat list of corner triples): built by the functions below.
FLOOR, WHITE, DARK, PANEL = 0.6, 0.8, 0.4, 0.7
CAMERA = {"at": [0.0, 1.0, 4.0], "yfov": 0.8}  # looking down -z, as quads.rs' camera


def quad(c, u, v):
    """The quad c +- u +- v, front faces u x v, as quads.rs `quad` (two triangles)."""
    at = lambda a, b: [c[i] + a * u[i] + b * v[i] for i in range(3)]
    p = [at(-1, -1), at(1, -1), at(1, 1), at(-1, 1)]
    return [p[0], p[1], p[2], p[0], p[2], p[3]]


def cube(lo, hi):
    """A box from lo to hi, faces out, as quads.rs `cube`."""
    p = [[hi[a] if (k >> a) & 1 else lo[a] for a in range(3)] for k in range(8)]
    tris = []
    for f in [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]:
        tris += [p[f[0]], p[f[1]], p[f[2]], p[f[0]], p[f[2]], p[f[3]]]
    return tris


def model():
    """The objects of tests/common/quads.rs `lightless_model`: (name, albedo, corners)."""
    return [
        ("floor", FLOOR, quad([0, 0, 0], [0, 0, 2], [2, 0, 0])),
        ("white", WHITE, cube([-1.0, 0.0, -0.6], [-0.2, 0.8, 0.2])),
        ("dark", DARK, cube([0.3, 0.0, -1.2], [0.9, 1.6, -0.6])),
        ("panel", PANEL, quad([0.2, 1.2, -0.2], [0.6, 0.0, 0.0], [0.0, 0.3, -0.4])),
    ]


def write_gltf(path, objects):
    """The objects as a glTF 2.0 file (one mesh and material each, double-sided) with the
    camera; no light of any kind."""
    bin_, views, accessors, meshes, materials, nodes = b"", [], [], [], [], []
    for i, (name, albedo, corners) in enumerate(objects):
        flat = [x for p in corners for x in p]
        data = struct.pack(f"<{len(flat)}f", *flat)
        views.append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(data)})
        bin_ += data
        lo = [min(p[a] for p in corners) for a in range(3)]
        hi = [max(p[a] for p in corners) for a in range(3)]
        accessors.append({"bufferView": len(views) - 1, "count": len(corners), "type": "VEC3",
                          "componentType": 5126, "min": lo, "max": hi})
        materials.append({"name": name, "doubleSided": True, "pbrMetallicRoughness": {
            "baseColorFactor": [albedo, albedo, albedo, 1.0], "metallicFactor": 0.0}})
        meshes.append({"primitives": [{"attributes": {"POSITION": i}, "material": i}]})
        nodes.append({"name": name, "mesh": i})
    nodes.append({"camera": 0, "translation": CAMERA["at"]})
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {"yfov": CAMERA["yfov"], "znear": 0.001}}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(bin_), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(bin_).decode()}],
    }
    with open(path, "w") as f:
        json.dump(doc, f)


def die(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(1)


def load_mitsuba(variant):
    # Dr.Jit's LLVM backend with LLVM 19 (LLVM 15 fails in code generation here).
    llvm = os.environ.get("DRJIT_LIBLLVM_PATH") or next(
        iter(sorted(glob.glob("/usr/lib/*/libLLVM-19.so"))), None)
    if variant == "auto":
        variant = "llvm_ad_rgb" if llvm else "scalar_rgb"
    if variant.startswith("llvm") and llvm:
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm
    try:
        import mitsuba as mi
    except ImportError as e:
        die(f"cannot import mitsuba ({e}): pip install mitsuba numpy")
    try:
        mi.set_variant(variant)
    except (ImportError, AttributeError, RuntimeError) as e:
        die(f"Mitsuba's {variant} variant does not start ({e}); try --variant scalar_rgb")
    return mi


def write_ply(path, corners):
    """Triangles (three corners each, unshared) as a binary PLY file."""
    n = len(corners)
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {n // 3}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(head.encode())
        for p in corners:
            f.write(struct.pack("<3f", *p))
        for t in range(n // 3):
            f.write(struct.pack("<B3i", 3, 3 * t, 3 * t + 1, 3 * t + 2))


def mitsuba_scene(mi, objects, size, out):
    import numpy as np
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "sensor": {
            "type": "perspective",
            "fov": float(np.degrees(CAMERA["yfov"])),
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=CAMERA["at"], target=[CAMERA["at"][0], CAMERA["at"][1], CAMERA["at"][2] - 1],
                up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
        },
    }
    for name, albedo, corners in objects:
        path = os.path.join(out, f"{name}.ply")
        write_ply(path, corners)
        scene[name] = {"type": "ply", "filename": path, "face_normals": True, "bsdf": {
            "type": "twosided", "bsdf": {
                "type": "diffuse", "reflectance": {"type": "rgb", "value": albedo}}}}
    return mi.load_dict(scene)


def rel_mse(test, ref):
    import numpy as np
    t, r = np.asarray(test, np.float64)[..., :3], np.asarray(ref, np.float64)[..., :3]
    return float(np.mean((t - r) ** 2 / (r * r + 0.01)))


def lum(img):
    import numpy as np
    i = np.asarray(img, np.float64)[..., :3]
    return float((0.2126 * i[..., 0] + 0.7152 * i[..., 1] + 0.0722 * i[..., 2]).mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=1024, help="samples a pixel, both renderers")
    ap.add_argument("--out", default="out/bench/environment")
    ap.add_argument("--irad", default="target/release/irad")
    ap.add_argument("--variant", default="auto",
                    help="Mitsuba variant; auto: llvm_ad_rgb with libLLVM-19, else scalar_rgb")
    a = ap.parse_args()
    if a.size <= 0 or a.spp <= 0:
        die("--size and --spp must be positive")
    import numpy as np
    os.makedirs(a.out, exist_ok=True)
    objects = model()
    gltf = os.path.join(a.out, "lightless.gltf")
    write_gltf(gltf, objects)
    if not os.path.exists(a.irad):
        die(f"{a.irad}: no irad binary (cargo build --release, or --irad PATH)")
    ref_dir = os.path.join(a.out, "irad")
    cmd = [a.irad, "reference", gltf, "--size", f"{a.size}x{a.size}", "--spp", str(a.spp),
           "--out", ref_dir, "--overwrite"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        die(f"{' '.join(cmd)} failed:\n{p.stderr}")
    note = [l for l in p.stderr.splitlines() if l.startswith("note:")]
    print("irad:", note[0] if note else "(no note)")
    mi = load_mitsuba(a.variant)
    irad_img = np.array(mi.Bitmap(os.path.join(ref_dir, "frame_0000.exr")).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))
    scene = mitsuba_scene(mi, objects, a.size, a.out)
    m = np.array(mi.render(scene, spp=a.spp, seed=1))[..., :3]
    mi.Bitmap(np.ascontiguousarray(m, dtype=np.float32)).write(os.path.join(a.out, "mitsuba.exr"))
    print(f"Mitsuba {mi.__version__} ({mi.variant()}), constant emitter of radiance 1, "
          f"{a.size}x{a.size}, {a.spp} spp each")
    print(f"mean luminance: irad {lum(irad_img):.5f}, Mitsuba {lum(m):.5f}")
    print(f"irad against Mitsuba: relMSE {rel_mse(irad_img, m):.5f}, "
          f"bias {100 * (lum(irad_img) / lum(m) - 1):+.2f}%")
    print(f"images: {ref_dir}/frame_0000.exr, {a.out}/mitsuba.exr")


if __name__ == "__main__":
    main()
