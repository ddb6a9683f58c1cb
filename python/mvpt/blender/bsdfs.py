"""Mitsuba 3 BSDF elements that the material conversion builds from: two-sided wrappers,
blends, mirrors and GGX conductors and dielectrics, and the surface they make with an
emission."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

from .xml_writer import Element, plugin

FALLBACK = (0.8, 0.8, 0.8)   # Cycles' surface for objects without a material


@dataclass
class Surface:
    bsdf: Element
    emission: Optional[tuple] = None   # radiance (RGB), where the material emits


def diffuse(colour=FALLBACK) -> Element:
    return twosided(plugin("bsdf", "diffuse").rgb("reflectance", colour))


def twosided(bsdf: Element) -> Element:
    wrapper = plugin("bsdf", "twosided")
    wrapper.add(bsdf)
    return wrapper


def blend(weight: float, first: Element, second: Element) -> Element:
    """(1 - weight) first + weight second: Blender's Mix Shader and Mitsuba's blendbsdf alike."""
    b = plugin("bsdf", "blendbsdf").float("weight", weight)
    b.add(first)
    b.add(second)
    return b


def ior_from_f0(f0: float) -> float:
    """The index of refraction whose normal-incidence Fresnel reflectance is f0."""
    s = math.sqrt(min(max(f0, 0.0), 0.999))
    return (1 + s) / (1 - s)


def conductor(roughness: float) -> Element:
    """A perfect-mirror metal (reflectance 1, tinted by specular_reflectance) of GGX alpha r²."""
    if roughness <= 0:
        return plugin("bsdf", "conductor").string("material", "none")
    return (plugin("bsdf", "roughconductor").string("material", "none").string("distribution", "ggx")
            .float("alpha", max(roughness * roughness, 1e-4)))


def dielectric(roughness: float, ior: float) -> Element:
    ior = max(ior, 1.0 + 1e-4)
    if roughness <= 0:
        return plugin("bsdf", "dielectric").float("int_ior", ior).float("ext_ior", 1.0)
    return (plugin("bsdf", "roughdielectric").string("distribution", "ggx")
            .float("alpha", max(roughness * roughness, 1e-4)).float("int_ior", ior).float("ext_ior", 1.0))

