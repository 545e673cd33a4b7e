#!/usr/bin/env python3
"""Writes the collider meshes of the body scenes (closed, outward, y up, metres):

- icosphere.obj: a unit icosphere, 3 subdivisions (1280 triangles): `scenes/body-sphere.toml`
  scales it to compare a mesh collider with the analytic sphere.
- mannequin.obj: a standing figure 1.73 m tall facing +z, feet on y = 0: a torso of
  elliptic sections, neck, head, arms and legs of tapered capsules, feet and hands as
  ellipsoids. Each part is a closed surface of its own; the parts overlap (a limb runs
  into the torso), which clothlab's fields read by winding number (core::sdf).

Run from anywhere: python3 scenes/meshes/make_bodies.py (writes next to itself).
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def write_obj(path, verts, tris, comment):
    with open(path, "w") as f:
        f.write(f"# {comment}\n# written by scenes/meshes/make_bodies.py\n")
        for v in verts:
            f.write("v %.5f %.5f %.5f\n" % v)
        for t in tris:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    p = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    p = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in p]
    for _ in range(levels):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                v = [(p[a][i] + p[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in v))
                p.append(tuple(x / n for x in v))
                mid[k] = len(p) - 1
            return mid[k]

        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return p, f


class Mesh:
    def __init__(self):
        self.v, self.t = [], []

    def add(self, verts, tris):
        # Outward: a closed part's signed volume is positive.
        vol = 0.0
        for a, b, c in tris:
            pa, pb, pc = verts[a], verts[b], verts[c]
            vol += (pa[0] * (pb[1] * pc[2] - pb[2] * pc[1]) - pa[1] * (pb[0] * pc[2] - pb[2] * pc[0])
                    + pa[2] * (pb[0] * pc[1] - pb[1] * pc[0]))
        if vol < 0:
            tris = [(a, c, b) for a, b, c in tris]
        o = len(self.v)
        self.v += verts
        self.t += [(a + o, b + o, c + o) for a, b, c in tris]


def norm(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def lathe(a, b, profile, seg=16, up=(0, 0, 1)):
    """A closed surface about the axis a→b: profile = [(s, rx, rz)], s from 0 (a) to 1
    (b), radii along two directions across the axis; the first and last radii 0 (poles)."""
    u = norm(tuple(b[i] - a[i] for i in range(3)))
    e1 = norm(cross(u, up)) if abs(sum(u[i] * up[i] for i in range(3))) < 0.99 else norm(cross(u, (1, 0, 0)))
    e2 = cross(e1, u)
    ln = math.sqrt(sum((b[i] - a[i]) ** 2 for i in range(3)))
    verts, rings = [], []
    for s, rx, rz in profile:
        c = tuple(a[i] + u[i] * s * ln for i in range(3))
        if rx == 0 and rz == 0:
            verts.append(c)
            rings.append([len(verts) - 1])
            continue
        ring = []
        for k in range(seg):
            th = 2 * math.pi * k / seg
            verts.append(tuple(c[i] + e1[i] * rx * math.cos(th) + e2[i] * rz * math.sin(th) for i in range(3)))
            ring.append(len(verts) - 1)
        rings.append(ring)
    tris = []
    for r0, r1 in zip(rings, rings[1:]):
        if len(r0) == 1:
            tris += [(r0[0], r1[(k + 1) % seg], r1[k]) for k in range(seg)]
        elif len(r1) == 1:
            tris += [(r0[k], r0[(k + 1) % seg], r1[0]) for k in range(seg)]
        else:
            for k in range(seg):
                k1 = (k + 1) % seg
                tris += [(r0[k], r0[k1], r1[k1]), (r0[k], r1[k1], r1[k])]
    return verts, tris


def capsule(a, b, ra, rb, seg=14, caps=4):
    """A tapered capsule: hemispheres of radii ra at a and rb at b."""
    ln = math.sqrt(sum((b[i] - a[i]) ** 2 for i in range(3)))
    prof = []
    for k in range(caps + 1):  # the cap at a, from its pole
        th = math.pi / 2 * (1 - k / caps)
        prof.append(((-ra * math.sin(th)) / ln, ra * math.cos(th), ra * math.cos(th)))
    for k in range(caps + 1):  # the cap at b, to its pole
        th = math.pi / 2 * k / caps
        prof.append((1 + (rb * math.sin(th)) / ln, rb * math.cos(th), rb * math.cos(th)))
    prof[0] = (prof[0][0], 0, 0)
    prof[-1] = (prof[-1][0], 0, 0)
    return lathe(a, b, prof, seg)


def ellipsoid(c, r, seg=14, rings=8):
    a = (c[0], c[1] - r[1], c[2])
    b = (c[0], c[1] + r[1], c[2])
    prof = []
    for k in range(rings + 1):
        th = math.pi * k / rings
        s = (1 - math.cos(th)) / 2
        prof.append((s, r[0] * math.sin(th) if 0 < k < rings else 0, r[2] * math.sin(th) if 0 < k < rings else 0))
    return lathe(a, b, prof, seg, up=(0, 0, 1))


def mannequin():
    m = Mesh()
    # Torso: elliptic sections (half-widths across x and z) from the crotch to the neck.
    y0, y1 = 0.84, 1.50
    sect = [(0.84, 0, 0), (0.86, 0.11, 0.08), (0.90, 0.16, 0.11), (0.97, 0.17, 0.115), (1.05, 0.15, 0.10),
            (1.13, 0.14, 0.10), (1.22, 0.155, 0.11), (1.32, 0.17, 0.115), (1.40, 0.185, 0.105),
            (1.45, 0.16, 0.09), (1.49, 0.09, 0.06), (1.50, 0, 0)]
    prof = [((y - y0) / (y1 - y0), rx, rz) for y, rx, rz in sect]
    m.add(*lathe((0, y0, 0), (0, y1, 0), prof, seg=20, up=(1, 0, 0)))
    m.add(*capsule((0, 1.44, 0), (0, 1.58, 0.005), 0.055, 0.048))  # neck
    m.add(*ellipsoid((0, 1.655, 0.01), (0.08, 0.105, 0.095)))  # head
    for sx in (-1, 1):
        sh, el, wr = (sx * 0.19, 1.41, 0.0), (sx * 0.235, 1.13, -0.01), (sx * 0.26, 0.87, 0.03)
        m.add(*capsule(sh, el, 0.052, 0.042))  # upper arm
        m.add(*capsule(el, wr, 0.040, 0.030))  # forearm
        m.add(*ellipsoid((sx * 0.265, 0.80, 0.035), (0.025, 0.07, 0.045)))  # hand
        hip, knee, ankle = (sx * 0.09, 0.90, 0.0), (sx * 0.10, 0.48, 0.01), (sx * 0.10, 0.08, 0.0)
        m.add(*capsule(hip, knee, 0.085, 0.055))  # thigh
        m.add(*capsule(knee, ankle, 0.052, 0.036))  # shin
        m.add(*ellipsoid((sx * 0.10, 0.035, 0.05), (0.045, 0.035, 0.115)))  # foot
    return m


if __name__ == "__main__":
    v, f = icosphere(3)
    write_obj(os.path.join(HERE, "icosphere.obj"), v, f, "unit icosphere, 3 subdivisions")
    m = mannequin()
    write_obj(os.path.join(HERE, "mannequin.obj"), m.v, m.t,
              "a standing mannequin, 1.73 m, facing +z, feet on y = 0; overlapping closed parts")
    print(len(f), "icosphere triangles;", len(m.t), "mannequin triangles")
