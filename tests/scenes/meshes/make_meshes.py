"""Write the tiny test meshes of this folder (run once; the outputs are committed).

icosphere.obj / icosphere.ply / icosphere.serialized: a unit icosphere (2 subdivisions,
320 triangles) with per-vertex normals and spherical uv, in three file formats, so the
obj/ply/serialized readers are compared on the same geometry.

icosphere_attributes.ply: the same sphere with mesh attributes (Mitsuba's PLY naming):
vertex_color (color_0..2, a colour that varies sharply with the position), face_tint_color (tint_r, tint_g, tint_b)
and face_w (w_0, a scalar in [0, 1]), for the mesh_attribute texture. The serialized file follows
Mitsuba's format (version 4): u16 0x041C, u16 version, zlib stream of flags, name,
vertex/triangle counts, float32 positions, normals, uvs, u32 indices; then a u64 offset
table and u32 mesh count at the end."""
import struct
import zlib
from pathlib import Path

import numpy as np


def icosphere(levels=2):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(levels):
        cache, nf = {}, []

        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in cache:
                m = v[a] + v[b]
                v.append(m / np.linalg.norm(m))
                cache[k] = len(v) - 1
            return cache[k]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    p = np.array(v, np.float32)
    uv = np.stack([0.5 + np.arctan2(p[:, 0], p[:, 2]) / (2 * np.pi), 0.5 + np.arcsin(p[:, 1]) / np.pi], 1)
    return p, p.copy(), uv.astype(np.float32), np.array(f, np.uint32)


def write_obj(path, p, n, uv, f):
    with open(path, "w") as o:
        o.write("# unit icosphere, 2 subdivisions (make_meshes.py)\n")
        o.writelines(f"v {x:.7f} {y:.7f} {z:.7f}\n" for x, y, z in p)
        o.writelines(f"vn {x:.7f} {y:.7f} {z:.7f}\n" for x, y, z in n)
        o.writelines(f"vt {u:.7f} {w:.7f}\n" for u, w in uv)
        o.writelines(f"f {a+1}/{a+1}/{a+1} {b+1}/{b+1}/{b+1} {c+1}/{c+1}/{c+1}\n" for a, b, c in f)


def write_ply(path, p, n, uv, f):
    head = ("ply\nformat binary_little_endian 1.0\ncomment unit icosphere (make_meshes.py)\n"
            f"element vertex {len(p)}\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as o:
        o.write(head.encode())
        o.write(np.concatenate([p, n, uv], 1).astype("<f4").tobytes())
        for a, b, c in f:
            o.write(struct.pack("<Biii", 3, int(a), int(b), int(c)))


def write_attribute_ply(path, p, n, uv, f):
    # Colours that change sharply from vertex to vertex, so that interpolation errors show.
    color = (0.5 + 0.45 * np.sin(np.array([23.0, 29.0, 31.0]) * p + np.array([0.0, 2.0, 4.0]))).astype(np.float32)
    centre = p[f].mean(1)
    tint = np.stack([0.5 + 0.4 * np.sin(7 * centre[:, 0]), 0.5 + 0.4 * np.sin(5 * centre[:, 1] + 1),
                     0.5 + 0.4 * np.sin(3 * centre[:, 2] + 2)], 1).astype(np.float32)
    w = (0.5 + 0.5 * np.sin(9 * centre[:, 0] + 4 * centre[:, 2])).astype(np.float32)
    head = ("ply\nformat binary_little_endian 1.0\ncomment unit icosphere with attributes (make_meshes.py)\n"
            f"element vertex {len(p)}\nproperty float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
            "property float color_0\nproperty float color_1\nproperty float color_2\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\n"
            "property float tint_r\nproperty float tint_g\nproperty float tint_b\nproperty float w_0\nend_header\n")
    with open(path, "wb") as o:
        o.write(head.encode())
        o.write(np.concatenate([p, n, uv, color], 1).astype("<f4").tobytes())
        for (a, b, c), t, x in zip(f, tint, w):
            o.write(struct.pack("<Biii4f", 3, int(a), int(b), int(c), *t, x))


def write_serialized(path, p, n, uv, f):
    has_normals, has_uv, single = 0x0001, 0x0002, 0x1000
    body = struct.pack("<I", has_normals | has_uv | single) + b"icosphere\0"
    body += struct.pack("<QQ", len(p), len(f))
    body += p.astype("<f4").tobytes() + n.astype("<f4").tobytes() + uv.astype("<f4").tobytes()
    body += f.astype("<u4").tobytes()
    data = struct.pack("<HH", 0x041C, 4) + zlib.compress(body)
    data += struct.pack("<Q", 0) + struct.pack("<I", 1)
    Path(path).write_bytes(data)


if __name__ == "__main__":
    here = Path(__file__).parent
    mesh = icosphere()
    write_obj(here / "icosphere.obj", *mesh)
    write_ply(here / "icosphere.ply", *mesh)
    write_serialized(here / "icosphere.serialized", *mesh)
    write_attribute_ply(here / "icosphere_attributes.ply", *mesh)
