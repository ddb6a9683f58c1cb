"""Pixel filters against Mitsuba 3: path tracing with each of Mitsuba's reconstruction filters
converges to Mitsuba's image of the same scene (tests/scenes/filters/checkerboard.xml: sharp
edges of a checkerboard floor and a sphere against the sky, three cameras, one with a crop
window), and a film without a filter is Mitsuba's default gaussian.

Mitsuba splats each sample into every pixel its filter reaches and divides by the sum of the
weights; mvpt's path tracing splats too, each pass's splats one estimate with a control
variate for the sum of the weights. Neighbouring pixels of both are correlated: each side is
estimated from independent seeds on 2×2 blocks of pixels, averaged per seed before the spread
is taken. At equal samples, mvpt's pixels are as precise as Mitsuba's, for both methods. The
reference is Mitsuba's `llvm_ad_rgb`,
which evaluates the filters exactly (`scalar_rgb` reads them from a table of 31 steps per
radius); its float32 sums of normalised weights are off by about 1e-4 where the image is
flat, which `sys_rel` covers. The films sample their borders (`sample_border`), as mvpt
always does."""
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mitsuba_compare as mc  # noqa: E402

pytest.importorskip("mitsuba")
mvpt = pytest.importorskip("mvpt")

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "filters" / "checkerboard.xml"


@pytest.fixture(autouse=True)
def _restore_mitsuba_variant():
    """These tests switch Mitsuba to `llvm_ad_rgb`; other modules keep objects of the variant
    they set when they were imported."""
    import mitsuba as mi
    before = mi.variant()
    yield
    if before and mi.variant() != before:
        mi.set_variant(before)
BLOCK = 2
SEEDS = 16
MITSUBA_SPP = 32  # per seed
MVPT_SPP = 64  # per seed


def _mitsuba(rfilter: str) -> list:
    mi = mc._mitsuba("llvm_ad_rgb")
    scene = mi.load_file(str(SCENE), filter=rfilter)
    out = []
    for i, _ in enumerate(scene.sensors()):
        seeds = [np.array(mi.render(scene, sensor=i, seed=1 + SEEDS * i + k, spp=MITSUBA_SPP)) for k in range(SEEDS)]
        out.append(mc.block_estimate_from_seeds(seeds, BLOCK, "mitsuba"))
    return out


def _mvpt(rfilter: str) -> list:
    scene = mvpt.load_file(SCENE, filter=rfilter)
    runs = [mvpt.render(scene, spp=MVPT_SPP, seed=5 + k) for k in range(SEEDS)]
    return [(vid, mc.block_estimate_from_seeds([r.images[vid] for r in runs], BLOCK, "mvpt")) for vid in runs[0].view_ids]


def _compare(mitsuba_filter: str, mvpt_filter: str) -> mc.CompareResult:
    pairs = [(i, vid, a, b) for i, ((vid, a), b) in enumerate(zip(_mvpt(mvpt_filter), _mitsuba(mitsuba_filter)))]
    return mc.compare_estimates(f"mvpt {mvpt_filter} vs Mitsuba {mitsuba_filter}", pairs, block=1, sys_rel=1e-3)


@pytest.mark.parametrize("rfilter", ["box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"])
def test_filter_matches_mitsuba(rfilter):
    res = _compare(rfilter, rfilter)
    print(res.summary())
    assert res.passed, res.summary()


@pytest.mark.parametrize("mitsuba_filter, mvpt_filter", [("mitchell", "catmullrom"), ("lanczos", "gaussian")])
def test_another_filter_is_detected(mitsuba_filter, mvpt_filter):
    """The comparison tells filters apart: Catmull-Rom is Mitchell-Netravali with other B and C."""
    res = _compare(mitsuba_filter, mvpt_filter)
    assert not res.passed and res.block_failures, res.summary()


@pytest.mark.parametrize("method", ["pt", "mvpt"])
@pytest.mark.parametrize("rfilter", ["tent", "gaussian", "mitchell", "lanczos"])
def test_splats_are_as_precise_as_mitsubas(rfilter, method):
    """Both methods splat each sample over the pixels its filter reaches, each pass one
    estimate, the first two passes each the other's control variate: per pixel as precise as
    Mitsuba's normalised splatting at equal samples (measured 1.01-1.13 times its variance).
    Path tracing by filter importance sampling had 3.7-13 times Mitsuba's variance here (each
    sample in one pixel); where the filter has negative lobes, a held pass's ratio whose W
    nears 0 is not used (using it gave `lanczos` 12 times Mitsuba's variance at 16 spp)."""
    seeds, spp = 16, 16
    mi = mc._mitsuba("llvm_ad_rgb")
    s_mi = mi.load_file(str(SCENE), filter=rfilter)
    ref = [np.array(mi.render(s_mi, sensor=0, seed=1 + k, spp=spp), np.float64) for k in range(seeds)]
    s = mvpt.load_file(SCENE, filter=rfilter)
    ours = [np.asarray(mvpt.render(s, spp=spp, seed=100 + k, method=method, views=["front"]).images["front"],
                       np.float64) for k in range(seeds)]
    ratio = np.var(ours, axis=0, ddof=1).mean() / np.var(ref, axis=0, ddof=1).mean()
    print(f"{rfilter}, {method}: per-pixel variance, mvpt / Mitsuba = {ratio:.3f}")
    assert ratio < 1.5, ratio


def test_a_film_without_a_filter_is_gaussian():
    """Mitsuba 3 (and 0.6) give a film without an rfilter a gaussian of stddev 0.5."""
    xml = SCENE.read_text()
    assert xml.count('<rfilter type="$filter"/>') == 3
    bare = mvpt.load_string(xml.replace('<rfilter type="$filter"/>', ""), SCENE.parent)
    a = mvpt.render(bare, spp=4, seed=1)
    b = mvpt.render(mvpt.load_file(SCENE, filter="gaussian"), spp=4, seed=1)
    c = mvpt.render(mvpt.load_file(SCENE, filter="box"), spp=4, seed=1)
    for vid in a.view_ids:
        assert a.images[vid].tobytes() == b.images[vid].tobytes()
        assert a.images[vid].tobytes() != c.images[vid].tobytes()
