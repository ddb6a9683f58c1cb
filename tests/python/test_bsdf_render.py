"""Tiny renders of each BSDF on a floor under an area light, mvpt against
Mitsuba 3 (scalar_rgb): the per-channel image means of several independent
renders must agree (Welch t-test, Sidak-corrected over all comparisons).

Two scene choices avoid differences that are not the BSDFs' business (see the
bsdf branch report): the light gets an explicit black BSDF (Mitsuba gives
emitter shapes a black default BSDF), and a diffuse ground below the floor
catches every ray that passes through it (Mitsuba discards the radiance of a
path whose only scattering events were null transmissions).
Power: the standard error of a mean is ~0.4% for the diffuse/glossy cases and
2-6% for the mask and the caustic-heavy dielectric floors.
"""
import numpy as np
import pytest
from scipy import stats

mi = pytest.importorskip("mitsuba")
mi.set_variant("scalar_rgb")
import mvpt  # noqa: E402

N_SEEDS, SPP, RES = 8, 32, 12
ALPHA = 0.01

BSDFS = {
    "roughplastic": '<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/>'
                    '<rgb name="diffuse_reflectance" value="0.2, 0.4, 0.7"/></bsdf>',
    "roughconductor": '<bsdf type="roughconductor"><string name="material" value="Au"/>'
                      '<float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.4"/></bsdf>',
    "plastic": '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5, 0.3, 0.1"/></bsdf>',
    "conductor": '<bsdf type="conductor"><string name="material" value="Cu"/></bsdf>',
    "dielectric": '<bsdf type="dielectric"/>',
    "thindielectric": '<bsdf type="thindielectric"/>',
    "roughdielectric": '<bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf>',
    "twosided-blendbsdf": '<bsdf type="twosided"><bsdf type="blendbsdf"><float name="weight" value="0.4"/>'
                          '<bsdf type="diffuse"/><bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>'
                          '</bsdf></bsdf>',
    "mask": '<bsdf type="mask"><float name="opacity" value="0.4"/><bsdf type="twosided"><bsdf type="diffuse"/>'
            '</bsdf></bsdf>',
}
N_TESTS = 3 * len(BSDFS)


def scene_xml(bsdf):
    return f'''<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="5"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 3, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RES}"/><integer name="height" value="{RES}"/>
      <rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="{SPP}"/></sampler></sensor>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/></transform>{bsdf}</shape>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="20"/>
    <translate y="-1"/></transform><bsdf type="diffuse"/></shape>
  <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/><scale value="0.6"/>
    </transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="10, 8, 6"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><translate z="-1.5"/><scale value="3"/></transform>
    <bsdf type="diffuse"/></shape>
</scene>'''


@pytest.mark.parametrize("name", sorted(BSDFS))
def test_render_matches_mitsuba(name):
    xml = scene_xml(BSDFS[name])
    mi_scene, our_scene = mi.load_string(xml), mvpt.load_string(xml)
    ours = np.array([list(mvpt.render(our_scene, seed=s + 1, threads=1).images.values())[0].mean(axis=(0, 1))
                     for s in range(N_SEEDS)])
    theirs = np.array([np.array(mi.render(mi_scene, seed=s))[..., :3].mean(axis=(0, 1)) for s in range(N_SEEDS)])
    level = 1 - (1 - ALPHA) ** (1 / N_TESTS)
    for c in range(3):
        t, p = stats.ttest_ind(ours[:, c], theirs[:, c], equal_var=False)
        assert p > level, (f"{name} channel {c}: mvpt {ours[:, c].mean():.5f} vs mitsuba {theirs[:, c].mean():.5f} "
                           f"(p = {p:.2g} <= {level:.2g})")
