"""Renders with each emitter: analytic radiance (a diffuse plane under a point
or directional light, a convex object in a constant environment, a closed
emitting diffuse box), and comparisons against Mitsuba 3 (scalar_rgb)."""
import numpy as np
import pytest

import mvpt
from light_scenes import ROOM, block_z, compare, render_mitsuba, scene_xml, SIZE
from scipy import stats
from test_lights_chi2 import shared_scenes, synthetic_envmap

try:
    import mitsuba as mi  # noqa: F401
except Exception:  # pragma: no cover
    mi = None
needs_mitsuba = pytest.mark.skipif(mi is None, reason="mitsuba (scalar_rgb) is not installed")


def render(xml, spp, seed=7, base_dir="."):
    r = mvpt.render(mvpt.load_string(xml, base_dir), spp=spp, seed=seed)
    return [(r.images[k], r.variance[k]) for k in r.images]


def zcheck(views, expected, alpha=0.01):
    """Sidak-corrected block z-tests of rendered views against exact images."""
    zs = [block_z(img, var, exp, np.zeros_like(exp)) for (img, var), exp in zip(views, expected)]
    z_crit = stats.norm.isf((1 - (1 - alpha) ** (1 / sum(z.size for z in zs))) / 2)
    for i, ((img, _), exp, z) in enumerate(zip(views, expected, zs)):
        assert np.abs(z).max() < z_crit, f"view {i}: max |z| = {np.abs(z).max():.2f} > {z_crit:.2f}"
        assert abs(img.mean() / exp.mean() - 1) < 0.01, f"view {i}: mean {img.mean()} vs {exp.mean()}"


def footprint_radius2(size, fov_deg, height, ss=16):
    """Squared distance from the image-centre axis, on a plane `height` below a camera
    looking straight down, of ss x ss points per pixel (box filter footprint)."""
    t = np.tan(np.radians(fov_deg) / 2)
    f = (np.arange(size * ss) + 0.5) / (size * ss)
    x = (2 * f - 1) * t * height
    return x[None, :] ** 2 + x[:, None] ** 2


def pixel_average(v, size, ss=16):
    return v.reshape(size, ss, size, ss, -1).mean(axis=(1, 3))


DOWN_VIEWS = [("0, 0, 3", "0, 0, 0", "0, 1, 0"), ("0, 0, 2", "0, 0, 0", "1, 0, 0")]
PLANE = '<shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>' \
        '<bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>'


def test_point_light_over_plane():
    """L = rho/pi * I cos(theta) / r^2 = rho/pi * I h / r^3 (light at height h)."""
    intensity, h, rho, fov = np.array([3.0, 2.0, 1.0]), 1.0, 0.6, 60
    xml = scene_xml(PLANE + '<emitter type="point"><point name="position" x="0" y="0" z="1"/>'
                    '<rgb name="intensity" value="3, 2, 1"/></emitter>', views=DOWN_VIEWS, fov=fov)
    views = render(xml, spp=64)
    expected = []
    for cam_h in (3.0, 2.0):
        r2 = footprint_radius2(SIZE, fov, cam_h)
        L = rho / np.pi * h / (r2 + h * h) ** 1.5
        expected.append(pixel_average(L[..., None] * intensity, SIZE))
    zcheck(views, expected)


def test_directional_light_on_plane():
    """L = rho/pi * E cos(theta), uniform over the plane."""
    d = np.array([1.0, 0.5, -2.0])
    cos_t = -d[2] / np.linalg.norm(d)
    xml = scene_xml(PLANE + '<emitter type="directional"><vector name="direction" x="1" y="0.5" z="-2"/>'
                    '<rgb name="irradiance" value="2, 3, 4"/></emitter>', views=DOWN_VIEWS, fov=60)
    views = render(xml, spp=16)
    L = 0.6 / np.pi * np.array([2, 3, 4]) * cos_t
    for img, _ in views:
        np.testing.assert_allclose(img, np.broadcast_to(L, img.shape), rtol=1e-4)


def test_constant_environment_convex_object():
    """A convex diffuse object only sees the environment: L = rho * L_env on it
    (depth unlimited: nothing else can contribute). The views see only the cube."""
    rho, le = np.array([0.8, 0.5, 0.2]), np.array([1.0, 2.0, 0.5])
    body = ('<shape type="cube"><transform name="to_world"><rotate x="1" y="1" angle="30"/></transform>'
            '<bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf></shape>'
            '<emitter type="constant"><rgb name="radiance" value="1, 2, 0.5"/></emitter>')
    views = [("0, -3, 0.2", "0, 0, 0", "0, 0, 1"), ("2.2, 1.5, -1.2", "0, 0, 0", "0, 0, 1")]
    out = render(scene_xml(body, views=views, max_depth=-1, fov=15), spp=64)
    for img, var in out:
        assert np.all(var > 0), "a pixel missed the cube"
    zcheck(out, [np.broadcast_to(rho * le, img.shape).copy() for img, _ in out])


def test_closed_emitting_box_furnace():
    """Inside a closed diffuse box (albedo rho) whose walls emit L_e inwards,
    L = L_e (1 + rho + rho^2 + ...) = L_e / (1 - rho) with unlimited depth."""
    body = ('<shape type="cube"><boolean name="flip_normals" value="true"/><transform name="to_world"><scale value="2"/></transform>'
            '<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>'
            '<emitter type="area"><rgb name="radiance" value="1, 0.5, 0.25"/></emitter></shape>')
    views = [("0, 0, 0", "0, 1, 0", "0, 0, 1"), ("0.5, -1, 0.3", "-1, 0, -1", "0, 0, 1")]
    expected = np.array([1, 0.5, 0.25]) / (1 - 0.5)
    views_out = render(scene_xml(body, views=views, max_depth=-1, fov=70), spp=32)
    zcheck(views_out, [np.broadcast_to(expected, img.shape).copy() for img, _ in views_out])


# ---------------------------------------------------------------- Mitsuba comparisons

SYNTH_ENV = "{env}"


EMITTERS = {
    "point": '<emitter type="point"><point name="position" x="-0.6" y="-0.5" z="2"/><rgb name="intensity" value="5, 4, 3"/></emitter>',
    "spot": '<emitter type="spot"><transform name="to_world"><lookat origin="-1, -1.5, 2.5" target="0.2, 0.2, 0" up="0, 0, 1"/>'
            '</transform><rgb name="intensity" value="20"/><float name="cutoff_angle" value="25"/>'
            '<float name="beam_width" value="12"/></emitter>',
    "directional": '<emitter type="directional"><vector name="direction" x="0.4" y="0.6" z="-1"/>'
                   '<rgb name="irradiance" value="2, 1.8, 1.5"/></emitter>',
    "constant": '<emitter type="constant"><rgb name="radiance" value="0.6, 0.8, 1"/></emitter>',
    "envmap": '<emitter type="envmap"><string name="filename" value="{env}"/><float name="scale" value="0.3"/>'
              '<transform name="to_world"><rotate x="1" angle="90"/><rotate z="1" angle="30"/></transform></emitter>',
    "area": '<shape type="rectangle"><transform name="to_world"><scale x="0.5" y="0.3"/><rotate x="1" angle="160"/>'
            '<translate x="-0.4" y="0.3" z="2.2"/></transform><emitter type="area"><rgb name="radiance" value="12, 10, 8"/></emitter></shape>',
    # A mirroring to_world: the rectangle's normal is +z transformed as a normal (Mitsuba's analytic
    # rectangle), not the side its mirrored triangles would give.
    "area-mirrored": '<shape type="rectangle"><transform name="to_world"><scale x="-0.5" y="0.3"/><rotate x="1" angle="160"/>'
                     '<translate x="-0.4" y="0.3" z="2.2"/></transform><emitter type="area"><rgb name="radiance" value="12, 10, 8"/>'
                     '</emitter></shape>',
}


N_COMPARISONS = len(EMITTERS) + 1


@needs_mitsuba
@pytest.mark.parametrize("kind", list(EMITTERS))
def test_matches_mitsuba(kind, tmp_path):
    synthetic_envmap(tmp_path / "env.exr")
    xml = scene_xml(ROOM + EMITTERS[kind].format(env=tmp_path / "env.exr"), max_depth=4)
    ref = render_mitsuba(xml, 2, spp=64, seeds=4)
    ours = render(xml, spp=256, seed=11)
    failures = compare(ours, ref, n_tests=N_COMPARISONS)
    assert not failures, "; ".join(failures)


@needs_mitsuba
def test_matpreview_envmap_matches_mitsuba():
    path = shared_scenes() / "m3data-matpreview" / "envmap.exr"
    if not path.exists():
        pytest.skip(f"shared scenes not available ({path} is absent)")
    emitter = (f'<emitter type="envmap"><string name="filename" value="{path}"/>'
               '<transform name="to_world"><rotate x="1" angle="90"/><rotate z="1" angle="-60"/></transform></emitter>')
    xml = scene_xml(ROOM + emitter, max_depth=4)
    ref = render_mitsuba(xml, 2, spp=64, seeds=4)
    ours = render(xml, spp=256, seed=13)
    failures = compare(ours, ref, n_tests=N_COMPARISONS)
    assert not failures, "; ".join(failures)
