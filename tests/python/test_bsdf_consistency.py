"""Internal consistency of the BSDFs: sample weights equal eval/pdf, delta
lobes are discrete and land where they must, roughness() values, the phong
formula, and white-furnace energy checks."""
import numpy as np
import pytest

from bsdf_cases import DELTA, FLAGS, direction, probe

ROUGH = {
    "roughconductor-ggx-aniso": '<bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
                                '<float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.5"/></bsdf>',
    "roughconductor-beckmann-novis": '<bsdf type="roughconductor"><float name="alpha" value="0.3"/>'
                                     '<boolean name="sample_visible" value="false"/></bsdf>',
    "roughdielectric-ggx": '<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>'
                           '<float name="alpha" value="0.3"/></bsdf>',
    "roughdielectric-beckmann-novis": '<bsdf type="roughdielectric"><float name="alpha" value="0.25"/>'
                                      '<boolean name="sample_visible" value="false"/></bsdf>',
    "roughplastic": '<bsdf type="roughplastic"><string name="distribution" value="ggx"/></bsdf>',
    "plastic": '<bsdf type="plastic"/>',
    "phong": '<bsdf type="phong"><float name="exponent" value="12"/></bsdf>',
    "twosided": '<bsdf type="twosided"><bsdf type="roughconductor"/></bsdf>',
    "blendbsdf": '<bsdf type="blendbsdf"><float name="weight" value="0.4"/><bsdf type="diffuse"/>'
                 '<bsdf type="roughconductor"/></bsdf>',
    "mask": '<bsdf type="mask"><bsdf type="roughplastic"/></bsdf>',
}
WIS = [direction(20, 30), direction(65, 200), direction(40, 100, below=True)]


@pytest.mark.parametrize("name", sorted(ROUGH))
def test_weight_is_eval_over_pdf(name):
    pr = probe(ROUGH[name])
    n_checked = 0
    for wi in WIS:
        wo, w, pdf, typ = pr.sample(*wi, 4000, 3)
        typ = typ.astype(np.uint32).ravel()
        pdf = pdf.ravel()
        keep = (w.max(axis=1) > 0) & ((typ & DELTA) == 0)
        if not keep.any():
            continue
        wo_k = np.ascontiguousarray(wo[keep])
        f = pr.eval(*wi, wo_k)
        p = pr.pdf(*wi, wo_k).ravel()
        # pdf() recomputes the half-vector from (wi, wo) in float32: ~1e-4 relative round-off
        # near grazing refraction, hence the 1e-3 tolerance (as in the Mitsuba comparisons).
        assert np.allclose(p, pdf[keep], rtol=1e-3, atol=1e-7), f"{name}: sampled pdf != pdf()"
        assert np.allclose(w[keep], f / p[:, None], rtol=1e-3, atol=1e-6), f"{name}: weight != eval/pdf"
        n_checked += int(keep.sum())
    assert n_checked > 3000


def test_one_sided_bsdfs_are_black_from_below():
    wi = direction(30, 10, below=True)
    for xml in ['<bsdf type="conductor"/>', '<bsdf type="roughconductor"/>', '<bsdf type="plastic"/>',
                '<bsdf type="roughplastic"/>', '<bsdf type="phong"/>']:
        wo, w, pdf, typ = probe(xml).sample(*wi, 200, 1)
        assert np.all(w == 0), xml


def _reflect(wi):
    return np.array([-wi[0], -wi[1], wi[2]])


def test_delta_lobes_are_discrete_and_exact():
    eta = 1.5046 / 1.000277  # bk7 / air, the dielectric defaults
    for below in (False, True):
        wi = np.array(direction(35, 70, below=below))
        wo, w, pdf, typ = probe('<bsdf type="dielectric"/>').sample(*wi, 2000, 5)
        typ = typ.astype(np.uint32).ravel()
        refl = typ == FLAGS["delta_reflection"]
        trans = typ == FLAGS["delta_transmission"]
        assert refl.any() and trans.any() and np.all(refl | trans)
        assert np.allclose(wo[refl], _reflect(wi), atol=1e-6)
        # Snell: tangential components scale by -1/eta (relative to the side of wi), z flips side.
        e = eta if not below else 1.0 / eta
        t = wo[trans]
        assert np.allclose(t[:, :2], -wi[:2] / e, atol=1e-5)
        assert np.all(np.sign(t[:, 2]) == -np.sign(wi[2]))
        assert np.allclose(np.linalg.norm(t, axis=1), 1.0, atol=1e-5)
        # The discrete probabilities are F and 1 - F, and the empirical split matches.
        F = pdf.ravel()[refl][0]
        assert np.allclose(pdf.ravel()[trans], 1 - F, atol=1e-6)
        assert abs(refl.mean() - F) < 5 * np.sqrt(F * (1 - F) / 2000) + 1e-3
    wi = np.array(direction(50, 10))
    wo, w, pdf, typ = probe('<bsdf type="thindielectric"/>').sample(*wi, 1000, 5)
    typ = typ.astype(np.uint32).ravel()
    null = typ == FLAGS["null"]
    assert null.any() and np.allclose(wo[null], -wi, atol=1e-7) and np.allclose(w[null], 1.0)
    wo, w, pdf, typ = probe('<bsdf type="mask"><float name="opacity" value="0.25"/><bsdf type="diffuse"/></bsdf>'
                            ).sample(*wi, 4000, 5)
    null = typ.astype(np.uint32).ravel() == FLAGS["null"]
    assert np.allclose(wo[null], -wi) and np.allclose(pdf.ravel()[null], 0.75) and np.allclose(w[null], 1.0)
    assert abs(null.mean() - 0.75) < 5 * np.sqrt(0.75 * 0.25 / 4000)
    # Delta BSDFs have no continuous part.
    for xml in ['<bsdf type="conductor"/>', '<bsdf type="dielectric"/>', '<bsdf type="thindielectric"/>']:
        pr = probe(xml)
        wos = np.ascontiguousarray(np.array([_reflect(wi)], np.float32))
        assert np.all(pr.eval(*wi, wos) == 0) and np.all(pr.pdf(*wi, wos) == 0)


@pytest.mark.parametrize("xml,expected", [
    ('<bsdf type="diffuse"/>', 1.0),
    ('<bsdf type="conductor"/>', 0.0),
    ('<bsdf type="dielectric"/>', 0.0),
    ('<bsdf type="thindielectric"/>', 0.0),
    ('<bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>', 0.3),
    ('<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.5"/></bsdf>', 0.3),
    ('<bsdf type="roughdielectric"/>', 0.1),
    ('<bsdf type="roughplastic"><float name="alpha" value="0.2"/></bsdf>', 0.2),
    ('<bsdf type="plastic"/>', 1.0),
    ('<bsdf type="phong"/>', np.sqrt(2 / 32)),
    ('<bsdf type="phong"><float name="exponent" value="98"/></bsdf>', np.sqrt(2 / 100)),
    ('<bsdf type="twosided"><bsdf type="roughconductor"><float name="alpha" value="0.4"/></bsdf></bsdf>', 0.4),
    ('<bsdf type="mask"><bsdf type="diffuse"/></bsdf>', 1.0),
])
def test_roughness(xml, expected):
    assert probe(xml).roughness() == pytest.approx(expected, rel=1e-6, abs=1e-7)


def test_phong_matches_formula():
    kd, ks, e = np.array([0.1, 0.3, 0.5]), np.array([0.4, 0.2, 0.1]), 17.0
    pr = probe('<bsdf type="phong"><float name="exponent" value="17"/><rgb name="diffuse_reflectance" '
               'value="0.1, 0.3, 0.5"/><rgb name="specular_reflectance" value="0.4, 0.2, 0.1"/></bsdf>')
    rng = np.random.default_rng(5)
    wi = np.array(direction(40, 30))
    wo = rng.normal(size=(500, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    cos_a = np.maximum(0, wo @ _reflect(wi))
    f = kd / np.pi + ks[None, :] * ((e + 2) / (2 * np.pi) * cos_a ** e)[:, None]
    expected = np.where(wo[:, 2:3] > 0, f * wo[:, 2:3], 0.0)
    got = pr.eval(*wi, np.ascontiguousarray(wo, dtype=np.float32))
    assert np.allclose(got, expected, rtol=1e-4, atol=1e-7)
    # The specular lobe is chosen with probability mean(ks) / (mean(ks) + mean(kd)).
    p_spec = ks.mean() / (ks.mean() + kd.mean())
    pdf_expected = np.where(wo[:, 2] > 0, p_spec * (e + 1) / (2 * np.pi) * cos_a ** e
                            + (1 - p_spec) * np.maximum(wo[:, 2], 0) / np.pi, 0.0)
    assert np.allclose(pr.pdf(*wi, np.ascontiguousarray(wo, dtype=np.float32)).ravel(), pdf_expected,
                       rtol=1e-4, atol=1e-7)


N_SAMPLES = 100_000


def _albedo(xml, wi, importance=False):
    wo, w, pdf, typ = probe(xml).sample(*wi, N_SAMPLES, 11, importance)
    m = w.mean(axis=1)
    return m.mean(), m.std() / np.sqrt(len(m))


@pytest.mark.parametrize("xml", [
    '<bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.6"/></bsdf>',
    '<bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.9"/>'
    '<boolean name="sample_visible" value="false"/></bsdf>',
    '<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.5"/></bsdf>',
    '<bsdf type="roughdielectric"><float name="alpha" value="0.3"/><boolean name="sample_visible" value="false"/></bsdf>',
    '<bsdf type="phong"><float name="exponent" value="2"/><float name="diffuse_reflectance" value="0.5"/>'
    '<float name="specular_reflectance" value="0.5"/></bsdf>',
    '<bsdf type="roughplastic"><float name="diffuse_reflectance" value="1"/><float name="alpha" value="0.4"/></bsdf>',
])
@pytest.mark.parametrize("theta", [5, 45, 85])
def test_white_furnace_at_most_one(xml, theta):
    """Unit-reflectance BSDFs reflect (and transmit) at most all energy."""
    for below in ((False, True) if "dielectric" in xml else (False,)):
        mean, sem = _albedo(xml, direction(theta, 30, below=below), importance=True)
        assert mean <= 1.0 + 5 * sem + 1e-4, f"albedo {mean} +- {sem}"
        assert mean > 0.3


@pytest.mark.parametrize("theta", [0, 30, 60, 89])
def test_smooth_dielectric_is_lossless(theta):
    """R + T = 1 for the smooth dielectric (adjoint mode: no 1/eta^2 radiance scaling)."""
    for below in (False, True):
        wi = direction(theta, 0, below=below)
        wo, w, pdf, typ = probe('<bsdf type="dielectric"/>').sample(*wi, 1000, 2, True)
        assert np.allclose(w, 1.0, atol=1e-6)  # every sample carries exactly its lobe's share
    for xml in ['<bsdf type="conductor"/>', '<bsdf type="thindielectric"/>']:
        wo, w, pdf, typ = probe(xml).sample(*direction(theta, 0), 1000, 2)
        assert np.allclose(w, 1.0, atol=1e-6), xml


@pytest.mark.parametrize("theta", [10, 60])
def test_plastic_white_furnace(theta):
    """With a white base, (rough) plastic conserves energy up to its approximations:
    the fitted diffuse Fresnel reflectance (plastic, ~0.1%) and the tabulated rough
    transmittance and single-scattering microfacet coat (roughplastic, a few %)."""
    mean, sem = _albedo('<bsdf type="plastic"><float name="diffuse_reflectance" value="1"/></bsdf>',
                        direction(theta), importance=True)
    assert abs(mean - 1.0) < 0.01 + 5 * sem
    mean, sem = _albedo('<bsdf type="roughplastic"><float name="diffuse_reflectance" value="1"/></bsdf>',
                        direction(theta), importance=True)
    assert 0.9 < mean < 1.0 + 5 * sem
