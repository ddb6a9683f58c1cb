"""Probe how Mitsuba 3's `path` integrator treats null (mask / thindielectric)
interactions, hide_emitters and max_depth, by tiny renders (8x8, scalar_rgb).
Evidence for the path-integrator notes in the bsdf branch report; not a test.

Scene: a floor rectangle with a `mask` BSDF (opacity op over diffuse), an area
light above it, optional environment / surface below the floor.
"""
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")


def scene(opacity, max_depth=-1, hide=False, env=False, below=False, light=True):
    parts = [f'<integrator type="path"><integer name="max_depth" value="{max_depth}"/>'
             f'<boolean name="hide_emitters" value="{str(hide).lower()}"/></integrator>',
             '<sensor type="perspective"><float name="fov" value="20"/><transform name="to_world">'
             '<lookat origin="0, 3, 4" target="0, 0, 0" up="0, 1, 0"/></transform>'
             '<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>'
             '<rfilter type="box"/></film><sampler type="independent"><integer name="sample_count" value="256"/>'
             '</sampler></sensor>',
             '<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/>'
             f'</transform><bsdf type="mask"><float name="opacity" value="{opacity}"/><bsdf type="diffuse"/></bsdf></shape>']
    if light:
        parts.append('<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/>'
                     '<scale value="0.5"/></transform><emitter type="area"><rgb name="radiance" value="10, 8, 6"/>'
                     '</emitter></shape>')
    if env:
        parts.append('<emitter type="constant"><rgb name="radiance" value="0"/></emitter>')
    if below:
        parts.append('<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/>'
                     '<scale value="1000"/><translate y="-5"/></transform><bsdf type="diffuse">'
                     '<rgb name="reflectance" value="0"/></bsdf></shape>')
    return mi.load_string('<scene version="3.0.0">' + "".join(parts) + "</scene>")


if __name__ == "__main__":
    full = np.array(mi.render(scene(1.0)))[..., :3].mean()
    print(f"opacity 1: {full:.4f}  (opacity 0.4 would give {0.4 * full:.4f} if unbiased)")
    for kw in [dict(), dict(env=True), dict(below=True), dict(below=True, max_depth=2),
               dict(hide=True, env=True), dict(hide=True, below=True)]:
        v = np.array(mi.render(scene(0.4, **kw)))[..., :3].mean()
        print(f"opacity 0.4 {kw}: {v:.4f} = {v / full:.3f} x opacity-1 value")
