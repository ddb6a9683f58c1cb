"""The world as a Mitsuba 3 environment emitter: a Background node's Color x Strength is a
`constant` emitter of that radiance (as Cycles takes it: a white diffuse surface under a world
of radiance L renders L); an Environment Texture on its Color is an `envmap` scaled by the
strength and turned so that Blender's equirectangular directions land on the same pixels
(a Mapping node's rotation included)."""
from __future__ import annotations

import math
import os

from . import sockets
from .report import Report
from .xml_writer import Element, plugin

# Mitsuba's envmap frame (u = 0 along local -Z, u = 1/4 along +X, up +Y) to Blender's world,
# whose equirectangular u = 0.5 - atan2(y, x) / 2 pi (Cycles' direction_to_equirectangular)
# lies along -X at u = 0, +Y at u = 1/4, +X at the image's middle, up +Z: columns are the images
# of Mitsuba's local X, Y, Z.
ENVMAP_FRAME = ((0, 0, 1, 0), (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 0, 1))


def _matmul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)) for i in range(4))


def convert_world(world, report: Report) -> list[Element]:
    """The world's emitter elements (none for a black or missing world)."""
    if world is None:
        return []
    where = f"world '{world.name}'"
    tree = world.node_tree
    if tree is None:
        return _constant(tuple(world.color), 1.0)
    out = tree.get_output_node("CYCLES")
    node = sockets.linked_node(out.inputs["Surface"]) if out is not None else None
    if node is None:
        return []
    if node.bl_idname != "ShaderNodeBackground":
        report.warn(f"{where}: its surface node '{node.name}' ({node.bl_idname}) cannot be converted; "
                    f"the world is left black")
        return []
    if sockets.is_linked(node, "Strength"):
        report.warn(f"{where}: the strength of '{node.name}' is driven by a node; its own value is used")
    strength = sockets.value(node, "Strength")
    source = sockets.linked_node(node.inputs["Color"])
    if source is None:
        return _constant(sockets.rgb(node, "Color"), strength)
    if source.bl_idname == "ShaderNodeTexEnvironment":
        return _envmap(source, strength, report, where)
    report.warn(f"{where}: its colour is driven by node '{source.name}' ({source.bl_idname}), which is not "
                f"converted; its own colour is used")
    return _constant(sockets.rgb(node, "Color"), strength)


def _constant(colour, strength: float) -> list[Element]:
    radiance = tuple(float(c) * strength for c in colour[:3])
    if not any(radiance):
        return []
    return [plugin("emitter", "constant").rgb("radiance", radiance)]


def _envmap(node, strength: float, report: Report, where: str) -> list[Element]:
    image = node.image
    if image is None or image.source != "FILE" or image.packed_file is not None:
        report.warn(f"{where}: Environment Texture '{node.name}' has no image file; the world is left black")
        return []
    import bpy
    path = os.path.abspath(bpy.path.abspath(image.filepath, library=image.library))
    if not os.path.isfile(path):
        report.warn(f"{where}: environment image {path} does not exist; the world is left black")
        return []
    if node.projection != "EQUIRECTANGULAR":
        report.warn(f"{where}: Environment Texture projection {node.projection} is read as EQUIRECTANGULAR")
    e = plugin("emitter", "envmap").string("filename", path).float("scale", strength)
    e.matrix("to_world", _matmul(_inverse_rotation(node, report, where), ENVMAP_FRAME))
    return [e]


def _inverse_rotation(node, report: Report, where: str):
    """R⁻¹ for a Mapping node that rotates the lookup direction by R (identity without one):
    the texture is looked up at R d, so the environment turns by R⁻¹."""
    mapping = sockets.linked_node(node.inputs["Vector"])
    identity = ((1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1))
    if mapping is None:
        return identity
    if mapping.bl_idname != "ShaderNodeMapping" or mapping.vector_type not in ("POINT", "VECTOR", "TEXTURE"):
        report.warn(f"{where}: the environment's coordinates from '{mapping.name}' are not converted")
        return identity
    from mathutils import Euler
    rotation = Euler(sockets.value(mapping, "Rotation", (0, 0, 0)), "XYZ").to_matrix()
    if sockets.value(mapping, "Scale", (1, 1, 1)) != (1.0, 1.0, 1.0):
        report.warn(f"{where}: the scale of Mapping '{mapping.name}' is not converted")
    r = rotation if mapping.vector_type == "TEXTURE" else rotation.transposed()  # TEXTURE applies R⁻¹
    return tuple(tuple(r[i][j] if i < 3 and j < 3 else float(i == j) for j in range(4)) for i in range(4))
