#!/usr/bin/env python3
"""Writes the irregular mesh scenes' OBJ files (issue 44): meshes triangulated as the
tools users bring meshes from triangulate them, not as clothlab's grid is. Needs numpy and
scipy (`pip install numpy scipy`); run from anywhere:

    python3 scenes/meshes/make_irregular.py               # cape.obj and fan.obj
    python3 scenes/meshes/make_irregular.py --big N PATH  # a disc of about N vertices

- cape.obj: a cape (a trapezoid with a rounded hem, 1.0 m long, in the xy-plane, its
  shoulders at y = 1) filled with jittered points and triangulated by Delaunay
  (scipy.spatial.Delaunay, Qhull): vertices of 3 to 9 or more triangles, as a remeshed or
  Delaunay garment has.
- fan.obj: a round cloth (radius 0.8 m, xz-plane) whose centre is filled as a fan of 64
  triangles (Blender's circle fill "Triangle Fan"), rings of quads outside it: a centre
  of valence 64.
- --big N PATH: a Delaunay disc of about N jittered points (radius 1 m, xz-plane), for
  `bench --mesh` on meshes of a quarter of a million vertices and more (not committed).

The committed files are checked by `cargo test -p clothlab-core mesh_files`.
Positions in metres, in the mesh's own frame (a scene places them); uvs in [0, 1]. The
random points come from a fixed seed: the files are the same at every run.
"""
import math
import os
import sys

import numpy as np
from scipy.spatial import Delaunay

HERE = os.path.dirname(os.path.abspath(__file__))


def write(path, verts, uvs, tris, comment, digits=6):
    with open(path, "w") as f:
        f.write(f"# {comment}\n# written by scenes/meshes/make_irregular.py\n")
        fmt = f"{{:.{digits}f}}"
        for x, y, z in verts:
            f.write(f"v {fmt.format(x)} {fmt.format(y)} {fmt.format(z)}\n")
        for u, v in uvs:
            f.write(f"vt {u:.5f} {v:.5f}\n")
        for a, b, c in tris:
            a, b, c = a + 1, b + 1, c + 1
            f.write(f"f {a}/{a} {b}/{b} {c}/{c}\n")
    valence = np.bincount(np.asarray(tris).ravel(), minlength=len(verts))
    print(f"{path}: {len(verts)} vertices, {len(tris)} triangles, triangles a vertex {valence.min()}..{valence.max()}")


def jittered(rng, xmin, xmax, ymin, ymax, h, inside, keep_off=None):
    """Points of a hexagonal lattice of spacing h over the box, each moved by up to 0.3 h,
    those `inside` (and farther than 0.45 h from the boundary, where `keep_off` says)."""
    pts = []
    row_h = h * math.sqrt(3) / 2
    j = 0
    y = ymin
    while y <= ymax:
        x = xmin + (h / 2 if j % 2 else 0.0)
        while x <= xmax:
            p = (x + rng.uniform(-0.3, 0.3) * h, y + rng.uniform(-0.3, 0.3) * h)
            if inside(p) and (keep_off is None or keep_off(p) > 0.45 * h):
                pts.append(p)
            x += h
        y += row_h
        j += 1
    return pts


def delaunay(points):
    """Triangles of the Delaunay triangulation, counter-clockwise in the plane's (a, b)
    coordinates, without the slivers Qhull leaves along a curved hull (area under 1e-4
    of the mean)."""
    pts = np.asarray(points)
    tris = Delaunay(pts).simplices
    a, b, c = pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]]
    cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    tris = np.where((cross < 0)[:, None], tris[:, [0, 2, 1]], tris)
    keep = np.abs(cross) > 1e-4 * np.abs(cross).mean()
    return tris[keep]


def cape(h=0.032, seed=44):
    """The cape's outline: shoulders 0.5 m wide at y = 1, sides out to 1.2 m at y = 0.1, a
    hem bowed down to y = 0 at the middle. The outline's points at spacing h, the inside
    filled with jittered points; in the xy-plane, normals towards +z."""
    rng = np.random.default_rng(seed)
    top, bottom, shoulder, hem, bow = 1.0, 0.1, 0.25, 0.6, 0.1

    def half_width(y):
        t = (top - y) / (top - bottom)
        return shoulder + (hem - shoulder) * t

    def hem_y(x):
        return bottom - bow * (1.0 - (x / hem) ** 2)

    outline = []
    # Shoulders, left to right; the right side down; the hem right to left; the left side up.
    corners = [(-shoulder, top), (shoulder, top), (hem, bottom)]
    for (x0, y0), (x1, y1) in zip(corners, corners[1:]):
        k = max(2, round(math.hypot(x1 - x0, y1 - y0) / h))
        outline += [(x0 + (x1 - x0) * s / k, y0 + (y1 - y0) * s / k) for s in range(k)]
    k = round(2 * hem / h)
    outline += [(hem - 2 * hem * s / k, hem_y(hem - 2 * hem * s / k)) for s in range(k)]
    k = max(2, round(math.hypot(hem - shoulder, top - bottom) / h))
    outline += [(-hem + (hem - shoulder) * s / k, bottom + (top - bottom) * s / k) for s in range(k)]

    def inside(p):
        x, y = p
        return y < top and y > hem_y(x) and abs(x) < half_width(y) and abs(x) < hem

    def clearance(p):
        return min(math.hypot(p[0] - q[0], p[1] - q[1]) for q in outline)

    pts = outline + jittered(rng, -hem, hem, -bow, top, h, inside, clearance)
    tris = delaunay(pts)
    verts = [(x, y, 0.0) for x, y in pts]
    uvs = [((x + hem) / (2 * hem), (top - y) / (top + bow)) for x, y in pts]
    write(os.path.join(HERE, "cape.obj"), verts, uvs, tris, f"cape: Delaunay of {len(pts)} jittered points, spacing {h} m")


def fan(radius=0.8, around=64, rings=8):
    """A disc: the centre, then `rings` rings of `around` vertices; the centre joined to
    the first ring by a fan, each ring to the next by quads split along one diagonal."""
    verts, uvs, tris = [(0.0, 0.0, 0.0)], [(0.5, 0.5)], []
    for k in range(1, rings + 1):
        r = radius * k / rings
        for i in range(around):
            a = 2 * math.pi * i / around
            verts.append((r * math.cos(a), 0.0, r * math.sin(a)))
            uvs.append((0.5 + 0.5 * r / radius * math.cos(a), 0.5 + 0.5 * r / radius * math.sin(a)))

    def ring(k, i):
        return 1 + (k - 1) * around + i % around

    # Counter-clockwise seen from +y: x right, z towards the viewer, angles from x to z.
    for i in range(around):
        tris.append((0, ring(1, i + 1), ring(1, i)))
    for k in range(1, rings):
        for i in range(around):
            a, b, c, d = ring(k, i), ring(k, i + 1), ring(k + 1, i), ring(k + 1, i + 1)
            tris.append((a, b, d))
            tris.append((a, d, c))
    write(os.path.join(HERE, "fan.obj"), verts, uvs, tris, f"disc of radius {radius} m, a fan of {around} at its centre")


def big(count, path, seed=250):
    """A Delaunay disc of radius 1 m of about `count` jittered points, its rim on the circle."""
    rng = np.random.default_rng(seed)
    h = math.sqrt(math.pi / (count * math.sqrt(3) / 2))
    rim = round(2 * math.pi / h)
    outline = [(math.cos(2 * math.pi * s / rim), math.sin(2 * math.pi * s / rim)) for s in range(rim)]
    # Lattice points over the box, moved as jittered() moves them, those well inside the rim.
    row_h = h * math.sqrt(3) / 2
    ys = np.arange(-1.0, 1.0 + row_h, row_h)
    pts = []
    for j, y in enumerate(ys):
        xs = np.arange(-1.0 + (h / 2 if j % 2 else 0.0), 1.0 + h, h)
        p = np.stack([xs + rng.uniform(-0.3, 0.3, xs.size) * h, y + rng.uniform(-0.3, 0.3, xs.size) * h], axis=1)
        pts.append(p[np.hypot(p[:, 0], p[:, 1]) < 1.0 - 0.45 * h])
    pts = np.concatenate([np.asarray(outline)] + pts)
    tris = delaunay(pts)
    # The plane's (a, b) are (x, z) here: counter-clockwise from +y needs (x, z) clockwise.
    tris = tris[:, [0, 2, 1]]
    verts = [(x, 0.0, z) for x, z in pts]
    uvs = [(0.5 + 0.5 * x, 0.5 + 0.5 * z) for x, z in pts]
    write(path, verts, uvs, tris, f"disc: Delaunay of {len(pts)} jittered points", digits=5)


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--big":
        big(int(sys.argv[2]), sys.argv[3])
    else:
        cape()
        fan()
