#!/usr/bin/env python3
"""Seconds per frame of big open-plane meshes (issue 23 item 5; docs/design.md, "Big
meshes"): writes benches/big_mesh.py's meshes of the triangle counts given (default 187000
and 1040000), renders each RUNS times (default 3) at 256x256 with 256 VPLs over frames
0..FRAMES of its walking camera, and prints, per mesh, frame 0's seconds (and its shadow
maps' and G-buffer's) and the mean of the later frames, as min / median / max over the runs,
with the machine's load before and after.

    python3 benches/big_mesh_times.py target/release/irad [RUNS] [FRAMES] [TRIANGLES...] \\
        [-- RENDER FLAGS]
"""
import json, os, statistics, subprocess, sys, tempfile

args = sys.argv[1:]
extra = []
if "--" in args:
    extra = args[args.index("--") + 1 :]
    args = args[: args.index("--")]
binary = args[0] if args else "target/release/irad"
runs = int(args[1]) if len(args) > 1 else 3
frames = int(args[2]) if len(args) > 2 else 4
counts = [int(a) for a in args[3:]] or [187_000, 1_040_000]
here = os.path.dirname(os.path.abspath(__file__))
tmp = tempfile.mkdtemp(prefix="irad-big-mesh-")

def load():
    return open("/proc/loadavg").read().split()[:3]

print(f"load before: {' '.join(load())} (1, 5, 15 min); {os.cpu_count()} CPUs; flags {extra}")
for n in counts:
    d = os.path.join(tmp, str(n))
    made = subprocess.run([sys.executable, os.path.join(here, "big_mesh.py"), d, str(n)],
                          capture_output=True, text=True, check=True).stdout.strip()
    rows = []
    for r in range(runs):
        out = os.path.join(d, f"run{r}")
        subprocess.run([binary, "render", os.path.join(d, "big_mesh.gltf"), "--size", "256x256",
                        "--vpls", "256", "--frames", f"0..{frames}", "--out", out, *extra],
                       capture_output=True, check=True)
        fr = [json.loads(l) for l in open(os.path.join(out, "frames.jsonl"))]
        s0 = fr[0]["stages"]
        later = [f["seconds"] for f in fr[1:]]
        rows.append((fr[0]["seconds"], s0.get("shadow_maps", 0), s0.get("gbuffer", 0),
                     sum(later) / max(len(later), 1), fr[0]["drawn"]))
    print(made)
    for k, name in enumerate(["frame 0", "  shadow maps", "  G-buffer", "later frames (mean)"]):
        v = sorted(r[k] for r in rows)
        print(f"  {name:20} min {v[0]:6.2f}  median {statistics.median(v):6.2f}  max {v[-1]:6.2f} s")
    dr = rows[0][4]
    print(f"  drawn at frame 0: shadow faces {dr['shadow_faces']}, shadow triangles "
          f"{dr['shadow_triangles']}, G-buffer triangles {dr['gbuffer_triangles']} of {dr['triangles']}")
print(f"load after: {' '.join(load())}")
