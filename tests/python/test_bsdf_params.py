"""Parameters of the BSDF plugins: Mitsuba's presets and defaults, and clear
errors for invalid combinations."""
import numpy as np
import pytest

from bsdf_cases import direction, probe


def _normal_incidence_weight(xml):
    wo, w, pdf, typ = probe(xml).sample(0.0, 0.0, 1.0, 1, 0)
    return w[0]


def test_conductor_presets_match_mitsuba():
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    mi.set_log_level(mi.LogLevel.Error)
    import os
    ior_dir = os.path.join(os.path.dirname(mi.__file__), "data", "ior")
    names = sorted({f.rsplit(".", 2)[0] for f in os.listdir(ior_dir) if f.endswith(".spd")})
    assert len(names) > 40
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*direction(40, 10))
    for name in names + ["none"]:
        xml = f'<bsdf type="conductor"><string name="material" value="{name}"/></bsdf>'
        ours = probe(xml).sample(*direction(40, 10), 1, 0)[1][0]
        bs, w = mi.load_dict({"type": "conductor", "material": name}).sample(ctx, si, 0.5, mi.Point2f(0.5, 0.5))
        assert np.allclose(ours, np.array(w), rtol=1e-5, atol=1e-7), name


def test_defaults():
    # conductor / roughconductor: material "none" is a perfect mirror.
    assert np.allclose(_normal_incidence_weight('<bsdf type="conductor"/>'), 1.0)
    # dielectric: bk7 inside, air outside -> F(0) = ((n-1)/(n+1))^2 with n = 1.5046/1.000277.
    n = 1.5046 / 1.000277
    wo, w, pdf, typ = probe('<bsdf type="dielectric"/>').sample(0, 0, 1, 64, 0)
    assert np.allclose(pdf[typ.ravel() == 32], ((n - 1) / (n + 1)) ** 2, rtol=1e-5)
    # named IORs are case-insensitive, numbers accepted
    for v in ('<string name="int_ior" value="BK7"/>', '<float name="int_ior" value="1.5046"/>'):
        wo, w, pdf2, typ2 = probe(f'<bsdf type="dielectric">{v}</bsdf>').sample(0, 0, 1, 64, 0)
        assert np.allclose(pdf2, pdf)


@pytest.mark.parametrize("xml,needle", [
    ('<bsdf type="conductor"><string name="material" value="Gold"/></bsdf>', "unknown conductor material"),
    ('<bsdf type="conductor"><string name="material" value="Au"/><float name="eta" value="1"/></bsdf>',
     "either (eta, k) or material"),
    ('<bsdf type="dielectric"><string name="int_ior" value="glass"/></bsdf>', "unknown IOR name"),
    ('<bsdf type="dielectric"><float name="int_ior" value="-1"/></bsdf>', "positive"),
    ('<bsdf type="roughdielectric"><float name="int_ior" value="1"/><float name="ext_ior" value="1"/></bsdf>',
     "must differ"),
    ('<bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf>', "invalid distribution"),
    ('<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/></bsdf>', "both 'alpha_u' and 'alpha_v'"),
    ('<bsdf type="roughconductor"><float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/>'
     '<float name="alpha_v" value="0.2"/></bsdf>', "either 'alpha' or"),
    ('<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.2"/></bsdf>',
     "anisotropic"),
    ('<bsdf type="twosided"><bsdf type="dielectric"/></bsdf>', "transmission"),
    ('<bsdf type="twosided"/>', "nested"),
    ('<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/></bsdf>', "exactly two"),
    ('<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>', "weight"),
    ('<bsdf type="mask"/>', "nested bsdf"),
    ('<bsdf type="plastic"><float name="roughness" value="0.1"/></bsdf>', "roughness"),
])
def test_invalid_parameters_fail_clearly(xml, needle):
    with pytest.raises(Exception) as e:
        probe(xml)
    assert needle in str(e.value), str(e.value)
