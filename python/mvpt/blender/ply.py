"""Binary little-endian PLY triangle meshes with per-vertex normals and texture coordinates,
the properties mvpt's and Mitsuba 3's PLY readers take (x y z, nx ny nz, u v;
vertex_indices)."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def write_ply(path: Path, positions: np.ndarray, normals: np.ndarray, uvs, triangles: np.ndarray) -> None:
    """Write a mesh: positions and normals (n, 3), uvs (n, 2) or None, triangles (m, 3) of
    vertex indices."""
    n, m = len(positions), len(triangles)
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4")]
    if uvs is not None:
        fields += [("u", "<f4"), ("v", "<f4")]
    vertices = np.empty(n, dtype=fields)
    for i, axis in enumerate("xyz"):
        vertices[axis] = positions[:, i]
        vertices["n" + axis] = normals[:, i]
    if uvs is not None:
        vertices["u"], vertices["v"] = uvs[:, 0], uvs[:, 1]
    faces = np.empty(m, dtype=[("count", "u1"), ("indices", "<i4", (3,))])
    faces["count"] = 3
    faces["indices"] = triangles
    header = ["ply", "format binary_little_endian 1.0", "comment written by mvpt from a Blender scene",
              f"element vertex {n}"]
    header += [f"property float {name}" for name, _ in fields]
    header += [f"element face {m}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        f.write(vertices.tobytes())
        f.write(faces.tobytes())
