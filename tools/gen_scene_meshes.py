"""Writes the analytic meshes of fixtures/scenes/ (committed; rerun only to change them).

sphere_r0.3.obj : icosphere (icosahedron subdivided 3 times, 1280 faces), radius 0.3 m, centre origin
disc_r0.09.obj  : closed cylinder radius 0.09 m (the Cusick support disc), 96 segments, z from -0.02 to 0
"""
import math, os

here = os.path.join(os.path.dirname(__file__), "..", "fixtures", "scenes")

def icosphere(level, r):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
         (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid = {}
        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[k] = len(v) - 1
            return mid[k]
        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return [tuple(r * x for x in p) for p in v], f

def disc(r, h, n):
    v = [(0, 0, 0), (0, 0, -h)]
    for i in range(n):
        a = 2 * math.pi * i / n
        v.append((r * math.cos(a), r * math.sin(a), 0))
        v.append((r * math.cos(a), r * math.sin(a), -h))
    f = []
    for i in range(n):
        t0, b0, t1, b1 = 2 + 2 * i, 3 + 2 * i, 2 + 2 * ((i + 1) % n), 3 + 2 * ((i + 1) % n)
        f += [(0, t0, t1), (1, b1, b0), (t0, b0, b1), (b1, t1, t0)]
    return v, f

def write(name, v, f, note):
    with open(os.path.join(here, name), "w") as o:
        o.write(f"# {note} (tools/gen_scene_meshes.py)\n")
        for p in v:
            o.write("v %.9f %.9f %.9f\n" % p)
        for t in f:
            o.write("f %d %d %d\n" % tuple(i + 1 for i in t))

write("sphere_r0.3.obj", *icosphere(3, 0.3), "icosphere level 3, radius 0.3 m")
write("disc_r0.09.obj", *disc(0.09, 0.02, 96), "Cusick support disc, radius 0.09 m, top at z = 0")
