"""Tests of the `principled` and `principledthin` BSDFs: χ² of sample against pdf,
weight = eval/pdf, eval and pdf against Mitsuba 3's plugins, and a small render
against Mitsuba."""
from __future__ import annotations

import numpy as np
import pytest

from mvpt import _probes

from chi2 import chi2_test  # the shared harness, tests/python/chi2.py


# --------------------------------------------------------------------------- helpers

def principled_xml(params: dict, type_: str = "principled") -> str:
    body = ""
    for k, v in params.items():
        if isinstance(v, (tuple, list)):
            body += f'<rgb name="{k}" value="{v[0]}, {v[1]}, {v[2]}"/>'
        else:
            body += f'<float name="{k}" value="{v}"/>'
    return f'<bsdf type="{type_}">{body}</bsdf>'


def mitsuba_dict(params: dict, type_: str = "principled") -> dict:
    d = {"type": type_}
    for k, v in params.items():
        d[k] = {"type": "rgb", "value": list(v)} if isinstance(v, (tuple, list)) else v
    return d


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return (v / np.linalg.norm(v)).astype(np.float32)


def random_dirs(rng, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return (v / np.linalg.norm(v, axis=1)[:, None]).astype(np.float32)


# --------------------------------------------------------------------------- χ²

# Parameter sets exercising each lobe, with moderate roughness so the pdf is smooth
# enough for grid integration; incident directions from the front and (for
# transmission) from inside.
CHI2_CASES = [
    ("principled", "default", {}, (0.3, 0.2, 0.8)),
    ("principled", "metallic", {"metallic": 0.8, "roughness": 0.35, "base_color": (0.9, 0.6, 0.2)}, (0.6, -0.1, 0.5)),
    ("principled", "spec_trans_front", {"spec_trans": 0.7, "roughness": 0.35}, (0.4, 0.3, 0.6)),
    ("principled", "spec_trans_back", {"spec_trans": 0.7, "roughness": 0.35, "eta": 1.4}, (0.3, -0.4, -0.6)),
    ("principled", "clearcoat", {"clearcoat": 0.9, "clearcoat_gloss": 0.3, "roughness": 0.6}, (-0.5, 0.2, 0.4)),
    ("principled", "sheen", {"sheen": 0.8, "sheen_tint": 0.5, "base_color": (0.2, 0.5, 0.8)}, (0.1, 0.7, 0.3)),
    ("principled", "anisotropic", {"anisotropic": 0.8, "roughness": 0.4, "metallic": 0.5}, (0.5, 0.5, 0.4)),
    ("principled", "all", {"metallic": 0.2, "spec_trans": 0.4, "clearcoat": 0.6, "clearcoat_gloss": 0.2,
                           "sheen": 0.3, "anisotropic": 0.5, "spec_tint": 0.3, "flatness": 0.4, "roughness": 0.45,
                           "base_color": (0.9, 0.5, 0.2)}, (-0.2, 0.6, 0.5)),
    ("principledthin", "thin_default", {}, (0.3, 0.2, 0.8)),
    ("principledthin", "thin_spec_trans", {"spec_trans": 0.7, "roughness": 0.4, "eta": 1.33}, (0.5, -0.2, 0.6)),
    ("principledthin", "thin_diff_trans_back", {"diff_trans": 1.2, "spec_trans": 0.4, "roughness": 0.5,
                                                "anisotropic": 0.6}, (-0.3, 0.4, -0.5)),
    ("principledthin", "thin_all", {"diff_trans": 0.6, "spec_trans": 0.5, "sheen": 0.5, "flatness": 0.5,
                                    "spec_tint": 0.4, "roughness": 0.35, "base_color": (0.3, 0.7, 0.2)},
     (0.1, 0.6, 0.3)),
]


@pytest.mark.parametrize("type_,name,params,wi", CHI2_CASES, ids=[c[1] for c in CHI2_CASES])
def test_chi2_sample_matches_pdf(type_, name, params, wi):
    probe = _probes.BsdfProbe(principled_xml(params, type_))
    wi = unit(wi)

    seed = sum(map(ord, name))  # a different random stream per case: independent tests (Šidák)

    def sample_fn(n):
        wo, _, pdf, _ = probe.sample(*wi, n, seed)
        return wo, np.asarray(pdf).reshape(-1) > 0

    def pdf_fn(wo):
        return np.asarray(probe.pdf(*wi, np.ascontiguousarray(wo, dtype=np.float32))).reshape(-1)

    ok, p, msg = chi2_test(sample_fn, pdf_fn, n_samples=1_000_000, n_tests=len(CHI2_CASES))
    assert ok, f"{name}: {msg}"


# --------------------------------------------------------------------------- weight

@pytest.mark.parametrize("type_,name,params,wi", CHI2_CASES, ids=[c[1] for c in CHI2_CASES])
def test_weight_is_eval_over_pdf(type_, name, params, wi):
    probe = _probes.BsdfProbe(principled_xml(params, type_))
    wi = unit(wi)
    wo, weight, pdf, stype = probe.sample(*wi, 20000, 3)
    pdf = np.asarray(pdf).reshape(-1)
    ok = pdf > 0
    assert ok.mean() > 0.5, "most samples should succeed"
    wo, weight, pdf = wo[ok], weight[ok], pdf[ok]
    ev = probe.eval(*wi, np.ascontiguousarray(wo))
    pd = np.asarray(probe.pdf(*wi, np.ascontiguousarray(wo))).reshape(-1)
    np.testing.assert_allclose(pdf, pd, rtol=1e-5)
    np.testing.assert_allclose(weight, ev / pd[:, None], rtol=1e-4, atol=1e-7)
    # Transmission samples go to the other side, reflections stay.
    trans = (stype[ok] == 16) | (stype[ok] == 4)  # BsdfGlossyTransmission, BsdfDiffuseTransmission
    assert np.all(wo[trans, 2] * wi[2] < 0) and np.all(wo[~trans, 2] * wi[2] > 0)


# --------------------------------------------------------------------------- Mitsuba

MITSUBA_CASES = CHI2_CASES + [
    ("principled", "sharp_clearcoat", {"clearcoat": 1.0, "clearcoat_gloss": 0.9, "roughness": 0.1}, None),
    ("principled", "glass_like", {"spec_trans": 1.0, "eta": 1.33, "roughness": 0.08}, None),
    ("principled", "specular_tint_flat", {"specular": 0.8, "spec_tint": 0.7, "flatness": 0.9, "sheen": 0.5,
                                          "base_color": (0.1, 0.7, 0.3)}, None),
    ("principled", "rgb_valued_weights", {"metallic": (0.1, 0.5, 0.9), "roughness": (0.2, 0.3, 0.4)}, None),
    # The floor tiles of bitterli-staircase2 (its bitmap base colour replaced by an rgb).
    ("principled", "staircase_tiles", {"base_color": (0.6, 0.5, 0.4), "spec_tint": 0.0, "spec_trans": 0.0,
                                       "metallic": 0.745455, "anisotropic": 0.0, "roughness": 0.5, "sheen": 0.0,
                                       "sheen_tint": 0.5, "clearcoat": 0.0, "clearcoat_gloss": 0.173205,
                                       "specular": 0.5}, None),
    ("principledthin", "thin_sharp", {"spec_trans": 0.9, "roughness": 0.1, "eta": 1.6, "spec_tint": 0.5,
                                      "base_color": (0.9, 0.2, 0.4)}, None),
    ("principledthin", "thin_full_diff_trans", {"diff_trans": 2.0, "sheen": 0.7, "sheen_tint": 0.6}, None),
]


@pytest.mark.parametrize("type_,name,params,wi", MITSUBA_CASES, ids=[c[1] for c in MITSUBA_CASES])
def test_eval_pdf_match_mitsuba(type_, name, params, wi):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    probe = _probes.BsdfProbe(principled_xml(params, type_))
    bsdf = mi.load_dict(mitsuba_dict(params, type_))
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.uv = mi.Point2f(0.5, 0.5)
    rng = np.random.default_rng(sum(map(ord, name)))
    wis = random_dirs(rng, 12)
    n_checked = 0
    for wi_ in wis:
        if abs(wi_[2]) < 1e-2:
            continue
        # Random directions plus the mirror direction, where the sharp lobes peak.
        wos = np.concatenate([random_dirs(rng, 120), np.array([[-wi_[0], -wi_[1], wi_[2]]], np.float32)])
        wos = wos[np.abs(wos[:, 2]) > 1e-3]
        f = probe.eval(*wi_, wos)
        p = np.asarray(probe.pdf(*wi_, wos)).reshape(-1)
        si.wi = mi.Vector3f(*map(float, wi_))
        f_ref = np.array([list(bsdf.eval(ctx, si, mi.Vector3f(*map(float, w)))) for w in wos])
        p_ref = np.array([bsdf.pdf(ctx, si, mi.Vector3f(*map(float, w))) for w in wos])
        # Relative 1e-3, with an absolute floor far below any visible contribution.
        np.testing.assert_allclose(f, f_ref, rtol=1e-3, atol=1e-6, err_msg=f"eval, wi={wi_}")
        np.testing.assert_allclose(p, p_ref, rtol=1e-3, atol=1e-6, err_msg=f"pdf, wi={wi_}")
        n_checked += len(wos)
    assert n_checked > 1000


def test_parameter_errors():
    with pytest.raises(ValueError, match="either 'eta' or 'specular'"):
        _probes.BsdfProbe('<bsdf type="principled"><float name="eta" value="1.5"/>'
                        '<float name="specular" value="0.5"/></bsdf>')
    with pytest.raises(ValueError, match="roughnes"):
        _probes.BsdfProbe('<bsdf type="principled"><float name="roughnes" value="0.5"/></bsdf>')


# --------------------------------------------------------------------------- render

RENDER_SCENE = """
<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, -3.2, 2.2" target="0, 0, 0" up="0, 0, 1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle">
    <bsdf type="principled">
      <rgb name="base_color" value="0.7, 0.4, 0.2"/>
      <float name="roughness" value="0.3"/>
      <float name="metallic" value="0.3"/>
      <float name="clearcoat" value="0.5"/>
      <float name="sheen" value="0.4"/>
      <float name="anisotropic" value="0.3"/>
      <float name="spec_trans" value="0.2"/>
    </bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="180"/><translate x="0.4" y="0.8" z="1.6"/></transform>
    <emitter type="area"><rgb name="radiance" value="6, 6, 6"/></emitter>
  </shape>
</scene>
"""


def test_render_matches_mitsuba():
    """A principled rectangle under a small area light, 32x32 at 1024 spp (standard
    error of each image mean ~0.2%): image means agree with Mitsuba within 1%."""
    mi = pytest.importorskip("mitsuba")
    import mvpt

    mi.set_variant("scalar_rgb")
    ref = np.array(mi.render(mi.load_string(RENDER_SCENE.format(spp=1024)), seed=1))
    scene = mvpt.load_string(RENDER_SCENE.format(spp=1024))
    img = next(iter(mvpt.render(scene, seed=3).images.values()))
    m_ref, m = ref.mean(axis=(0, 1)), img.mean(axis=(0, 1))
    assert np.all(np.abs(m - m_ref) <= 0.01 * m_ref), f"means {m} vs Mitsuba {m_ref}"


from shared_data import require_shared  # noqa: E402


SPHERE_SCENE = """
<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="35"/>
    <transform name="to_world"><lookat origin="-4, 0, 0.6" target="0, 0, 0" up="0, 0, 1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="obj">
    <string name="filename" value="{mesh}"/>
    {bsdf}
  </shape>
  <shape type="cube">
    <transform name="to_world"><scale x="3" y="3" z="0.1"/><translate z="-1.1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="2"/><rotate y="1" angle="150"/><translate x="1.5" y="0.5" z="2.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="2, 2, 2"/></emitter>
  </shape>
</scene>
"""

SPHERE_BSDFS = {
    "principled": principled_xml({"base_color": (0.3, 0.6, 0.8), "roughness": 0.3, "spec_trans": 0.5,
                                  "metallic": 0.2, "clearcoat": 0.6, "sheen": 0.5, "anisotropic": 0.4}),
    "principledthin": principled_xml({"base_color": (0.7, 0.2, 0.1), "roughness": 0.25, "spec_trans": 0.5,
                                      "diff_trans": 0.8, "sheen": 0.4, "eta": 1.4}, "principledthin"),
}


@pytest.mark.parametrize("type_", list(SPHERE_BSDFS))
def test_sphere_render_matches_mitsuba(type_):
    """An OBJ sphere (closed: refraction through it) over a diffuse slab, 32x32:
    image means agree with Mitsuba within 1%."""
    mi = pytest.importorskip("mitsuba")
    import mvpt

    mesh = require_shared("m3data-testsuite/common/meshes/sphere.obj")
    # 1024 spp: the standard error of each image mean is ~0.3%, so 1% is > 2.5 sigma of the difference.
    xml = SPHERE_SCENE.format(spp=1024, mesh=mesh, bsdf=SPHERE_BSDFS[type_])
    try:  # same plugins, vectorised: faster than scalar_rgb on this scene
        mi.set_variant("llvm_ad_rgb")
    except Exception:
        mi.set_variant("scalar_rgb")
    ref = np.array(mi.render(mi.load_string(xml), seed=1))
    img = next(iter(mvpt.render(mvpt.load_string(xml), seed=5).images.values()))
    m_ref, m = ref.mean(axis=(0, 1)), img.mean(axis=(0, 1))
    assert np.all(np.abs(m - m_ref) <= 0.01 * m_ref), f"means {m} vs Mitsuba {m_ref}"


# --------------------------------------------------------------------------- textures

def _checker(name: str, c0: float, c1: float, scale: float) -> str:
    return (f'<texture name="{name}" type="checkerboard"><transform name="to_uv"><scale x="{scale}" y="{scale}"/>'
            f'</transform><float name="color0" value="{c0}"/><float name="color1" value="{c1}"/></texture>')


# The textured materials of Mitsuba's test suite (bsdf_spheres/test_texturedprincipled*_path.xml).
TEXTURED = {
    "principled": '<bsdf type="principled"><rgb name="base_color" value="0.2, 0.8, 0.1"/>'
                  '<float name="roughness" value="0.15"/>' + _checker("anisotropic", 0.05, 0.8, 5)
                  + _checker("metallic", 0.7, 0.1, 5) + _checker("clearcoat", 0.9, 0.1, 2.5)
                  + _checker("sheen", 0.2, 0.9, 2.5) + _checker("spec_trans", 0.7, 0.1, 5)
                  + '<float name="specular" value="0.7"/></bsdf>',
    "principledthin": '<bsdf type="principledthin"><rgb name="base_color" value="0.7, 0.1, 0.1"/>'
                      + _checker("anisotropic", 0.05, 0.8, 5) + _checker("spec_trans", 0.2, 0.8, 5)
                      + _checker("diff_trans", 0.4, 1.4, 2.5) + _checker("sheen", 0.2, 0.9, 2.5)
                      + '<float name="eta" value="1.33"/></bsdf>',
}


@pytest.mark.parametrize("type_", list(TEXTURED))
def test_textured_parameters_match_mitsuba(type_):
    """Texture-valued lobe weights (checkerboards) evaluated per uv, against Mitsuba."""
    mi = pytest.importorskip("mitsuba")
    xml = TEXTURED[type_]
    try:
        _probes.BsdfProbe(xml)
    except ValueError as e:
        if "checkerboard" in str(e):
            pytest.skip(f"no checkerboard texture plugin in this build: {e}")
        raise
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_string(f'<bsdf version="3.0.0" {xml[len("<bsdf "):]}')
    ctx = mi.BSDFContext()
    rng = np.random.default_rng(11)
    # uv at cell centres of the finest checkerboard (period 1/5 in uv: cells 0.1 wide).
    for u, v in [(0.05, 0.05), (0.15, 0.05), (0.05, 0.15), (0.25, 0.35), (0.55, 0.85), (0.95, 0.45)]:
        probe = _probes.BsdfProbe(xml, u, v)
        si = mi.SurfaceInteraction3f()
        si.uv = mi.Point2f(u, v)
        for wi in random_dirs(rng, 3):
            wos = random_dirs(rng, 60)
            si.wi = mi.Vector3f(*map(float, wi))
            f = probe.eval(*wi, wos)
            p = np.asarray(probe.pdf(*wi, wos)).reshape(-1)
            f_ref = np.array([list(bsdf.eval(ctx, si, mi.Vector3f(*map(float, w)))) for w in wos])
            p_ref = np.array([bsdf.pdf(ctx, si, mi.Vector3f(*map(float, w))) for w in wos])
            np.testing.assert_allclose(f, f_ref, rtol=1e-3, atol=1e-6, err_msg=f"eval at uv=({u}, {v})")
            np.testing.assert_allclose(p, p_ref, rtol=1e-3, atol=1e-6, err_msg=f"pdf at uv=({u}, {v})")
