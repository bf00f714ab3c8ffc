#!/usr/bin/env python3
"""A model of about 200k triangles whose light comes from an emissive texture (issue 23
item 5's "200k-triangle model with emissive textures loads in at most 5 s"): a ceiling panel
meshed as an N x N grid, textured by a 1024 x 1024 emissive image of bright stripes, over a
grey floor. Writes big_emissive.gltf + .bin + .png into the folder given (default
/tmp/irad-big-emissive) and prints the triangle count.

    python3 benches/big_emissive.py [DIR] [N]
    farm-bench -n 3 -- target/release/irad scenes DIR/big_emissive.gltf
"""
import json, math, os, struct, sys, zlib
from gltf_buffer import Buffer, bounds

out = sys.argv[1] if len(sys.argv) > 1 else "/tmp/irad-big-emissive"
n = int(sys.argv[2]) if len(sys.argv) > 2 else 316
os.makedirs(out, exist_ok=True)

# The panel: (n+1)^2 vertices at y = 1 over [-1, 1]^2, faces down; uv over [0, 1]^2.
pos, uv, idx = [], [], []
for j in range(n + 1):
    for i in range(n + 1):
        x, z = -1 + 2 * i / n, -1 + 2 * j / n
        pos += [x, 1.0, z]
        uv += [i / n, j / n]
for j in range(n):
    for i in range(n):
        a = j * (n + 1) + i
        b, c, d = a + 1, a + n + 1, a + n + 2
        idx += [a, b, d, a, d, c]  # wound to face -y
floor_pos = [-2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2]
floor_idx = [0, 2, 1, 0, 3, 2]
buf = Buffer()
add = buf.add
bin_, views, accessors = buf.bin, buf.views, buf.accessors

p0 = add(pos, "f", len(pos) // 3, "VEC3", 5126, bounds(pos))
t0 = add(uv, "f", len(uv) // 2, "VEC2", 5126)
i0 = add(idx, "I", len(idx), "SCALAR", 5125)
p1 = add(floor_pos, "f", 4, "VEC3", 5126, bounds(floor_pos))
i1 = add(floor_idx, "I", 6, "SCALAR", 5125)

# A 1024 x 1024 RGB image: bright stripes on black (the panel emits in bands).
w = h = 1024
rows = b"".join(
    b"\x00" + bytes((255, 240, 200) if (y // 64) % 2 == 0 else (0, 0, 0)) * w for y in range(h)
)
def chunk(t, d):
    return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) \
    + chunk(b"IDAT", zlib.compress(rows, 6)) + chunk(b"IEND", b"")
open(os.path.join(out, "big_emissive.png"), "wb").write(png)
open(os.path.join(out, "big_emissive.bin"), "wb").write(bin_)
doc = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2]}],
    "nodes": [
        {"mesh": 0},
        {"mesh": 1},
        {"camera": 0, "translation": [0, 0.5, 3.2]},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
    "meshes": [
        {"primitives": [{"attributes": {"POSITION": p0, "TEXCOORD_0": t0}, "indices": i0, "material": 0}]},
        {"primitives": [{"attributes": {"POSITION": p1}, "indices": i1, "material": 1}]},
    ],
    "materials": [
        {"name": "panel", "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0},
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
         "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}},
        {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0}},
    ],
    "extensionsUsed": ["KHR_materials_emissive_strength"],
    "textures": [{"source": 0}],
    "images": [{"uri": "big_emissive.png"}],
    "buffers": [{"uri": "big_emissive.bin", "byteLength": len(bin_)}],
    "bufferViews": views,
    "accessors": accessors,
}
json.dump(doc, open(os.path.join(out, "big_emissive.gltf"), "w"))
print(f"{out}/big_emissive.gltf: {len(idx) // 3 + 2} triangles, emissive texture {w}x{h}")
