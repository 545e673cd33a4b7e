"""glTF files written by another tool than clothlab (trimesh, 4.x), for core/tests/suite/mesh_files.rs.

A 9 x 9 sheet of 0.8 m, its squares split along one diagonal (at most 6 triangles a
vertex), exported by trimesh as a binary .glb and as a .gltf with its buffer embedded as a
data URI; the .glb cut short, which must be refused; and the same sheet split along
alternating diagonals (a "union jack": 8 triangles at every other interior vertex), which
today's fixed tables refuse in one line (issue 44 lifts the limit).
Run: python3 make_foreign.py (numpy and trimesh from PyPI).
"""
import json

import numpy as np
import trimesh

n, size = 9, 0.8
h = size / (n - 1)
vertices = np.array([[i * h - size / 2, 0.0, j * h] for j in range(n) for i in range(n)], dtype=np.float64)


def sheet(alternate):
    faces = []
    for j in range(n - 1):
        for i in range(n - 1):
            a, b, c, d = j * n + i, j * n + i + 1, (j + 1) * n + i, (j + 1) * n + i + 1
            # Counter-clockwise seen from +y.
            if alternate and (i + j) % 2 == 1:
                faces += [[a, c, b], [b, c, d]]
            else:
                faces += [[a, c, d], [a, d, b]]
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.Trimesh(vertices=vertices, faces=np.array(faces), process=False), geom_name="sheet")
    return scene, len(faces)


scene, triangles = sheet(False)
with open("trimesh_sheet.glb", "wb") as f:
    f.write(trimesh.exchange.gltf.export_glb(scene))
files = trimesh.exchange.gltf.export_gltf(scene, embed_buffers=True)
with open("trimesh_sheet.gltf", "wb") as f:
    f.write(files["model.gltf"])
glb = open("trimesh_sheet.glb", "rb").read()
with open("truncated.glb", "wb") as f:
    f.write(glb[: len(glb) // 2])
with open("trimesh_unionjack.glb", "wb") as f:
    f.write(trimesh.exchange.gltf.export_glb(sheet(True)[0]))
print(json.dumps({"vertices": len(vertices), "triangles": triangles, "glb_bytes": len(glb)}))
