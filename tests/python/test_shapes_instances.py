"""Shape groups, instances and animated transforms (motion blur) against Mitsuba 3.

Mitsuba 3.9.1 cannot load <animation>, so the motion-blurred reference is built from
static Mitsuba renders at stratified random times (each of the K runs renders the scene
posed at t_k = (k + u_k) / K): their average is an unbiased estimate of the
shutter-integrated image, and their spread gives its variance."""
import numpy as np
import pytest

import mvpt
from shapes_compare import assert_z_scores, block_z_scores, compare_with_mitsuba, mi

SENSORS = """
  <sensor type="perspective">
    <float name="fov" value="45"/>{shutter}
    <transform name="to_world"><lookat origin="{o}" target="0,0.3,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
  </sensor>"""

LIGHTS = """
  <shape type="sphere"><point name="center" x="1" y="4" z="3"/><float name="radius" value="0.6"/>
    <emitter type="area"><rgb name="radiance" value="10"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-0.6"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.4,0.5,0.4"/></bsdf></shape>"""


def scene(body: str, shutter: bool = False, origins=("0,1.5,6", "4,2.5,-3")) -> str:
    sh = '<float name="shutter_open" value="0"/><float name="shutter_close" value="1"/>' if shutter else ""
    sensors = "".join(SENSORS.format(o=o, shutter=sh) for o in origins)
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  {sensors}{LIGHTS}
  {body}
</scene>"""


GROUP = """
  <shape type="shapegroup" id="grp">
    <shape type="sphere"><float name="radius" value="0.5"/>
      <bsdf type="diffuse"><texture name="reflectance" type="checkerboard"><transform name="to_uv"><scale x="6" y="4"/></transform></texture></bsdf></shape>
    <shape type="cylinder"><point name="p0" x="0.6" y="-0.5" z="0"/><point name="p1" x="0.6" y="0.5" z="0"/><float name="radius" value="0.2"/>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.2,0.2,0.8"/></bsdf></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.25"/><translate x="-0.6"/></transform>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.8,0.3,0.1"/></bsdf></shape>
  </shape>"""


def test_static_instances_match_mitsuba():
    body = GROUP + """
  <shape type="instance"><ref id="grp"/><transform name="to_world"><translate x="-1" y="0.2"/></transform></shape>
  <shape type="instance"><ref id="grp"/>
    <transform name="to_world"><scale value="0.8"/><rotate y="1" angle="70"/><translate x="1.2" y="0.4" z="0.5"/></transform></shape>
  <shape type="instance"><ref id="grp"/>
    <transform name="to_world"><scale x="1.2" y="0.6" z="1"/><rotate z="1" angle="-30"/><translate y="1.6" z="-1"/></transform></shape>"""
    compare_with_mitsuba(scene(body), spp=128, mi_spp=8, runs=16)


def test_area_emitter_in_shapegroup_is_an_error():
    xml = scene("""<shape type="shapegroup" id="g"><shape type="sphere">
        <emitter type="area"/></shape></shape>
      <shape type="instance"><ref id="g"/></shape>""")
    with pytest.raises(mvpt.SceneError, match="shapegroup cannot be an area emitter"):
        mvpt.load_string(xml)


def test_unreferenced_shapegroup_is_not_rendered():
    base = scene("")
    with_group = scene(GROUP)
    a = mvpt.render(mvpt.load_string(base), spp=8, seed=1).images
    b = mvpt.render(mvpt.load_string(with_group), spp=8, seed=1).images
    for k in a:
        assert np.array_equal(a[k], b[k])


# ---------------------------------------------------------------- motion blur

def lerp(a, b, t):
    return tuple(x + (y - x) * t for x, y in zip(a, b))


def poses(t: float):
    """The animated objects' transform parameters at time t (end poses hold outside the keys)."""
    tm = min(max((t - 0.25) / 0.5, 0.0), 1.0)  # keys at 0.25 and 0.75
    return {
        "inst": (lerp((-1.2, 0.2, 0), (0.4, 0.9, 0), t), 90.0 * t),          # keys at 0, 1
        "ball": (lerp((1.0, 0.0, 0.5), (1.0, 1.2, 1.0), tm), 0.4 + 0.3 * tm),  # keys at 0.25, 0.75
        "cube": (lerp((0.0, -0.2, -1.0), (-1.0, 0.3, -1.0), t), 60.0 * t),
    }


def animated_body(t=None) -> str:
    """Scene body: keyframed (t is None) or posed statically at time t."""
    def xf(name, key_times, make):
        if t is not None:
            return f'<transform name="to_world">{make(poses(t))}</transform>'
        keys = "".join(f'<transform time="{kt}">{make(poses(kt if name != "ball" else (0 if kt == 0.25 else 1)))}</transform>'
                       for kt in key_times)
        return f'<animation name="to_world">{keys}</animation>'

    inst = lambda p: (f'<rotate y="1" angle="{p["inst"][1]}"/>'
                      f'<translate x="{p["inst"][0][0]}" y="{p["inst"][0][1]}" z="{p["inst"][0][2]}"/>')
    ball = lambda p: (f'<scale value="{p["ball"][1]}"/>'
                      f'<translate x="{p["ball"][0][0]}" y="{p["ball"][0][1]}" z="{p["ball"][0][2]}"/>')
    cube = lambda p: (f'<scale value="0.3"/><rotate x="1" angle="{p["cube"][1]}"/>'
                      f'<translate x="{p["cube"][0][0]}" y="{p["cube"][0][1]}" z="{p["cube"][0][2]}"/>')
    return GROUP + f"""
  <shape type="instance"><ref id="grp"/>{xf("inst", (0, 1), inst)}</shape>
  <shape type="sphere">{xf("ball", (0.25, 0.75), ball)}
    <bsdf type="diffuse"><rgb name="reflectance" value="0.9,0.9,0.2"/></bsdf></shape>
  <shape type="cube">{xf("cube", (0, 1), cube)}
    <bsdf type="diffuse"><rgb name="reflectance" value="0.3,0.8,0.3"/></bsdf></shape>"""


def test_motion_blur_matches_time_sampled_mitsuba():
    xml = scene(animated_body(), shutter=True)
    result = mvpt.render(mvpt.load_string(xml), spp=128, seed=11)
    runs, mi_spp = 32, 4
    rng = np.random.default_rng(5)
    times = (np.arange(runs) + rng.random(runs)) / runs
    refs = [[], []]
    for k, t in enumerate(times):
        ms = mi.load_string(scene(animated_body(float(t))))
        for v in range(2):
            refs[v].append(np.array(mi.render(ms, sensor=v, spp=mi_spp, seed=100 + k)))
    zs = []
    for v, vid in enumerate(result.images):
        a, var_a = result.images[vid].astype(np.float64), result.variance[vid].astype(np.float64)
        r = np.stack(refs[v]).astype(np.float64)
        b, var_b = r.mean(axis=0), r.var(axis=0, ddof=1) / runs
        assert abs(a.mean() - b.mean()) <= 0.01 * b.mean(), (vid, a.mean(), b.mean())
        zs.append(block_z_scores(a, var_a, b, var_b, 4, f"view {vid}"))
    assert_z_scores(np.concatenate(zs), 1e-3)


def test_motion_blur_differs_from_static_pose():
    # Guard against an animation that is silently ignored: the blurred image must
    # differ clearly from the image at t = 0.
    blurred = mvpt.render(mvpt.load_string(scene(animated_body(), shutter=True)), spp=32, seed=2)
    static = mvpt.render(mvpt.load_string(scene(animated_body(0.0))), spp=32, seed=2)
    for k in blurred.images:
        assert np.abs(blurred.images[k] - static.images[k]).mean() > 0.01 * static.images[k].mean() + 1e-3


def test_animated_area_emitter_is_an_error():
    xml = scene("""<shape type="sphere"><animation name="to_world">
        <transform time="0"><translate x="1"/></transform><transform time="1"><translate x="2"/></transform>
      </animation><emitter type="area"/></shape>""")
    with pytest.raises(mvpt.SceneError, match="animated shape"):
        mvpt.load_string(xml)


def test_nested_instancing_is_an_error():
    xml = scene(GROUP + """<shape type="shapegroup" id="outer"><shape type="instance"><ref id="grp"/></shape></shape>
      <shape type="instance"><ref id="outer"/></shape>""")
    with pytest.raises(mvpt.SceneError, match="nested instancing"):
        mvpt.load_string(xml)
