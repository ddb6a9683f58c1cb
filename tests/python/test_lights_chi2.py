"""Chi-square tests: directions drawn by Light::sample_li against pdf_li, for
area lights on meshes and for environment maps (synthetic and a real one).

Environment maps use the shared full-sphere harness (chi2.py). Area lights
subtend a small cone with sharp edges, which a full-sphere grid resolves with a
handful of cells and whose Gauss-Legendre cell integrals miss slivers of the
support; they use light_chi2.py (a grid on the cone around the light, cell
integrals refined at the silhouette)."""

import numpy as np
import pytest

from mvpt import _core, _probes
from chi2 import chi2_test
from light_chi2 import chi2_directions, sidak_alpha

# Family-wise level 1% over all chi-square tests in this file (Sidak).
N_TESTS = 7
ALPHA = sidak_alpha(0.01, N_TESTS)


from shared_data import shared_scenes  # noqa: E402  (also used by test_lights_render)


def sampled_dirs(probe, ref, n, seed=1):
    d, w, pdf, _ = probe.sample_li(ref, n, seed=seed)
    ok = (w.max(axis=1) > 0) & (pdf > 0)
    d = d.copy()
    d[~ok] = 0
    return d, w, pdf, ok


def check_weights(probe, ref, d, w, pdf, ok):
    """sample_li's weight and pdf agree with eval and pdf_li at the sampled directions."""
    pdf_again = probe.pdf_li(ref, np.ascontiguousarray(d[ok][:2000]))
    np.testing.assert_allclose(pdf_again, pdf[ok][:2000], rtol=2e-3)
    L = probe.eval(ref, np.ascontiguousarray(d[ok][:2000]))
    np.testing.assert_allclose(w[ok][:2000], L / pdf[ok][:2000, None], rtol=2e-3)


RECT = """<shape type="rectangle">
  <transform name="to_world"><scale x="0.7" y="0.4"/><rotate x="1" angle="150"/><translate x="0.3" y="0.1" z="2"/></transform>
  <emitter type="area"><rgb name="radiance" value="2, 3, 4"/></emitter>
</shape>"""


@pytest.mark.parametrize("ref", [(0.0, 0.0, 0.0), (1.5, -1.0, 0.5), (0.2, 0.3, 1.6)])
def test_area_rectangle(ref):
    probe = _probes.LightProbe(RECT)
    n = 200_000
    d, w, pdf, ok = sampled_dirs(probe, ref, n)
    check_weights(probe, ref, d, w, pdf, ok)
    # Frame around the direction to the light's centre; the cone through its
    # corners (convex polygon) bounds the support.
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * [0.7, 0.4]
    c30, s30 = np.cos(np.radians(150)), np.sin(np.radians(150))
    pts = np.stack([corners[:, 0], corners[:, 1] * c30, corners[:, 1] * s30], 1) + [0.3, 0.1, 2]
    axis = np.array([0.3, 0.1, 2]) - ref
    axis /= np.linalg.norm(axis)
    v = pts - ref
    cos_min = float(np.min(v @ axis / np.linalg.norm(v, axis=1))) - 0.01
    p, msg = chi2_directions(d, lambda x: probe.pdf_li(ref, x), axis=axis, cos_min=cos_min, res=(32, 16))
    assert p > ALPHA, msg


def test_area_cube_mesh():
    """Closed emitter: area sampling picks back faces half of the time (failed samples)."""
    xml = """<shape type="cube"><transform name="to_world"><scale value="0.5"/><rotate y="1" angle="20"/>
             <translate z="2.5"/></transform><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"""
    probe = _probes.LightProbe(xml)
    ref = (0.4, 0.3, 0.0)
    d, w, pdf, ok = sampled_dirs(probe, ref, 200_000)
    assert 0.3 < ok.mean() < 0.7
    check_weights(probe, ref, d, w, pdf, ok)
    axis = np.array([0, 0, 2.5]) - ref
    dist = np.linalg.norm(axis)
    cos_min = float(np.cos(np.arcsin(min(1.0, 0.5 * np.sqrt(3) / dist)))) - 0.01
    p, msg = chi2_directions(d, lambda x: probe.pdf_li(ref, x), axis=axis, cos_min=cos_min, res=(32, 16),
                             allow_failures=True)
    assert p > ALPHA, msg


def synthetic_envmap(path, w=24, h=12):
    """Smooth gradient plus a bright 2x2 spot; values are exact in half precision."""
    y, x = np.mgrid[0:h, 0:w]
    img = np.zeros((h, w, 3), np.float32)
    img[..., 0] = 0.25 + x / 32
    img[..., 1] = 0.5 + (y % 3) / 4
    img[..., 2] = 1.0
    img[3:5, 17:19] = [40.0, 30.0, 20.0]
    _core.write_exr(str(path), {c: np.ascontiguousarray(img[..., i]) for i, c in enumerate("RGB")})
    return img


def envmap_chi2(probe, n, quad=6, n_tests=N_TESTS):
    """Shared harness on the full sphere (its pole is z; the envmap's is y: any axis will do).
    `quad` must resolve the texels: the density is only piecewise bilinear."""
    ref = (0.0, 0.0, 0.0)
    d, w, pdf, ok = sampled_dirs(probe, ref, n)
    check_weights(probe, ref, d, w, pdf, ok)
    return chi2_test(lambda m: (d[:m], ok[:m]), lambda x: probe.pdf_li(ref, x), n_samples=n,
                     n_cos=32, n_phi=64, quad=quad, alpha=0.01, n_tests=n_tests)


def test_envmap_synthetic(tmp_path):
    synthetic_envmap(tmp_path / "env.exr")
    xml = f"""<emitter type="envmap"><string name="filename" value="{tmp_path / 'env.exr'}"/>
              <float name="scale" value="0.5"/>
              <transform name="to_world"><rotate x="1" angle="35"/><rotate y="1" angle="-70"/></transform></emitter>"""
    ok, p, msg = envmap_chi2(_probes.LightProbe(xml), 300_000)
    assert ok, msg


def test_envmap_mis_compensation(tmp_path):
    synthetic_envmap(tmp_path / "env.exr")
    xml = f"""<emitter type="envmap"><string name="filename" value="{tmp_path / 'env.exr'}"/>
              <boolean name="mis_compensation" value="true"/></emitter>"""
    ok, p, msg = envmap_chi2(_probes.LightProbe(xml), 200_000)
    assert ok, msg


def test_envmap_matpreview():
    path = shared_scenes() / "m3data-matpreview" / "envmap.exr"
    if not path.exists():
        pytest.skip(f"shared scenes not available ({path} is absent)")
    probe = _probes.LightProbe(f'<emitter type="envmap"><string name="filename" value="{path}"/></emitter>')
    ok, p, msg = envmap_chi2(probe, 400_000, quad=16)  # 512 x 256 texels
    assert ok, msg
