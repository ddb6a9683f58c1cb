"""Path-integrator semantics against Mitsuba 3: null (mask) interactions, hide_emitters
and max_depth. Mitsuba keeps a path's radiance only if it scattered at a non-null
surface, hit an emitter, or could see an environment; a 0.4-opacity mask floor with
nothing behind it therefore renders at opacity^2 of the opaque floor. These cases
differ by tens of percent, so a 2% relative tolerance separates them cleanly while
being > 6 standard errors of the mean at these sample counts."""
import numpy as np
import pytest

import mvpt

mi = pytest.importorskip("mitsuba")
mi.set_variant("scalar_rgb")


def scene_xml(opacity, max_depth=-1, hide=False, env=False, below=False):
    parts = [f'<integrator type="path"><integer name="max_depth" value="{max_depth}"/>'
             f'<boolean name="hide_emitters" value="{str(hide).lower()}"/></integrator>',
             '<sensor type="perspective"><float name="fov" value="20"/><transform name="to_world">'
             '<lookat origin="0, 3, 4" target="0, 0, 0" up="0, 1, 0"/></transform>'
             '<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>'
             '<rfilter type="box"/></film><sampler type="independent"><integer name="sample_count" value="256"/>'
             '</sampler></sensor>',
             '<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/>'
             f'</transform><bsdf type="mask"><float name="opacity" value="{opacity}"/><bsdf type="diffuse"/></bsdf></shape>',
             '<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/>'
             '<scale value="0.5"/></transform><emitter type="area"><rgb name="radiance" value="10, 8, 6"/>'
             '</emitter></shape>']
    if env:
        parts.append('<emitter type="constant"><rgb name="radiance" value="0"/></emitter>')
    if below:
        parts.append('<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/>'
                     '<scale value="1000"/><translate y="-5"/></transform><bsdf type="diffuse">'
                     '<rgb name="reflectance" value="0"/></bsdf></shape>')
    return '<scene version="3.0.0">' + "".join(parts) + "</scene>"


def mitsuba_mean(xml):
    scene = mi.load_string(xml)
    return np.mean([np.array(mi.render(scene, seed=s, spp=1024))[..., :3].mean() for s in range(4)])


def mvpt_mean(xml):
    return mvpt.render(mvpt.load_string(xml), spp=4096, seed=3).images["0"].mean()


@pytest.mark.parametrize("kw", [dict(), dict(env=True), dict(below=True), dict(below=True, max_depth=2),
                                dict(max_depth=1)], ids=str)
def test_null_path_semantics_match_mitsuba(kw):
    xml = scene_xml(0.4, **kw)
    ours, theirs = mvpt_mean(xml), mitsuba_mean(xml)
    assert abs(ours - theirs) <= 0.02 * max(theirs, 1e-3), (kw, ours, theirs)


def test_hide_emitters_changes_nothing_when_no_emitter_is_visible():
    """The camera sees no emitter here, so hide_emitters must not change the image.
    Mitsuba 3.9.1 renders this scene about 2.6% brighter with hide_emitters=true, also
    with an opaque floor (0.4334 vs 0.4220 at max_depth=2): a bias of its own, which we
    do not reproduce; we compare with its hide_emitters=false render instead.

    Only the `below` variant is used: there every path scatters at a non-null surface.
    Where a path can end invalid after next-event estimation (a mask with nothing
    behind it), the valid-path rule makes the expected image depend on the MIS
    weights (NEE counts with probability `opacity`, BSDF sampling always), so even a
    black extra light changes it, in Mitsuba as in mvpt."""
    kw = dict(below=True)
    ours_hidden = mvpt_mean(scene_xml(0.4, hide=True, **kw))
    ours_shown = mvpt_mean(scene_xml(0.4, hide=False, **kw))
    theirs_shown = mitsuba_mean(scene_xml(0.4, hide=False, **kw))
    assert abs(ours_hidden - ours_shown) <= 0.02 * ours_shown, (kw, ours_hidden, ours_shown)
    assert abs(ours_shown - theirs_shown) <= 0.02 * theirs_shown, (kw, ours_shown, theirs_shown)
