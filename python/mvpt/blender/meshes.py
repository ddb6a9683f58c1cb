"""Evaluated Blender meshes as triangle meshes, one per material slot.

The mesh is the object's evaluated geometry (modifiers applied), split into its loop triangles
(Blender's own triangulation of n-gons). Each triangle corner carries Blender's corner normal
(which is the face normal on flat faces, the smooth normal elsewhere, and custom split normals
where set: what Cycles shades with) and the active render UV map's coordinates, with v flipped
(Mitsuba's textures put v = 0 at the image's top row, Blender's at its bottom). Corners equal
in position, normal and uv become one vertex."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class MeshPart:
    slot: int                 # material slot index
    positions: np.ndarray     # (n, 3) float32, object space
    normals: np.ndarray       # (n, 3) float32
    uvs: np.ndarray | None    # (n, 2) float32
    triangles: np.ndarray     # (m, 3) int32


def _get(collection, attribute: str, count: int, width: int, dtype) -> np.ndarray:
    out = np.empty(count * width, dtype=dtype)
    collection.foreach_get(attribute, out)
    return out.reshape(count, width) if width > 1 else out


def _uv_layer(mesh):
    for layer in mesh.uv_layers:
        if layer.active_render:
            return layer
    return mesh.uv_layers.active


def mesh_parts(mesh, slot_count: int) -> list[MeshPart]:
    """The triangles of `mesh` grouped by material slot (indices clamped into the slots, as
    Blender does), each part with its own compact vertex arrays."""
    mesh.calc_loop_triangles()
    n_tri = len(mesh.loop_triangles)
    if n_tri == 0:
        return []
    corners = _get(mesh.loop_triangles, "loops", n_tri, 3, np.int32)
    slots = _get(mesh.loop_triangles, "material_index", n_tri, 1, np.int32)
    slots = np.clip(slots, 0, max(slot_count - 1, 0))
    positions = _get(mesh.vertices, "co", len(mesh.vertices), 3, np.float32)
    corner_vertex = _get(mesh.loops, "vertex_index", len(mesh.loops), 1, np.int32)
    normals = _get(mesh.corner_normals, "vector", len(mesh.loops), 3, np.float32)
    layer = _uv_layer(mesh)
    uvs = _get(layer.uv, "vector", len(mesh.loops), 2, np.float32) if layer is not None else None
    parts = []
    for slot in np.unique(slots):
        used = corners[slots == slot]
        parts.append(_part(int(slot), used, corner_vertex, positions, normals, uvs))
    return parts


def _part(slot, used, corner_vertex, positions, normals, uvs) -> MeshPart:
    """One slot's triangles (corner indices `used`, (m, 3)) with welded vertices."""
    flat = used.reshape(-1)
    key = [corner_vertex[flat][:, None].astype(np.float64), normals[flat].astype(np.float64)]
    if uvs is not None:
        key.append(uvs[flat].astype(np.float64))
    unique, first, inverse = np.unique(np.hstack(key), axis=0, return_index=True, return_inverse=True)
    corner = flat[first]
    part_uvs = None
    if uvs is not None:
        part_uvs = uvs[corner].copy()
        part_uvs[:, 1] = 1.0 - part_uvs[:, 1]
    return MeshPart(slot, positions[corner_vertex[corner]], normals[corner], part_uvs,
                    inverse.reshape(-1, 3).astype(np.int32))
