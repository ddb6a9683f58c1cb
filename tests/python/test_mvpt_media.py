"""Multi-view path tracing through participating media (design doc §10) converges to the
volumetric path tracer: the shared vertex is the first surface that is not null, each view's
share is weighted by its own camera segment's transmittance (exact, or ratio-tracked in a
grid), and the in-scattering along the native camera segment stays with the native view
(heterogeneous media) or is shared as medium vertices (homogeneous ones).

Four small scenes seen by a 2x2 rig (fog around a rough metal ball, a heterogeneous grid
around a diffuse ball, a camera inside thin fog, an absorbing rough-glass ball), each
rendered by `volpath` with both methods over K independent seeds and compared by the block
t-tests of mitsuba_compare with no tolerance (mean_tol = 0), as test_mvpt_unbiased.py does
for surfaces. Where the media are homogeneous the scatterings on camera segments are shared
too (medium vertices); a fifth scene of dense fog seen from far-apart views makes their
densities differ from view to view."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from media_scenes import LIGHTS, blob_grid, heterogeneous, homogeneous, medium_xml, write_vol  # noqa: E402
from mitsuba_compare import ImageEstimate, compare_estimates, estimate_from_seeds  # noqa: E402

mvpt = pytest.importorskip("mvpt")

K = 8  # independent seeds per estimate
RIG = "grid:2x2,spacing=0.35"
WIDE_RIG = "grid:2x2,spacing=1.5"
PT_SPP, MV_SPP = 48, 24

SENSOR = """<sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0.3, 1.2, 4.5" target="0, 0.1, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="18"/><rfilter type="box"/></film>
    {medium}</sensor>"""


def _scene(body: str, sensor_medium: str = "") -> str:
    return f"""<scene version="3.0.0">
  <integrator type="volpath"><integer name="max_depth" value="24"/></integrator>
  {SENSOR.format(medium=sensor_medium)}
  {LIGHTS}
  {body}
</scene>"""


def _ball(bsdf: str, radius: float = 0.35, media: str = "") -> str:
    return (f'<shape type="sphere"><point name="center" x="0" y="0.1" z="0"/><float name="radius" value="{radius}"/>'
            f'{bsdf}{media}</shape>')


METAL = '<bsdf type="roughconductor"><string name="material" value="Au"/><float name="alpha" value="0.25"/></bsdf>'


def _cases(tmp: Path) -> dict:
    fog = homogeneous('<rgb name="sigma_t" value="1.2, 0.8, 0.5"/><float name="albedo" value="0.8"/>',
                      '<phase type="hg"><float name="g" value="0.5"/></phase>')
    vol = write_vol(tmp / "blob.vol", blob_grid(12))
    grid = heterogeneous(vol, '<float name="scale" value="2.5"/><float name="albedo" value="0.7"/>')
    thin = homogeneous('<float name="sigma_t" value="0.15"/><float name="albedo" value="0.9"/>')
    dense = homogeneous('<rgb name="sigma_t" value="3, 2, 1.4"/><float name="albedo" value="0.9"/>',
                        '<phase type="hg"><float name="g" value="-0.3"/></phase>')
    ink = homogeneous('<rgb name="sigma_t" value="2, 1, 0.4"/><float name="albedo" value="0"/>')
    glass = '<bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf>'
    return {
        "fog-metal": _scene(_ball('<bsdf type="null"/>', 0.9, medium_xml(fog, "interior")) + _ball(METAL)),
        "grid-diffuse": _scene('<shape type="cube"><bsdf type="null"/>' + medium_xml(grid, "interior") + "</shape>"
                               + _ball('<bsdf type="diffuse"/>', 0.3)),
        "dense-fog-wide": _scene(_ball('<bsdf type="null"/>', 0.9, medium_xml(dense, "interior"))
                                 + _ball('<bsdf type="diffuse"/>', 0.3)),
        "camera-in-fog": _scene(_ball(METAL, 0.5), medium_xml(thin, "medium")),
        "absorbing-glass": _scene(_ball(glass, 0.5, medium_xml(ink, "interior"))),
    }


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    return _cases(tmp_path_factory.mktemp("mv_media"))


def _estimates(scene, spp, method, base, splits=None):
    runs = [mvpt.render(scene, spp=spp, seed=base + i, method=method, splits=splits) for i in range(K)]
    ids = [v["id"] for v in scene.views]
    return runs, {v: estimate_from_seeds([r.images[v] for r in runs], v) for v in ids}


@pytest.mark.parametrize("name,splits", [(n, None) for n in ["fog-metal", "grid-diffuse", "dense-fog-wide",
                                                               "camera-in-fog", "absorbing-glass"]]
                         + [("fog-metal", 3), ("grid-diffuse", 3)])
def test_balance_through_media_is_unbiased(cases, name, splits):
    # Dense fog seen from far apart: the views' segments to a medium vertex differ in
    # transmittance, so its densities (§10) must be each view's own. The splits chosen for
    # these scenes are mostly one; three (over the three emitters, stratified) are tested too.
    scene = mvpt.load_string(cases[name], rig=WIDE_RIG if name == "dense-fog-wide" else RIG)
    ids = [v["id"] for v in scene.views]
    assert len(ids) == 4
    _, pt = _estimates(scene, PT_SPP, "pt", 1000)
    runs, mv = _estimates(scene, MV_SPP, "mvpt", 2000, splits)
    assert runs[0].stats["method"] == "mvpt"
    assert splits is None or runs[0].stats["splits"] == splits
    for v in ids:  # the test must see real sharing through the media
        sharing = runs[0].stats["views"][v]["multiview"]["mean_sharing"]
        assert sharing > 1.5, (v, sharing)
    res = compare_estimates(f"{name}: mvpt vs volpath", [(i, v, mv[v], pt[v]) for i, v in enumerate(ids)], mean_tol=0.0)
    print(res.summary())
    assert res.passed, res.summary()


@pytest.mark.parametrize("name", ["grid-diffuse", "fog-metal"])
def test_balance_weights_sum_to_one_through_media(cases, name):
    """Visibility through media (only surfaces that are not null block) is the same for every
    strategy, so the balance weights of a pixel still sum to one per pass in expectation; the
    medium vertices' contributions (fog-metal) add no weight."""
    scene = mvpt.load_string(cases[name], rig=RIG)
    ids = [v["id"] for v in scene.views]
    runs = [mvpt.render(scene, spp=MV_SPP, seed=3000 + i, method="mvpt") for i in range(K)]
    ones, w = {}, {}
    for v in ids:
        shape = runs[0].weight_sum[v].shape + (3,)
        ones[v] = ImageEstimate(np.ones(shape), np.zeros(shape), np.full(shape, np.inf), "1")
        w[v] = estimate_from_seeds([np.repeat(r.weight_sum[v][..., None], 3, axis=2) for r in runs], v)
    res = compare_estimates(f"{name}: sum of W per pass vs 1", [(i, v, w[v], ones[v]) for i, v in enumerate(ids)],
                            mean_tol=0.0)
    print(res.summary())
    assert res.passed, res.summary()


@pytest.mark.parametrize("name", ["grid-diffuse", "fog-metal"])
def test_media_renders_are_bit_identical_for_any_thread_count(cases, name):
    scene = mvpt.load_string(cases[name], rig=RIG)
    runs = [mvpt.render(scene, spp=4, seed=9, threads=t, method="mvpt") for t in (1, 2, 3)]
    for r in runs[1:]:
        for vid in runs[0].view_ids:
            assert np.array_equal(r.images[vid], runs[0].images[vid])
