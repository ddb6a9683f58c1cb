"""Blender's Principled BSDF (the 4.x/5.x model) in terms of mvpt's BSDFs.

Blender's Principled BSDF is a metal mixed by Metallic over a dielectric stack, whose
Transmission Weight mixes glass over an opaque base: a GGX dielectric specular layer (IOR,
scaled by Specular IOR Level: F0 x 2 x level) over a Lambertian diffuse of Base Color. Here:

    blendbsdf(Metallic, blendbsdf(Transmission, roughplastic, roughdielectric), roughconductor)

with GGX alpha = Roughness², the plastic's diffuse the Base Color and its IOR the one whose F0
equals Blender's scaled F0, the conductor a mirror tinted by Base Color (Blender's F82 model
brightens it towards grazing angles; the mirror does not), the glass tinted by Base Color.
Exact only without specular (Specular IOR Level 0, Metallic 0, no transmission): then it is a
Lambertian diffuse. Otherwise it differs, by Blender's multiple-scattering energy
compensation among others, and says so once per material. Alpha < 1 is Mitsuba's `mask`
(exact: Cycles mixes a transparent BSDF by 1 - Alpha). Emission Color x Emission Strength is
the surface's radiance (exact). Coat, sheen, subsurface, thin film and anisotropy are dropped,
with a warning."""
from __future__ import annotations

from . import sockets
from .bsdfs import Surface, blend, conductor, dielectric, ior_from_f0, twosided
from .xml_writer import plugin

# Lobes mvpt leaves out: input name, value at which the lobe is absent.
DROPPED = (("Coat Weight", 0.0), ("Sheen Weight", 0.0), ("Subsurface Weight", 0.0),
           ("Thin Film Thickness", 0.0), ("Anisotropic", 0.0), ("Diffuse Roughness", 0.0))


def principled(materials, node, where: str) -> Surface:
    report = materials.report
    c = lambda name: materials._constant(node, name, where)  # noqa: E731 (a reader of constant inputs)
    for name, absent in DROPPED:
        if name in node.inputs and c(name) != absent:
            report.warn(f"{where}: Principled BSDF '{node.name}': {name} {c(name):g} is not converted")
    materials._ignored_normal(node, where)
    metallic = min(max(c("Metallic"), 0.0), 1.0)
    transmission = min(max(c("Transmission Weight"), 0.0), 1.0)
    roughness = min(max(c("Roughness"), 0.0), 1.0)
    level = max(c("Specular IOR Level"), 0.0)
    ior = max(c("IOR"), 1.0)
    f0 = ((ior - 1) / (ior + 1)) ** 2 * 2 * level
    exact = metallic == 0 and transmission == 0 and f0 == 0
    parts = []
    if metallic < 1 and transmission < 1:
        parts.append(_opaque(materials, node, where, roughness, f0))
    if metallic < 1 and transmission > 0:
        glass = dielectric(roughness, ior)
        materials.textures.colour(glass, "specular_transmittance", node, "Base Color", where)
        parts.append(glass)
    bsdf = parts[0] if len(parts) == 1 else blend(transmission, parts[0], parts[1]) if parts else None
    if metallic > 0:
        metal = conductor(roughness)
        materials.textures.colour(metal, "specular_reflectance", node, "Base Color", where)
        bsdf = twosided(metal) if bsdf is None else blend(metallic, bsdf, twosided(metal))
    if not exact:
        report.warn(f"{where}: Principled BSDF '{node.name}' is approximated (metallic {metallic:g}, "
                    f"transmission {transmission:g}, GGX alpha {roughness * roughness:.4g}, F0 {f0:.4g}); "
                    f"see docs/blender.md")
    alpha = min(max(c("Alpha"), 0.0), 1.0)
    if alpha < 1:
        mask = plugin("bsdf", "mask").float("opacity", alpha)
        mask.add(bsdf)
        bsdf = mask
    return Surface(bsdf, _emission(materials, node, where))


def _opaque(materials, node, where, roughness, f0):
    """The opaque dielectric base: Lambertian diffuse, under a GGX coat when F0 > 0."""
    if f0 <= 0:
        b = plugin("bsdf", "diffuse")
        materials.textures.colour(b, "reflectance", node, "Base Color", where)
        return twosided(b)
    if roughness <= 0:
        b = plugin("bsdf", "plastic")
    else:
        b = plugin("bsdf", "roughplastic").string("distribution", "ggx").float("alpha", max(roughness ** 2, 1e-4))
    b.float("int_ior", ior_from_f0(f0)).float("ext_ior", 1.0)
    materials.textures.colour(b, "diffuse_reflectance", node, "Base Color", where)
    tint = sockets.rgb(node, "Specular Tint")
    if tint != (1.0, 1.0, 1.0):
        b.rgb("specular_reflectance", tint)
    return twosided(b)


def _emission(materials, node, where):
    strength = materials._constant(node, "Emission Strength", where)
    if strength == 0:
        return None
    colour = materials.textures.constant_colour(node, "Emission Color", where)
    radiance = tuple(strength * x for x in colour)
    return radiance if any(radiance) else None
