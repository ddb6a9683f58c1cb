"""Analytic shapes (sphere, disk, cylinder) against Mitsuba 3: geometry, uv
parameterisation (through checkerboard textures), flip_normals, spherical emitters."""
from shapes_compare import compare_with_mitsuba

SENSORS = """
  <sensor type="perspective">
    <float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="{o}" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
  </sensor>"""


def scene(body: str, origins=("0,1.5,6", "4,2,-4")) -> str:
    sensors = "".join(SENSORS.format(o=o) for o in origins)
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  {sensors}
  {body}
</scene>"""


CHECKER = """<bsdf type="diffuse"><texture name="reflectance" type="checkerboard">
   <rgb name="color0" value="0.8,0.3,0.1"/><rgb name="color1" value="0.1,0.3,0.8"/>
   <transform name="to_uv"><scale x="{sx}" y="{sy}"/></transform></texture></bsdf>"""


def test_sphere_disk_cylinder_match_mitsuba():
    body = f"""
  <shape type="sphere"><point name="center" x="-1.2" y="0" z="0"/><float name="radius" value="0.8"/>
    {CHECKER.format(sx=4, sy=3)}</shape>
  <shape type="sphere">
    <transform name="to_world"><scale value="0.5"/><rotate x="0.6" y="0.8" angle="50"/><translate x="0.3" y="1.2" z="0.5"/></transform>
    {CHECKER.format(sx=6, sy=4)}</shape>
  <shape type="cylinder"><point name="p0" x="1.2" y="-0.8" z="0"/><point name="p1" x="1.0" y="0.8" z="0.4"/>
    <float name="radius" value="0.5"/>{CHECKER.format(sx=5, sy=3)}</shape>
  <shape type="disk"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/><translate y="-0.8"/></transform>
    {CHECKER.format(sx=3, sy=8)}</shape>
  <shape type="disk"><boolean name="flip_normals" value="true"/>
    <transform name="to_world"><rotate y="1" angle="20"/><translate z="-2" y="0.5"/></transform></shape>
  <shape type="sphere"><point name="center" x="0.5" y="3" z="2"/><float name="radius" value="0.4"/>
    <emitter type="area"><rgb name="radiance" value="12,10,8"/></emitter></shape>
  <shape type="sphere"><float name="radius" value="20"/><boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="0.3,0.35,0.4"/></emitter></shape>
"""
    compare_with_mitsuba(scene(body), spp=128, mi_spp=8, runs=16)
