#!/usr/bin/env python3
"""A Sponza-like open-plane mesh of a given triangle count (issue 23 item 5's "187k-triangle
open-plane mesh ... a 1M-triangle mesh's first frame"): a 30 x 14 x 12 m court, its floor,
walls, roof, two storeys of galleries along the long sides on 2 x 12 open octagonal columns
(no caps), and hanging curtains, every plane tessellated as a grid (one grey material, albedo
0.6, double-sided), lit by a 4 x 2 m ceiling panel facing down. The camera walks along the
court over 4 s (a glTF animation). Writes big_mesh.gltf + .bin into the folder given
(default /tmp/irad-big-mesh) and prints the triangle count.

    python3 benches/big_mesh.py [DIR] [TRIANGLES]     # default 187000
    irad render DIR/big_mesh.gltf --size 256x256 --vpls 256 --frames 0..4 --out OUT
"""
import json, math, os, struct, sys
from gltf_buffer import Buffer, bounds

out = sys.argv[1] if len(sys.argv) > 1 else "/tmp/irad-big-mesh"
target = int(sys.argv[2]) if len(sys.argv) > 2 else 187_000
os.makedirs(out, exist_ok=True)

L, W, H = 15.0, 7.0, 12.0  # half-length (x), half-width (z), height (y)

def planes():
    """(origin, edge u, edge v) of every open plane (a parallelogram origin + a u + b v)."""
    p = [
        ((-L, 0, -W), (2 * L, 0, 0), (0, 0, 2 * W)),  # floor
        ((-L, H, -W), (0, 0, 2 * W), (2 * L, 0, 0)),  # roof
        ((-L, 0, -W), (0, H, 0), (2 * L, 0, 0)),  # back wall
        ((-L, 0, W), (2 * L, 0, 0), (0, H, 0)),  # front wall
        ((-L, 0, -W), (0, 0, 2 * W), (0, H, 0)),  # end walls
        ((L, 0, -W), (0, H, 0), (0, 0, 2 * W)),
    ]
    for s in (-1, 1):  # galleries: floors at 4 and 8 m, 3 m deep
        for y in (4.0, 8.0):
            p.append(((-L, y, min(s * 4.0, s * 7.0)), (2 * L, 0, 0), (0, 0, 3.0)))
    for k in range(6):  # curtains hanging from the upper gallery, 2 m wide, 3 m tall
        x = -12.5 + 5 * k
        for s in (-1, 1):
            p.append(((x, 4.5, s * 4.2), (2.0, 0, 0), (0.3, 3.0, s * 0.4)))
    return p

def columns():
    """(centre x, centre z, bottom y, height) of the columns: 12 a side, two storeys."""
    return [(-13.75 + 2.5 * i, s * 4.0, y, 4.0) for i in range(12) for s in (-1, 1) for y in (0.0, 4.0)]

SIDES, RADIUS = 8, 0.3

def count(d):
    """Triangles at d cells a metre (at least 1 a side)."""
    n = 0
    for o, u, v in planes():
        lu, lv = math.dist((0, 0, 0), u), math.dist((0, 0, 0), v)
        n += 2 * max(1, round(lu * d)) * max(1, round(lv * d))
    side = 2 * RADIUS * math.sin(math.pi / SIDES)
    for c in columns():
        n += SIDES * 2 * max(1, round(side * d)) * max(1, round(c[3] * d))
    return n + 2

lo, hi = 0.1, 100.0
for _ in range(60):
    mid = math.sqrt(lo * hi)
    lo, hi = (mid, hi) if count(mid) < target else (lo, mid)
d = min((lo, hi), key=lambda x: abs(count(x) - target))

pos, idx = [], []

def grid(o, u, v, nu, nv):
    base = len(pos) // 3
    for j in range(nv + 1):
        for i in range(nu + 1):
            pos.extend(o[k] + u[k] * i / nu + v[k] * j / nv for k in range(3))
    for j in range(nv):
        for i in range(nu):
            a = base + j * (nu + 1) + i
            idx.extend([a, a + 1, a + nu + 2, a, a + nu + 2, a + nu + 1])

for o, u, v in planes():
    lu, lv = math.dist((0, 0, 0), u), math.dist((0, 0, 0), v)
    grid(o, u, v, max(1, round(lu * d)), max(1, round(lv * d)))
side = 2 * RADIUS * math.sin(math.pi / SIDES)
for cx, cz, y0, h in columns():
    for s in range(SIDES):
        a0, a1 = 2 * math.pi * s / SIDES, 2 * math.pi * (s + 1) / SIDES
        p0 = (cx + RADIUS * math.cos(a0), y0, cz + RADIUS * math.sin(a0))
        p1 = (cx + RADIUS * math.cos(a1), y0, cz + RADIUS * math.sin(a1))
        grid(p0, tuple(p1[k] - p0[k] for k in range(3)), (0, h, 0), max(1, round(side * d)), max(1, round(h * d)))
tris = len(idx) // 3
light = [-2, H - 0.05, -1, 2, H - 0.05, -1, 2, H - 0.05, 1, -2, H - 0.05, 1]
light_idx = [0, 1, 2, 0, 2, 3]  # faces down

buf = Buffer()
add = buf.add
bin_, views, accessors = buf.bin, buf.views, buf.accessors

p0 = add(pos, "f", len(pos) // 3, "VEC3", 5126, bounds(pos))
i0 = add(idx, "I", len(idx), "SCALAR", 5125)
p1 = add(light, "f", 4, "VEC3", 5126, bounds(light))
i1 = add(light_idx, "I", 6, "SCALAR", 5125)
# The camera walks from x = -11 to 9 at 1.7 m, turned 60 degrees from -z toward +x (and
# 10 degrees down), so that it looks along the court past the columns.
times = [0.0, 4.0]
t0 = add(times, "f", 2, "SCALAR", 5126, ([0.0], [4.0]))
c0 = add([-11.0, 1.7, 2.0, 9.0, 1.7, 2.0], "f", 2, "VEC3", 5126)
yaw, pitch = math.radians(-60), math.radians(-10)
q_yaw = (0, math.sin(yaw / 2), 0, math.cos(yaw / 2))
q_pitch = (math.sin(pitch / 2), 0, 0, math.cos(pitch / 2))
def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)
rot = qmul(q_yaw, q_pitch)
open(os.path.join(out, "big_mesh.bin"), "wb").write(bin_)
doc = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2]}],
    "nodes": [
        {"mesh": 0, "name": "court"},
        {"mesh": 1, "name": "light"},
        {"camera": 0, "translation": [-11.0, 1.7, 2.0], "rotation": list(rot)},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.05}}],
    "meshes": [
        {"primitives": [{"attributes": {"POSITION": p0}, "indices": i0, "material": 0}]},
        {"primitives": [{"attributes": {"POSITION": p1}, "indices": i1, "material": 1}]},
    ],
    "materials": [
        {"name": "grey", "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0}},
        {"name": "light", "emissiveFactor": [1, 0.95, 0.85],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 60.0}},
         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}},
    ],
    "animations": [{"name": "walk", "channels": [{"sampler": 0, "target": {"node": 2, "path": "translation"}}],
                    "samplers": [{"input": t0, "output": c0, "interpolation": "LINEAR"}]}],
    "extensionsUsed": ["KHR_materials_emissive_strength"],
    "buffers": [{"uri": "big_mesh.bin", "byteLength": len(bin_)}],
    "bufferViews": views,
    "accessors": accessors,
}
json.dump(doc, open(os.path.join(out, "big_mesh.gltf"), "w"))
print(f"{out}/big_mesh.gltf: {tris + 2} triangles ({d:.2f} cells a metre)")
