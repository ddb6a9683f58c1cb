"""Animated sensors (camera motion blur) against Mitsuba 3.

Mitsuba 3.9.1 cannot load <animation>, so the reference is the average of static Mitsuba
renders with each camera posed at stratified random times of its shutter (run k at
t_k = open + (k + u_k) / K * (close - open)), as in test_shapes_instances.py: an unbiased
estimate of the shutter-integrated image whose spread gives its variance. The keyframes
rotate about one axis (after a fixed tilt), so slerp is linear in the angle and the pose at
any time is written exactly as a static <transform>."""
import numpy as np
import pytest

import mvpt
from shapes_compare import assert_z_scores, block_z_scores, mi

BODY = """
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <shape type="sphere"><point name="center" x="1.5" y="4" z="-2"/><float name="radius" value="0.7"/>
    <emitter type="area"><rgb name="radiance" value="12"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="5"/><rotate x="1" angle="-90"/><translate y="-0.6"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.4,0.5,0.4"/></bsdf></shape>
  <shape type="sphere"><float name="radius" value="0.6"/>
    <bsdf type="diffuse"><texture name="reflectance" type="checkerboard"><transform name="to_uv"><scale x="8" y="4"/></transform></texture></bsdf></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.35"/><rotate y="1" angle="30"/><translate x="-1.2" y="-0.25" z="0.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8,0.3,0.1"/></bsdf></shape>"""

FILM = """<film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>"""

# (time, yaw in degrees, translation) keyframes of the two sensors; shutters in SHUTTERS.
KEYS = [
    [(0.0, -12.0, (-1.0, 1.2, -5.0)), (1.0, 10.0, (1.2, 1.6, -5.5))],                                      # pinhole
    [(0.0, 8.0, (0.5, 1.0, -6.0)), (0.5, -6.0, (-0.3, 1.5, -5.0)), (1.0, 4.0, (0.8, 1.2, -4.5))],       # thin lens
]
SHUTTERS = [(0.0, 1.0), (0.2, 0.7)]
TILT = 12.0  # degrees of pitch (downwards) applied before the yaw


def pose(v: int, t: float):
    """Yaw and translation of sensor v at time t: linear between keys, end poses held outside."""
    keys = KEYS[v]
    if t <= keys[0][0]:
        return keys[0][1:]
    for (t0, a0, p0), (t1, a1, p1) in zip(keys, keys[1:]):
        if t <= t1:
            s = (t - t0) / (t1 - t0)
            return a0 + s * (a1 - a0), tuple(x + s * (y - x) for x, y in zip(p0, p1))
    return keys[-1][1:]


def xform(yaw: float, p) -> str:
    return (f'<rotate x="1" angle="{TILT}"/><rotate y="1" angle="{yaw}"/>'
            f'<translate x="{p[0]}" y="{p[1]}" z="{p[2]}"/>')


def sensors(t=None) -> str:
    """Both sensors, keyframed (t is None) or posed statically at their shutter time t[v]."""
    out = []
    for v, kind in enumerate(("""<sensor type="perspective"><float name="fov" value="50"/>""",
                              """<sensor type="thinlens"><float name="fov" value="45"/>
    <float name="aperture_radius" value="0.12"/><float name="focus_distance" value="5.5"/>""")):
        if t is None:
            keys = "".join(f'<transform time="{kt}">{xform(a, p)}</transform>' for kt, a, p in KEYS[v])
            xf = (f'<float name="shutter_open" value="{SHUTTERS[v][0]}"/><float name="shutter_close" value="{SHUTTERS[v][1]}"/>'
                  f'<animation name="to_world">{keys}</animation>')
        else:
            xf = f'<transform name="to_world">{xform(*pose(v, t[v]))}</transform>'
        out.append(f"{kind}\n    {xf}\n    {FILM}</sensor>")
    return "".join(out)


def scene(t=None) -> str:
    return f'<scene version="3.0.0">{sensors(t)}{BODY}</scene>'


def test_moving_cameras_match_time_sampled_mitsuba():
    result = mvpt.render(mvpt.load_string(scene()), spp=128, seed=3)
    runs, mi_spp = 32, 4
    rng = np.random.default_rng(8)
    strata = (np.arange(runs) + rng.random(runs)) / runs
    refs = [[], []]
    for k, u in enumerate(strata):
        times = [o + u * (c - o) for o, c in SHUTTERS]
        ms = mi.load_string(scene(times))
        for v in range(2):
            refs[v].append(np.array(mi.render(ms, sensor=v, spp=mi_spp, seed=200 + k)))
    zs, report = [], []
    for v, vid in enumerate(result.images):
        a, var_a = result.images[vid].astype(np.float64), result.variance[vid].astype(np.float64)
        r = np.stack(refs[v]).astype(np.float64)
        b, var_b = r.mean(axis=0), r.var(axis=0, ddof=1) / runs
        report.append(f"view {vid}: mvpt {a.mean():.5f}, mitsuba {b.mean():.5f}")
        assert abs(a.mean() - b.mean()) <= 0.01 * b.mean(), report
        zs.append(block_z_scores(a, var_a, b, var_b, 4, f"view {vid}"))
    assert_z_scores(np.concatenate(zs), 1e-3, "; ".join(report))


def test_camera_motion_is_not_ignored():
    # Guard against an animation that is silently ignored or evaluated at one time only:
    # the blurred image must differ clearly from the images at both shutter ends.
    blurred = mvpt.render(mvpt.load_string(scene()), spp=32, seed=2).images
    for end in (0, 1):
        static = mvpt.render(mvpt.load_string(scene([s[end] for s in SHUTTERS])), spp=32, seed=2).images
        for k in blurred:
            assert np.abs(blurred[k] - static[k]).mean() > 0.05 * static[k].mean(), (k, end)


def test_static_pose_inside_keyframes_is_exact():
    # A zero-length shutter at t = 0.5 renders the keyframed sensor at its pose at 0.5: with
    # the same seed the images equal those of the static sensor (up to float rounding of the
    # interpolated pose).
    xml = scene()
    xml_mid = xml.replace('<float name="shutter_open" value="0.0"/><float name="shutter_close" value="1.0"/>',
                          '<float name="shutter_open" value="0.5"/><float name="shutter_close" value="0.5"/>', 1)
    assert xml_mid != xml
    a = mvpt.render(mvpt.load_string(xml_mid), spp=4, seed=5).images
    b = mvpt.render(mvpt.load_string(scene([0.5, 0.2])), spp=4, seed=5).images
    k = next(iter(a))
    diff = np.abs(a[k] - b[k])
    # Rays may differ by rounding, so a few pixels near edges can flip; the rest is identical.
    assert np.mean(diff > 1e-3) < 0.02, np.mean(diff > 1e-3)


def test_scaled_sensor_keyframe_is_an_error():
    xml = scene().replace('<rotate x="1" angle="12.0"/>', '<scale value="1.5"/><rotate x="1" angle="12.0"/>', 1)
    with pytest.raises(mvpt.SceneError, match="keyframe at time 0.*rigid motion"):
        mvpt.load_string(xml)


def test_projection_api_from_python():
    # The bindings of Camera::generate_ray / project / film_density (design doc §2-§4):
    # a point on a moving thin-lens camera's ray projects back to its film position.
    s = mvpt.load_string(scene())
    for view, t, lens in ((0, 0.3, (0.0, 0.0)), (1, 0.45, (0.5, -0.3))):
        o, d = s.camera_generate_ray(view, (11.25, 20.5), lens, t)
        y = np.array(o) + 4.0 * np.array(d)
        x = s.camera_project(view, tuple(y), t, lens)
        assert x is not None and np.allclose(x, (11.25, 20.5), atol=1e-4), x
        assert s.camera_project(view, tuple(np.array(o) - np.array(d)), t, lens) is None  # behind
        assert s.camera_film_density(view, tuple(y), tuple(-np.array(d)), t, lens) > 0
    with pytest.raises(IndexError):
        s.camera_project(2, (0, 0, 0))
