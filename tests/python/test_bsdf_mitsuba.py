"""Our BSDFs against Mitsuba 3's own (scalar_rgb), loaded from the same XML.

* eval() and pdf() at random (wi, wo) pairs over the whole sphere must agree to
  a relative 1e-3 (plus a tiny absolute floor for float round-off near zero);
* sample() with identical random numbers must give the same direction, density,
  weight and lobe type: our samplers follow Mitsuba's mappings (visible-normal
  sampling per Heitz 2018 / Jakob 2014, lobe selection by u1), so this checks the
  sampling routines themselves, not just their distributions.

Known, documented differences (asserted as such where they matter):
* roughdielectric with sample_visible=false: Mitsuba samples a widened lobe but
  computes the weight as if it had not (a bias in Mitsuba); our weight is the
  exact eval/pdf. Directions and pdfs still agree; weights are not compared.
* Float round-off (different but equivalent arrangements of the formulas, our
  erfinv vs Dr.Jit's in the Beckmann inversion) leaves differences of ~1e-4 near
  grazing angles; a handful of samples exactly at a lobe-selection boundary may
  flip, so up to 0.5% of the samples may differ.
"""
import zlib

import numpy as np
import pytest

from bsdf_cases import direction, probe, random_directions

mi = pytest.importorskip("mitsuba")
mi.set_variant("scalar_rgb")

RTOL = 1e-3
ATOL = 1e-6


def _rough(kind, distr, alpha=None, au=None, av=None, visible=True, extra=""):
    a = (f'<float name="alpha" value="{alpha}"/>' if alpha is not None else
         f'<float name="alpha_u" value="{au}"/><float name="alpha_v" value="{av}"/>')
    return (f'<bsdf type="{kind}"><string name="distribution" value="{distr}"/>{a}'
            f'<boolean name="sample_visible" value="{str(visible).lower()}"/>{extra}</bsdf>')


SMOOTH = {  # BSDFs with a continuous part: eval/pdf compared
    "roughconductor-default": '<bsdf type="roughconductor"/>',
    "roughconductor-Au-ggx": _rough("roughconductor", "ggx", 0.25, extra='<string name="material" value="Au"/>'),
    "roughconductor-Cu-beckmann-aniso": _rough("roughconductor", "beckmann", au=0.1, av=0.4,
                                               extra='<string name="material" value="Cu"/>'),
    "roughconductor-etak-novis": _rough("roughconductor", "ggx", 0.3, visible=False,
                                        extra='<rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/>'
                                              '<rgb name="specular_reflectance" value="0.9, 0.8, 0.7"/>'),
    "roughdielectric-ggx": _rough("roughdielectric", "ggx", 0.3),
    "roughdielectric-beckmann-aniso": _rough("roughdielectric", "beckmann", au=0.15, av=0.35,
                                             extra='<string name="int_ior" value="water"/>'),
    "roughdielectric-ggx-novis": _rough("roughdielectric", "ggx", 0.2, visible=False,
                                        extra='<float name="int_ior" value="1.7"/><float name="ext_ior" value="1.2"/>'
                                              '<rgb name="specular_transmittance" value="0.5, 0.6, 0.7"/>'),
    "plastic": '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.5, 0.8"/></bsdf>',
    "plastic-nonlinear": '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.7, 0.5, 0.1"/>'
                         '<boolean name="nonlinear" value="true"/><float name="int_ior" value="1.9"/></bsdf>',
    "roughplastic": '<bsdf type="roughplastic"/>',
    "roughplastic-ggx": _rough("roughplastic", "ggx", 0.3,
                               extra='<rgb name="diffuse_reflectance" value="0.1, 0.4, 0.9"/>'),
    "roughplastic-beckmann-novis-nonlinear": _rough("roughplastic", "beckmann", 0.15, visible=False,
                                                    extra='<boolean name="nonlinear" value="true"/>'
                                                          '<string name="int_ior" value="diamond"/>'),
    "roughplastic-low-eta": _rough("roughplastic", "ggx", 0.2, extra='<float name="int_ior" value="1.1"/>'),
    "twosided-roughconductor": '<bsdf type="twosided">' + _rough("roughconductor", "ggx", 0.3) + '</bsdf>',
    "twosided-two": '<bsdf type="twosided"><bsdf type="diffuse"/>' + _rough("roughplastic", "ggx", 0.2) + '</bsdf>',
    "blendbsdf": '<bsdf type="blendbsdf"><float name="weight" value="0.3"/><bsdf type="diffuse"/>'
                 + _rough("roughconductor", "beckmann", 0.2) + '</bsdf>',
    "blendbsdf-delta": '<bsdf type="blendbsdf"><float name="weight" value="0.6"/>'
                       '<bsdf type="roughplastic"/><bsdf type="conductor"/></bsdf>',
    "mask": '<bsdf type="mask"><float name="opacity" value="0.7"/>' + _rough("roughconductor", "ggx", 0.4) + '</bsdf>',
    # A tilted normal (constant: the probe's uv is fixed), around an isotropic and an anisotropic lobe.
    "normalmap-roughplastic": '<bsdf type="normalmap"><rgb name="normalmap" value="0.7, 0.4, 0.85"/>'
                              + _rough("roughplastic", "ggx", 0.2) + '</bsdf>',
    "normalmap-roughconductor-aniso": '<bsdf type="normalmap"><rgb name="normalmap" value="0.35, 0.6, 0.8"/>'
                                      + _rough("roughconductor", "beckmann", au=0.1, av=0.4) + '</bsdf>',
}
DELTA_ONLY = {  # sample() only
    "conductor-default": '<bsdf type="conductor"/>',
    "conductor-Au": '<bsdf type="conductor"><string name="material" value="Au"/></bsdf>',
    "conductor-etak": '<bsdf type="conductor"><float name="eta" value="1.5"/><float name="k" value="2"/>'
                      '<rgb name="specular_reflectance" value="0.5, 0.7, 0.9"/></bsdf>',
    "conductor-spectrum": '<bsdf type="conductor"><spectrum name="eta" value="0.789"/>'
                          '<spectrum name="k" value="6.15"/></bsdf>',
    "dielectric": '<bsdf type="dielectric"/>',
    "dielectric-named": '<bsdf type="dielectric"><string name="int_ior" value="diamond"/>'
                        '<string name="ext_ior" value="water"/><rgb name="specular_transmittance" value="0.3, 0.6, 0.9"/></bsdf>',
    "thindielectric": '<bsdf type="thindielectric"><rgb name="specular_reflectance" value="0.8, 0.7, 0.6"/></bsdf>',
    "mask-dielectric": '<bsdf type="mask"><float name="opacity" value="0.3"/><bsdf type="dielectric"/></bsdf>',
    "normalmap-dielectric": '<bsdf type="normalmap"><rgb name="normalmap" value="0.6, 0.45, 0.9"/>'
                            '<bsdf type="dielectric"/></bsdf>',
}
TWO_SIDED_KINDS = ("roughdielectric", "dielectric", "thindielectric", "twosided", "mask", "normalmap")


def _mitsuba(xml):
    return mi.load_string(xml.replace("<bsdf ", '<bsdf version="3.0.0" ', 1))


def _si(wi):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.dp_du = mi.Vector3f(1, 0, 0)  # along the frame's s (normalmap's tangent)
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def _close(a, b, rtol=RTOL, atol=ATOL):
    return np.abs(a - b) <= rtol * np.maximum(np.abs(a), np.abs(b)) + atol


@pytest.mark.parametrize("name", sorted(SMOOTH))
def test_eval_pdf_match_mitsuba(name):
    xml = SMOOTH[name]
    ours, theirs = probe(xml), _mitsuba(xml)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    ctx = mi.BSDFContext()
    n_wo = 60
    # Mostly incidence from above (where one-sided BSDFs are non-zero), some from anywhere.
    wis = np.concatenate([random_directions(8, rng, upper_only=True), random_directions(4, rng)])
    checked = nonzero = 0
    for wi in wis:
        wos = random_directions(n_wo, rng)
        # Concentrate half the directions near the specular peak, where the lobe lives.
        peak = np.array([-wi[0], -wi[1], wi[2]], np.float32) + 0.3 * rng.standard_normal((n_wo // 2, 3)).astype(np.float32)
        wos[: n_wo // 2] = peak / np.linalg.norm(peak, axis=1, keepdims=True)
        f_ours = ours.eval(*wi, wos)
        p_ours = ours.pdf(*wi, wos).ravel()
        si = _si(wi)
        for j, wo in enumerate(wos):
            v = mi.Vector3f(*[float(x) for x in wo])
            f_mi = np.array(theirs.eval(ctx, si, v), dtype=np.float64)
            p_mi = float(theirs.pdf(ctx, si, v))
            assert np.all(_close(f_ours[j], f_mi)), f"{name}: eval wi={wi} wo={wo}: ours {f_ours[j]} mitsuba {f_mi}"
            assert _close(p_ours[j], p_mi), f"{name}: pdf wi={wi} wo={wo}: ours {p_ours[j]} mitsuba {p_mi}"
            checked += 1
            nonzero += p_mi > 0
    assert nonzero > checked // 10, f"{name}: too few non-zero comparisons ({nonzero}/{checked})"


def _sample_pairs(name, xml, n=400):
    ours, theirs = probe(xml), _mitsuba(xml)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    below = any(k in xml for k in TWO_SIDED_KINDS)
    wis = [direction(t, p, below=b) for t, p, b in [(15, 20, False), (55, 140, False), (78, -60, False)]
           + ([(35, 80, True), (70, 250, True)] if below else [])]
    ctx = mi.BSDFContext()
    for wi in wis:
        u = rng.random((n, 3)).astype(np.float32)
        wo, w, pdf, typ = ours.sample_u(*wi, u)
        pdf, typ = pdf.ravel(), typ.ravel()
        si = _si(wi)
        for i in range(n):
            bs, w_mi = theirs.sample(ctx, si, float(u[i, 0]), mi.Point2f(float(u[i, 1]), float(u[i, 2])))
            yield wi, u[i], (wo[i], w[i], float(pdf[i]), int(typ[i])), (
                np.array(bs.wo), np.array(w_mi, dtype=np.float64), float(bs.pdf), int(bs.sampled_type))


@pytest.mark.parametrize("name", sorted(SMOOTH) + sorted(DELTA_ONLY))
def test_sample_matches_mitsuba(name):
    xml = {**SMOOTH, **DELTA_ONLY}[name]
    compare_weight = "novis" not in name or "roughdielectric" not in name
    wo_tol = 1e-3
    n = bad = 0
    first_bad = None
    for wi, u, (wo, w, pdf, typ), (wo_m, w_m, pdf_m, typ_m) in _sample_pairs(name, xml):
        valid_ours, valid_mi = w.max() > 0 and pdf > 0, w_m.max() > 0 and pdf_m > 0
        if not valid_ours and not valid_mi:
            continue
        n += 1
        ok = valid_ours == valid_mi and typ == typ_m and np.all(np.abs(wo - wo_m) <= wo_tol)
        ok = ok and _close(pdf, pdf_m)
        if compare_weight:
            ok = ok and np.all(_close(w, w_m, atol=1e-5))
        if not ok:
            bad += 1
            first_bad = first_bad or (wi, u, (wo, w, pdf, typ), (wo_m, w_m, pdf_m, typ_m))
    assert n > 100, f"{name}: only {n} valid samples"
    # Samples at lobe-selection or validity boundaries may legitimately flip (see above).
    assert bad <= 0.005 * n, f"{name}: {bad}/{n} samples differ; first: {first_bad}"
