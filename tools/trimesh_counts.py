"""Loads each mesh file with trimesh and prints one JSON object per file, one a line:
{"file", "version", "vertices", "faces", "geometries", "bounds": [[min], [max]], "colored",
"color_sum"}: the scene's geometry placed by its node transforms and concatenated (nodes scaled to
zero included); the geometries with vertex colours and the sum of their colours (0-255 RGBA).
Usage: python tools/trimesh_counts.py FILE...   (the venv of tools/ensure_test_tools.sh)
"""
import json
import sys

import numpy
import trimesh


def vertex_colors(g):
    """A geometry's COLOR_0 as 0-255 RGBA: trimesh keeps it as the visual when the primitive has
    no material, else as its visual's vertex attribute 'color' (the floats as stored)."""
    if g.visual.kind == "vertex":
        return numpy.asarray(g.visual.vertex_colors, dtype=numpy.int64)
    c = getattr(g.visual, "vertex_attributes", {}).get("color")
    if c is None:
        return None
    c = numpy.asarray(c)
    return numpy.round(c * 255).astype(numpy.int64) if c.dtype.kind == "f" else c.astype(numpy.int64)


for path in sys.argv[1:]:
    scene = trimesh.load(path, force="scene", process=False)
    mesh = scene.to_mesh() if hasattr(scene, "to_mesh") else scene.dump(concatenate=True)
    colored = [vertex_colors(g) for g in scene.geometry.values()]
    colored = [c for c in colored if c is not None]
    print(json.dumps({
        "file": path,
        "version": trimesh.__version__,
        "vertices": int(len(mesh.vertices)),
        "faces": int(len(mesh.faces)),
        "geometries": len(scene.geometry),
        "bounds": mesh.bounds.tolist() if len(mesh.vertices) else None,
        "colored": len(colored),
        "color_sum": [int(sum(int(c[:, k].sum()) for c in colored)) for k in range(4)],
    }))
