"""Loads each mesh file with trimesh and prints one JSON object per file, one a line:
{"file", "version", "vertices", "faces", "geometries", "bounds": [[min], [max]]}, the scene's
geometry placed by its node transforms and concatenated (nodes scaled to zero included).
Usage: python tools/trimesh_counts.py FILE...   (the venv of tools/ensure_test_tools.sh)
"""
import json
import sys

import trimesh

for path in sys.argv[1:]:
    scene = trimesh.load(path, force="scene", process=False)
    mesh = scene.to_mesh() if hasattr(scene, "to_mesh") else scene.dump(concatenate=True)
    print(json.dumps({
        "file": path,
        "version": trimesh.__version__,
        "vertices": int(len(mesh.vertices)),
        "faces": int(len(mesh.faces)),
        "geometries": len(scene.geometry),
        "bounds": mesh.bounds.tolist() if len(mesh.vertices) else None,
    }))
