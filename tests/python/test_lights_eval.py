"""Point evaluations of emitters: envmap orientation (which texel a direction
sees), delta-light weights against their formulas, and agreement with
Mitsuba 3's own plugins (scalar_rgb) when it is installed."""
import numpy as np
import pytest

from mvpt import _probes
from test_lights_chi2 import synthetic_envmap

try:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
except Exception:  # pragma: no cover - Mitsuba is optional
    mi = None
needs_mitsuba = pytest.mark.skipif(mi is None, reason="mitsuba (scalar_rgb) is not installed")


def latlong_dir(u, v):
    """Mitsuba's lat-long convention (emitters/envmap.cpp)."""
    th, ph = np.pi * v, 2 * np.pi * u
    return np.stack([np.sin(ph) * np.sin(th), np.cos(th), -np.cos(ph) * np.sin(th)], -1).astype(np.float32)


def rotation(axis, angle_deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    t = np.radians(angle_deg)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(t) * K + (1 - np.cos(t)) * K @ K


@pytest.mark.parametrize("rotate", [None, ((0, 1, 0), 30.0), ((1, 0, 0), -50.0)])
def test_envmap_texel_orientation(tmp_path, rotate):
    """Column x sits at u = (x + 1/2)/W, row y at v = y/(H-1): the direction of a
    texel centre sees exactly that texel (times scale)."""
    img = synthetic_envmap(tmp_path / "env.exr")
    h, w, _ = img.shape
    tw = ""
    R = np.eye(3)
    if rotate:
        (ax, angle) = rotate
        tw = f'<transform name="to_world"><rotate x="{ax[0]}" y="{ax[1]}" z="{ax[2]}" angle="{angle}"/></transform>'
        R = rotation(ax, angle)
    probe = _probes.LightProbe(f'<emitter type="envmap"><string name="filename" value="{tmp_path / "env.exr"}"/>'
                             f'<float name="scale" value="2"/>{tw}</emitter>')
    y, x = np.mgrid[1:h - 1, 0:w]  # the first and last rows are the poles
    d = latlong_dir((x.ravel() + 0.5) / w, y.ravel() / (h - 1)) @ R.T.astype(np.float32)
    L = probe.eval((0, 0, 0), np.ascontiguousarray(d, dtype=np.float32))
    np.testing.assert_allclose(L, 2 * img[y.ravel(), x.ravel()], rtol=1e-4)
    # Half way between two columns: the average (bilinear lookup), also across the seam u = 0.
    d = latlong_dir(np.zeros(h - 2), np.arange(1, h - 1) / (h - 1)) @ R.T.astype(np.float32)
    L = probe.eval((0, 0, 0), np.ascontiguousarray(d, dtype=np.float32))
    np.testing.assert_allclose(L, img[1:h - 1, 0] + img[1:h - 1, w - 1], rtol=1e-4)


@needs_mitsuba
def test_envmap_matches_mitsuba(tmp_path):
    synthetic_envmap(tmp_path / "env.exr")
    fn = str(tmp_path / "env.exr")
    probe = _probes.LightProbe(f'<emitter type="envmap"><string name="filename" value="{fn}"/><float name="scale" value="1.5"/>'
                             '<transform name="to_world"><rotate x="1" angle="40"/><rotate z="1" angle="15"/></transform></emitter>')
    em = mi.load_dict({"type": "envmap", "filename": fn, "scale": 1.5,
                       "to_world": mi.ScalarTransform4f().rotate([0, 0, 1], 15) @ mi.ScalarTransform4f().rotate([1, 0, 0], 40)})
    rng = np.random.default_rng(3)
    d = rng.normal(size=(1500, 3))
    d = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    it = mi.Interaction3f()
    L_mi, pdf_mi = [], []
    for v in d:
        si = mi.SurfaceInteraction3f()
        si.wi = -mi.Vector3f(v)
        L_mi.append(np.array(em.eval(si)))
        ds = mi.DirectionSample3f()
        ds.d = mi.Vector3f(v)
        pdf_mi.append(em.pdf_direction(it, ds))
    np.testing.assert_allclose(probe.eval((0, 0, 0), d), np.array(L_mi), rtol=1e-4)
    # Near the poles 1/sin(theta) amplifies float round-off differently in the two codes.
    local_y = d @ (rotation((0, 0, 1), 15) @ rotation((1, 0, 0), 40))[:, 1]
    away = np.abs(local_y) < 0.99
    np.testing.assert_allclose(probe.pdf_li((0, 0, 0), d)[away], np.array(pdf_mi)[away], rtol=1e-4)


def test_point_light_weight():
    probe = _probes.LightProbe('<emitter type="point"><point name="position" x="1" y="2" z="3"/>'
                             '<rgb name="intensity" value="5, 6, 7"/></emitter>')
    ref = (0.5, -1.0, 0.0)
    d, w, pdf, dist = probe.sample_li(ref, 4)
    r = np.array([1, 2, 3]) - ref
    np.testing.assert_allclose(dist, np.linalg.norm(r), rtol=1e-6)
    np.testing.assert_allclose(d, np.tile(r / np.linalg.norm(r), (4, 1)), rtol=1e-6)
    np.testing.assert_allclose(w, np.tile(np.array([5, 6, 7]) / (r @ r), (4, 1)), rtol=1e-5)
    assert probe.is_delta and not probe.is_environment


def test_directional_weight():
    probe = _probes.LightProbe('<emitter type="directional"><vector name="direction" x="1" y="-2" z="0.5"/>'
                             '<rgb name="irradiance" value="3, 2, 1"/></emitter>')
    d, w, pdf, dist = probe.sample_li((0.1, 0.2, 0.3), 3)
    dd = -np.array([1, -2, 0.5]) / np.linalg.norm([1, -2, 0.5])
    np.testing.assert_allclose(d, np.tile(dd, (3, 1)), rtol=1e-6)
    np.testing.assert_allclose(w, np.tile([3, 2, 1], (3, 1)))
    assert np.all(np.isfinite(dist)) and probe.is_delta and not probe.is_environment


def spot_profile(cos_t, cutoff, beam):
    th = np.arccos(np.clip(cos_t, -1, 1))
    return np.where(cos_t > np.cos(np.radians(cutoff)),
                    np.where(cos_t >= np.cos(np.radians(beam)), 1.0, (np.radians(cutoff) - th) / np.radians(cutoff - beam)),
                    0.0)


def test_spot_falloff():
    xml = ('<emitter type="spot"><transform name="to_world"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/>'
           '</transform><rgb name="intensity" value="4"/><float name="cutoff_angle" value="30"/>'
           '<float name="beam_width" value="10"/></emitter>')
    probe = _probes.LightProbe(xml)
    angles = np.radians(np.linspace(0.5, 39.5, 40))  # avoid the exact cutoff, where float acos decides
    for a in angles:
        ref = (2 * np.tan(a), 0.0, 0.0)  # on the plane z = 0, angle a off the spot axis
        _, w, _, dist = probe.sample_li(ref, 1)
        expected = 4 * spot_profile(np.cos(a), 30, 10) / dist[0] ** 2
        np.testing.assert_allclose(w[0], expected, rtol=1e-4, atol=1e-7)


@needs_mitsuba
def test_spot_and_point_match_mitsuba():
    xml = ('<emitter type="spot"><transform name="to_world"><lookat origin="0.5, 1, 2" target="0, 0, 0" up="0, 1, 0"/>'
           '</transform><rgb name="intensity" value="4, 3, 2"/><float name="cutoff_angle" value="25"/></emitter>')
    probe = _probes.LightProbe(xml)
    em = mi.load_string(xml.replace("<emitter ", '<emitter version="3.0.0" '))
    rng = np.random.default_rng(5)
    refs = rng.uniform(-1.5, 1.5, size=(300, 3)) * [1, 1, 0.3]
    for ref in refs:
        it = mi.Interaction3f()
        it.p = mi.Point3f(ref)
        _, w_mi = em.sample_direction(it, [0.5, 0.5])
        _, w, _, _ = probe.sample_li(tuple(ref), 1)
        np.testing.assert_allclose(w[0], np.array(w_mi), rtol=2e-4, atol=1e-6)


def test_constant_environment():
    probe = _probes.LightProbe('<emitter type="constant"><rgb name="radiance" value="0.5, 1, 2"/></emitter>')
    d, w, pdf, _ = probe.sample_li((0, 0, 0), 1000)
    np.testing.assert_allclose(pdf, 1 / (4 * np.pi), rtol=1e-6)
    np.testing.assert_allclose(w, np.tile(np.array([0.5, 1, 2]) * 4 * np.pi, (1000, 1)), rtol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, rtol=1e-5)
    # Uniform on the sphere: mean direction ~ 0 (|mean| < 5 sigma, sigma = 1/sqrt(3n)).
    assert np.all(np.abs(d.mean(axis=0)) < 5 / np.sqrt(3 * 1000))
    assert probe.is_environment


@pytest.mark.parametrize("xml, message", [
    ('<emitter type="spot"><float name="cutoff_angle" value="10"/><float name="beam_width" value="20"/></emitter>', "beam_width"),
    ('<emitter type="point"><point name="position" x="1" y="0" z="0"/><transform name="to_world"><translate x="1"/></transform></emitter>', "position"),
    ('<emitter type="directional"><vector name="direction" x="0" y="0" z="0"/></emitter>', "direction"),
    ('<emitter type="envmap"><string name="filename" value="missing-file.exr"/></emitter>', "missing-file.exr"),
    ('<emitter type="constant"><rgb name="radiance" value="1"/><float name="scale" value="2"/></emitter>', "scale"),
])
def test_bad_parameters(xml, message):
    with pytest.raises(ValueError, match=message):
        _probes.LightProbe(xml)


def test_animated_point_light_moves():
    """to_world may be an <animation>: the light sits at the interpolated position at `time`."""
    xml = ('<emitter type="point"><animation name="to_world">'
           '<transform time="0"><translate x="0" y="0" z="1"/></transform>'
           '<transform time="1"><translate x="2" y="0" z="1"/></transform></animation></emitter>')
    probe = _probes.LightProbe(xml)
    for t, x in [(0.0, 0.0), (0.25, 0.5), (1.0, 2.0), (3.0, 2.0)]:
        d, w, _, dist = probe.sample_li((0, 0, 0), 1, time=t)
        np.testing.assert_allclose(dist[0], np.hypot(x, 1.0), rtol=1e-5)
        np.testing.assert_allclose(d[0], np.array([x, 0, 1]) / np.hypot(x, 1.0), rtol=1e-5, atol=1e-7)
