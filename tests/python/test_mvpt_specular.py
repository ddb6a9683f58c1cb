"""Paths from purely specular first vertices (glass, a mirror), which no view can share, are
split K ways by multi-view path tracing (`delta_splits`, docs/multiview-path-tracing.md,
"Where nothing can be shared"): the images still converge to path tracing's (block tests over
independent seeds, as test_mvpt_unbiased.py, with no tolerance), under a box and a gaussian
filter, with K chosen by the pilot and fixed; and the split paths do lower those pixels'
variance."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mvpt
from mitsuba_compare import block_estimate_from_seeds, compare_estimates

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "mv" / "specular.xml"
SEEDS = 16


def _scene(filter_: str, options: str = ""):
    xml = SCENE.read_text().replace('<integrator type="$integrator">', f'<integrator type="mvpath">{options}', 1)
    return mvpt.load_string(xml, SCENE.parent, filter=filter_)


def _estimates(scene, spp: int, method: str, base: int):
    """Per view, 8x8 block means of independent seeds: a filter wider than a pixel correlates
    neighbouring pixels, so each block's variance comes from the spread of its seeds' means."""
    runs = [mvpt.render(scene, spp=spp, seed=base + i, method=method) for i in range(SEEDS)]
    ids = list(runs[0].images)
    return runs, {v: block_estimate_from_seeds([r.images[v] for r in runs], 8, v) for v in ids}


@pytest.fixture(scope="module", params=["box", "gaussian"])
def reference(request):
    runs, est = _estimates(_scene(request.param), 24, "pt", 1000)
    return request.param, est


@pytest.mark.parametrize("delta_splits", ["auto", 4])
def test_split_specular_paths_are_unbiased(reference, delta_splits):
    filter_, pt = reference
    option = (f'<string name="delta_splits" value="auto"/>' if delta_splits == "auto"
              else f'<integer name="delta_splits" value="{delta_splits}"/>')
    runs, mv = _estimates(_scene(filter_, option), 8, "mvpt", 3000)
    k = runs[0].stats["delta_splits"]
    assert k > 1 if delta_splits == "auto" else k == delta_splits, k
    res = compare_estimates(f"specular ({filter_}) mvpt delta_splits={k} vs pt",
                            [(i, v, mv[v], pt[v]) for i, v in enumerate(pt)], block=1, mean_tol=0.0)
    print(res.summary())
    assert res.passed, res.summary()


def test_split_paths_lower_the_variance_of_specular_pixels():
    # Pixels whose samples no view shares (received contributions per native sample below 1.5)
    # are the spheres': four paths per sample must lower their variance of the mean at equal
    # native samples by well over a third (a quarter of it where the suffix is all of it).
    one = [mvpt.render(_scene("box", '<integer name="delta_splits" value="1"/>'), spp=8, seed=s, method="mvpt")
           for s in range(6)]
    four = [mvpt.render(_scene("box", '<integer name="delta_splits" value="4"/>'), spp=8, seed=s, method="mvpt")
            for s in range(6)]
    ratios = []
    for v in one[0].images:
        unshared = one[0].contributions[v] / np.maximum(one[0].sample_count[v], 1) < 1.5
        assert unshared.mean() > 0.05, unshared.mean()  # the spheres cover a part of every view
        var1 = np.stack([r.images[v] for r in one]).var(axis=0, ddof=1)[unshared].mean()
        var4 = np.stack([r.images[v] for r in four]).var(axis=0, ddof=1)[unshared].mean()
        ratios.append(var4 / var1)
    assert np.mean(ratios) < 0.65, ratios
