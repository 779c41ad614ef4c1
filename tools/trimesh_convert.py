"""Times trimesh on drapekit's convert benchmark: load + merge_vertices + fix_normals + export.

Usage: python trimesh_convert.py IN.stl OUT.ply   (prints one JSON object)
Run through tools/bench_convert.sh, which installs trimesh in tools/.venv.
"""
import json
import sys
import time

import trimesh

src, dst = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
mesh = trimesh.load(src)
t1 = time.perf_counter()
mesh.merge_vertices()
t2 = time.perf_counter()
mesh.fix_normals()
t3 = time.perf_counter()
mesh.export(dst)
t4 = time.perf_counter()
print(json.dumps({
    "version": trimesh.__version__,
    "load": t1 - t0,
    "merge_vertices": t2 - t1,
    "fix_normals": t3 - t2,
    "export": t4 - t3,
    "total": t4 - t0,
    "faces": int(len(mesh.faces)),
    "vertices": int(len(mesh.vertices)),
    "watertight": bool(mesh.is_watertight),
    "winding_consistent": bool(mesh.is_winding_consistent),
}))
