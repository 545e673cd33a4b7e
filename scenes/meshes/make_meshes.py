#!/usr/bin/env python3
"""Writes the mesh scenes' OBJ files (issue 34): a round tablecloth, a skirt (an open
cylinder) and a flag with a hole. Each is a regular triangulation (every interior vertex
in six triangles, with six edges and six bending springs: the solvers' tables hold 12),
quads split along one diagonal as clothlab's grid is. Run from anywhere:

    python3 scenes/meshes/make_meshes.py

The files are committed; `cargo test -p clothlab-core mesh_files` checks that they
load and what they hold. Positions in metres, in the mesh's own frame (a scene places
them); uvs in [0, 1].
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def grid(nu, nv, point, keep_quad=lambda i, j: True, wrap_u=False):
    """Vertices of an nu × nv lattice (point(i, j) -> (x, y, z), uv from i, j), triangles of
    the kept quads; with wrap_u the last column joins the first (a closed ring)."""
    cols = nu if wrap_u else nu
    quads_u = nu if wrap_u else nu - 1
    index = {}
    verts, uvs, tris = [], [], []

    def vid(i, j):
        i = i % nu if wrap_u else i
        if (i, j) not in index:
            index[(i, j)] = len(verts)
            verts.append(point(i, j))
            uvs.append((i / (cols - (0 if wrap_u else 1)), j / (nv - 1)))
        return index[(i, j)]

    for j in range(nv - 1):
        for i in range(quads_u):
            if not keep_quad(i, j):
                continue
            p00, p10, p01, p11 = vid(i, j), vid(i + 1, j), vid(i, j + 1), vid(i + 1, j + 1)
            # Counter-clockwise seen from +y for a sheet in the xz-plane (x right, z towards
            # the viewer), as core::grid::build.
            tris.append((p00, p01, p11))
            tris.append((p00, p11, p10))
    return verts, uvs, tris


def write(name, verts, uvs, tris, comment):
    path = os.path.join(HERE, name)
    with open(path, "w") as f:
        f.write(f"# {comment}\n# written by scenes/meshes/make_meshes.py\n")
        for x, y, z in verts:
            f.write(f"v {x:.6f} {y:.6f} {z:.6f}\n")
        for u, v in uvs:
            f.write(f"vt {u:.6f} {v:.6f}\n")
        for a, b, c in tris:
            a, b, c = a + 1, b + 1, c + 1
            f.write(f"f {a}/{a} {b}/{b} {c}/{c}\n")
    print(f"{path}: {len(verts)} vertices, {len(tris)} triangles")


def tablecloth(n=61, radius=0.9):
    """A disc: the quads of an n × n lattice over [-r, r]² whose four corners lie in it."""
    h = 2 * radius / (n - 1)
    point = lambda i, j: (-radius + i * h, 0.0, -radius + j * h)
    inside = lambda i, j: math.hypot(*(c for c in point(i, j)[::2])) <= radius

    def keep(i, j):
        return all(inside(i + di, j + dj) for di in (0, 1) for dj in (0, 1))

    verts, uvs, tris = grid(n, n, point, keep)
    write("tablecloth.obj", verts, uvs, tris, f"round tablecloth, radius {radius} m, lattice {n}x{n}")


def skirt(around=64, down=24, radius=0.35, flare=0.2, length=0.6):
    """An open cone: the waist (j = 0, radius r) at y = 0, the hem `length` below, `flare`
    wider. Wound so normals point outwards."""
    def point(i, j):
        t = j / (down - 1)
        r = radius + flare * t
        a = -2 * math.pi * i / around
        return (r * math.cos(a), -length * t, r * math.sin(a))

    verts, uvs, tris = grid(around, down, point, wrap_u=True)
    write("skirt.obj", verts, uvs, tris, f"skirt: waist radius {radius} m, hem {radius + flare} m, {length} m long")


def flag(nu=61, nv=41, width=1.5, height=1.0, hole=(0.9, 0.5), hole_r=0.18):
    """A vertical sheet in the xy-plane (x from the pole, y up), a round hole cut out."""
    hx, hy = width / (nu - 1), height / (nv - 1)
    point = lambda i, j: (i * hx, height - j * hy, 0.0)

    def keep(i, j):
        cx, cy = (i + 0.5) * hx, height - (j + 0.5) * hy
        return math.hypot(cx - hole[0], cy - hole[1]) > hole_r

    verts, uvs, tris = grid(nu, nv, point, keep)
    write("flag_hole.obj", verts, uvs, tris, f"flag {width}x{height} m with a hole of radius {hole_r} m")


if __name__ == "__main__":
    tablecloth()
    skirt()
    flag()
