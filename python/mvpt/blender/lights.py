"""Blender lights as Mitsuba 3 emitters, with Cycles' power units (docs/blender.md, "Lights";
each factor checked against Cycles renders in tests/python/test_blender_cycles.py):

- point, power P [W], colour C: radiant intensity I = C P / (4 pi) [W/sr]; with a radius r > 0
  and visible to the camera, a sphere of radius r with radiance C P / (4 pi * pi r²), whose
  intensity is the same;
- spot: the same intensity inside the cone, cut off at half the spot size;
- sun, strength S: irradiance C S [W/m²] on a surface facing it;
- area, power P over a shape of area A (world space, after the object's scale): one-sided
  Lambertian radiance C P / (pi A) [W/(m² sr)], emitted along the light's -Z.

A light's shape has Mitsuba's `null` BSDF: rays pass through it (Cycles' lights are seen from
the front and let rays through from behind). Blender lights point down their local -Z; Mitsuba's spot, rectangle and disk face +Z, so
their to_world is the object's matrix times a half turn about X."""
from __future__ import annotations

import math

from .report import Report
from .xml_writer import Element, plugin

HALF_TURN_X = ((1, 0, 0, 0), (0, -1, 0, 0), (0, 0, -1, 0), (0, 0, 0, 1))


def _matmul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)) for i in range(4))


def _scaled(m, sx: float, sy: float):
    return _matmul(m, ((sx, 0, 0, 0), (0, sy, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)))


def _power(light) -> float:
    """The light's power or strength, with Blender's exposure (power x 2^exposure)."""
    return float(light.energy) * 2.0 ** float(getattr(light, "exposure", 0.0))


def _axis_length(m, j: int) -> float:
    return math.sqrt(sum(m[i][j] ** 2 for i in range(3)))


def convert_light(obj, matrix, report: Report) -> list[Element]:
    """The emitter elements (an emitter, or a shape with an area emitter) of one instance of
    the light object `obj` at world matrix `matrix` (rows of four)."""
    light = obj.data
    where = f"light '{light.name}'"
    colour = tuple(float(c) for c in light.color)
    if getattr(light, "use_nodes", False) and light.node_tree is not None:
        report.warn(f"{where}: its shader nodes are not converted (its colour and power are used)")
    kind = light.type
    if kind == "POINT":
        return [_point(light, matrix, colour, report, where, bool(getattr(obj, "visible_camera", True)))]
    if kind == "SPOT":
        return [_spot(light, matrix, colour, report, where)]
    if kind == "SUN":
        return [_sun(light, matrix, colour, report, where)]
    if kind == "AREA":
        if not getattr(obj, "visible_camera", True):
            report.note(f"{where}: Cycles hides it from the camera; mvpt's camera sees its front where it is "
                        f"in view")
        return _area(light, matrix, colour, report, where)
    report.warn(f"{where}: light type {kind} cannot be converted; left out")
    return []


def _intensity(light, colour):
    return tuple(c * _power(light) / (4 * math.pi) for c in colour)


def _point(light, matrix, colour, report, where, seen: bool) -> Element:
    """A point emitter; the sphere of the light's radius where the camera sees it (mvpt's
    camera would see the sphere of a light that Cycles hides from it, Blender's default)."""
    position = tuple(matrix[i][3] for i in range(3))
    r = float(light.shadow_soft_size)
    if r > 0 and not seen:
        report.note(f"{where}: hidden from the camera, so a point light: its radius {r:g} m is dropped "
                    f"(sharper shadows)")
    if r <= 0 or not seen:
        e = plugin("emitter", "point").rgb("intensity", _intensity(light, colour))
        e.add(Element("point", name="position", value=", ".join(f"{x:.9g}" for x in position)))
        return e
    if getattr(light, "use_soft_falloff", False):
        report.note(f"{where}: Cycles' soft falloff (intensity x d²/(d² + r²) near the light) is not modelled: "
                    f"a sphere of radius {r:g} m")
    sphere = plugin("shape", "sphere").float("radius", r)
    sphere.add(Element("point", name="center", value=", ".join(f"{x:.9g}" for x in position)))
    radiance = tuple(i / (math.pi * r * r) for i in _intensity(light, colour))
    sphere.add(plugin("bsdf", "null"))
    sphere.add(plugin("emitter", "area").rgb("radiance", radiance))
    return sphere


def _spot(light, matrix, colour, report, where) -> Element:
    half = math.degrees(float(light.spot_size)) / 2
    blend = float(light.spot_blend)
    # Cycles' smooth region: cos(angle) from cos(half) to cos(half) + (1 - cos(half)) blend.
    c = math.cos(math.radians(half))
    beam = math.degrees(math.acos(min(c + (1 - c) * blend, 1.0)))
    if blend > 0:
        report.warn(f"{where}: its blend {blend:g} becomes a linear falloff in angle from {beam:.3g} to "
                    f"{half:.3g} degrees (Cycles: a smoothstep in cosine)")
    if float(light.shadow_soft_size) > 0:
        report.note(f"{where}: its radius {light.shadow_soft_size:g} m is dropped (a point spot light)")
    sx, sy = _axis_length(matrix, 0), _axis_length(matrix, 1)
    if abs(sx - sy) > 1e-6 * max(sx, sy):
        report.warn(f"{where}: its non-uniform scale (an elliptical cone) is not converted: a round cone")
    m = _matmul(_unit_axes(matrix), HALF_TURN_X)
    e = plugin("emitter", "spot").rgb("intensity", _intensity(light, colour))
    return e.float("cutoff_angle", min(half, 90.0)).float("beam_width", min(beam, half, 90.0)).matrix("to_world", m)


def _unit_axes(m):
    """`m` with its three axes normalised (a rigid pose)."""
    lengths = [_axis_length(m, j) or 1.0 for j in range(3)]
    return tuple(tuple(m[i][j] / lengths[j] if j < 3 and i < 3 else m[i][j] for j in range(4)) for i in range(4))


def _sun(light, matrix, colour, report, where) -> Element:
    d = [-matrix[i][2] for i in range(3)]
    n = math.sqrt(sum(x * x for x in d)) or 1.0
    angle = math.degrees(float(light.angle))
    if angle > 1.0:
        report.warn(f"{where}: its angular diameter {angle:.3g} degrees is dropped (sharp shadows)")
    elif angle > 0:
        report.note(f"{where}: its angular diameter {angle:.3g} degrees is dropped (sharp shadows)")
    e = plugin("emitter", "directional").rgb("irradiance", tuple(c * _power(light) for c in colour))
    e.add(Element("vector", name="direction", value=", ".join(f"{x / n:.9g}" for x in d)))
    return e


def _area(light, matrix, colour, report, where) -> list[Element]:
    if getattr(light, "cycles", None) is not None and getattr(light.cycles, "is_portal", False):
        report.warn(f"{where}: a portal light; left out (mvpt has no portals)")
        return []
    shape = light.shape
    sx = float(light.size)
    sy = float(light.size_y) if shape in ("RECTANGLE", "ELLIPSE") else sx
    if shape not in ("SQUARE", "RECTANGLE", "DISK", "ELLIPSE"):
        report.warn(f"{where}: area shape {shape} cannot be converted; left out")
        return []
    spread = math.degrees(float(getattr(light, "spread", math.pi)))
    if spread < 179.999:
        report.warn(f"{where}: its spread {spread:.3g} degrees is dropped (a Lambertian emitter)")
    area = _axis_length(matrix, 0) * sx * _axis_length(matrix, 1) * sy
    disk = shape in ("DISK", "ELLIPSE")
    if disk:
        area *= math.pi / 4
    if area <= 0:
        report.warn(f"{where}: its area is zero; left out")
        return []
    radiance = tuple(c * _power(light) / (math.pi * area) for c in colour)
    s = plugin("shape", "disk" if disk else "rectangle")
    s.matrix("to_world", _matmul(_scaled(matrix, sx / 2, sy / 2), HALF_TURN_X))
    s.add(plugin("bsdf", "null"))
    s.add(plugin("emitter", "area").rgb("radiance", radiance))
    return [s]
