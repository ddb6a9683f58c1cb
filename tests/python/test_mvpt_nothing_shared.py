"""Where no two views can share a path in time, multi-view path tracing renders as path tracing
(docs/multiview-path-tracing.md, "Where nothing can be shared"): one view, or views of moving
shapes whose shutters do not overlap. The images are path tracing's, bit for bit."""
from pathlib import Path

import numpy as np

import mvpt

MOVING = Path(__file__).resolve().parents[1] / "scenes" / "mv" / "moving.xml"


def render(views, method, spp=4):
    return mvpt.render(mvpt.load_file(MOVING, res=16), spp=spp, seed=7, views=views, method=method)


def test_shutters_that_only_touch_are_path_traced():
    # f0 is open over [0, 0.5] and f2 over [0.5, 1] while a sphere and a cube move.
    mv, pt = render(["f0", "f2"], "mvpt"), render(["f0", "f2"], "pt")
    assert mv.stats["method"] == "pt"
    assert any("nothing to share" in n for n in mv.stats["notes"]), mv.stats["notes"]
    for v in ("f0", "f2"):
        assert np.array_equal(mv.images[v], pt.images[v])


def test_one_view_is_path_traced():
    mv, pt = render(["f1"], "mvpt"), render(["f1"], "pt")
    assert mv.stats["method"] == "pt"
    assert np.array_equal(mv.images["f1"], pt.images["f1"])


def test_overlapping_shutters_still_share():
    # f0 [0, 0.5] and f1 [0.25, 0.75] overlap: the method shares their first vertices.
    r = render(["f0", "f1"], "mvpt", spp=1)
    assert r.stats["method"] == "mvpt"
    assert r.stats["multiview"]["mean_sharing"] > 1.0
    assert not any("nothing to share" in n for n in r.stats["notes"])
