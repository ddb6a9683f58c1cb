"""Blender materials (Cycles shader node trees) as Mitsuba 3 BSDFs and area-emitter radiance.

Exact: Diffuse BSDF (roughness 0), Emission (radiance = Color x Strength, as Cycles takes it),
Mix Shader with a constant factor (blendbsdf), Add Shader of an emission and a BSDF, Glass
(roughness 0), materials without nodes' Cycles default (diffuse 0.8) and the Principled BSDF
with Specular IOR Level 0, Metallic 0 and no transmission, coat, sheen or subsurface (a
Lambertian diffuse). Approximated, with a warning: the other Principled BSDFs (docs/blender.md,
"Materials"), Glossy, rough Glass. Any other node: a warning naming material and node, and the
fallback, diffuse 0.8. Opaque BSDFs are wrapped in `twosided`: Cycles shades both sides."""
from __future__ import annotations

from . import sockets, textures
from .bsdfs import Surface, blend, conductor, dielectric, diffuse, twosided
from .principled import principled
from .report import Report
from .xml_writer import plugin


class Materials:
    """Converts materials once each; `where` names them in warnings."""

    def __init__(self, report: Report, folder):
        self.report = report
        self.textures = textures.Textures(report, folder)
        self.cache: dict = {}

    def surface(self, material) -> Surface:
        key = material.name if material is not None else None
        if key not in self.cache:
            self.cache[key] = self._convert(material)
        return self.cache[key]

    def _convert(self, material) -> Surface:
        if material is None:
            return Surface(diffuse())
        where = f"material '{material.name}'"
        tree = material.node_tree  # Blender 5 always shades with the tree (use_nodes is deprecated)
        if tree is None:
            self.report.note(f"{where} has no shader nodes: rendered as a diffuse of its viewport colour")
            return Surface(diffuse(tuple(material.diffuse_color)[:3]))
        out = tree.get_output_node("CYCLES")
        node = sockets.linked_node(out.inputs["Surface"]) if out is not None else None
        if node is None:
            self.report.warn(f"{where} has no surface shader: rendered black, as in Cycles")
            return Surface(twosided(plugin("bsdf", "diffuse").rgb("reflectance", (0, 0, 0))))
        if out is not None and sockets.is_linked(out, "Volume"):
            self.report.warn(f"{where}: its volume shader is not converted (surfaces only)")
        if out is not None and sockets.is_linked(out, "Displacement"):
            self.report.warn(f"{where}: its displacement is not converted")
        return self.shader(node, where)

    def shader(self, node, where: str) -> Surface:
        """A shader node as a Surface; unknown nodes fall back to diffuse 0.8 with a warning."""
        convert = getattr(self, "_" + node.bl_idname, None)
        if node.mute:
            self.report.warn(f"{where}: node '{node.name}' is muted; rendered as diffuse 0.8")
            return Surface(diffuse())
        if convert is None:
            self.report.warn(f"{where}: node '{node.name}' ({node.bl_idname}) cannot be converted; "
                             f"rendered as diffuse 0.8")
            return Surface(diffuse())
        return convert(node, where)

    def _input_shader(self, node, index: int, where: str) -> Surface:
        source = sockets.linked_node(node.inputs[index])
        if source is None:  # an unlinked shader input is no shader: black, no emission
            return Surface(twosided(plugin("bsdf", "diffuse").rgb("reflectance", (0, 0, 0))))
        return self.shader(source, where)

    def _constant(self, node, name: str, where: str) -> float:
        if sockets.is_linked(node, name):
            self.report.warn(f"{where}: input '{name}' of node '{node.name}' is driven by a node; "
                             f"its own value {sockets.value(node, name):g} is used")
        return sockets.value(node, name)

    def _ignored_normal(self, node, where: str) -> None:
        if sockets.is_linked(node, "Normal"):
            self.report.warn(f"{where}: the normal map or bump on node '{node.name}' is not converted")

    # Shader nodes, by their bl_idname.
    def _ShaderNodeBsdfDiffuse(self, node, where):
        if self._constant(node, "Roughness", where) > 0:
            self.report.warn(f"{where}: node '{node.name}' has roughness (Oren-Nayar); rendered Lambertian")
        self._ignored_normal(node, where)
        b = plugin("bsdf", "diffuse")
        self.textures.colour(b, "reflectance", node, "Color", where)
        return Surface(twosided(b))

    def _ShaderNodeEmission(self, node, where):
        colour = self.textures.constant_colour(node, "Color", where)
        strength = self._constant(node, "Strength", where)
        return Surface(twosided(plugin("bsdf", "diffuse").rgb("reflectance", (0, 0, 0))),
                       tuple(c * strength for c in colour))

    def _ShaderNodeMixShader(self, node, where):
        fac = min(max(self._constant(node, "Fac", where), 0.0), 1.0)
        a, b = self._input_shader(node, 1, where), self._input_shader(node, 2, where)
        emission = _mix_emission(a.emission, b.emission, fac)
        return Surface(blend(fac, a.bsdf, b.bsdf), emission)

    def _ShaderNodeAddShader(self, node, where):
        a, b = self._input_shader(node, 0, where), self._input_shader(node, 1, where)
        emitters = [s for s in (a, b) if s.emission is not None]
        if len(emitters) == 1:  # emission + a BSDF: exact
            other = b if emitters[0] is a else a
            return Surface(other.bsdf, emitters[0].emission)
        self.report.warn(f"{where}: Add Shader '{node.name}' of two BSDFs cannot be converted; "
                         f"its first shader is used")
        return a

    def _ShaderNodeBsdfGlossy(self, node, where):
        self._ignored_normal(node, where)
        r = self._constant(node, "Roughness", where)
        b = conductor(r)
        self.textures.colour(b, "specular_reflectance", node, "Color", where)
        if r > 0:
            self.report.warn(f"{where}: Glossy BSDF '{node.name}' is rendered as a single-scattering GGX "
                             f"conductor of alpha {r * r:.4g} (Cycles: {node.distribution})")
        return Surface(twosided(b))

    def _ShaderNodeBsdfGlass(self, node, where):
        self._ignored_normal(node, where)
        r = self._constant(node, "Roughness", where)
        b = dielectric(r, self._constant(node, "IOR", where))
        colour = self.textures.constant_colour(node, "Color", where)
        b.rgb("specular_reflectance", colour).rgb("specular_transmittance", colour)
        if r > 0:
            self.report.warn(f"{where}: Glass BSDF '{node.name}' is rendered as a single-scattering GGX "
                             f"roughdielectric of alpha {r * r:.4g} (Cycles: {node.distribution})")
        return Surface(b)

    def _ShaderNodeBsdfPrincipled(self, node, where):
        return principled(self, node, where)


def _mix_emission(a, b, fac):
    if a is None and b is None:
        return None
    a, b = a or (0.0, 0.0, 0.0), b or (0.0, 0.0, 0.0)
    return tuple((1 - fac) * x + fac * y for x, y in zip(a, b))
