"""Ranges of a render and their merge (docs/distributed.md): `passes=(first, count)` takes the
samples of those passes; the states of disjoint ranges (or seeds) merge into the render of
all of them, in one order whatever order they are given in; path tracing's merge equals the
one-process render of all the passes (under the box filter); multi-view path tracing's, and
splatting path tracing's, merged variance combines the ranges' (Chan et al.) and its merged image converges to path tracing's (block z-tests);
states that differ or share samples are refused; the command line writes the merged outputs."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mvpt
from mvpt import cli
from mitsuba_compare import compare_estimates, estimate_from_seeds

from small_scenes import slow_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes" / "mv"


def _ranges(scene, tmp_path, method, ranges, seed=1, tag=""):
    paths = []
    for first, count in ranges:
        path = tmp_path / f"{tag}{first}_{count}.mvpt-state"
        mvpt.render(scene, seed=seed, method=method, passes=(first, count), state=path)
        paths.append(path)
    return paths


def test_path_tracing_merge_is_the_whole_render(tmp_path):
    scene = mvpt.load_string(slow_scene(3, res=24))
    whole = mvpt.render(scene, seed=1, method="pt", passes=(0, 12))
    plain = mvpt.render(scene, seed=1, method="pt", spp=12)
    paths = _ranges(scene, tmp_path, "pt", [(0, 5), (5, 4), (9, 3)])
    merged = mvpt.merge(scene, paths)
    again = mvpt.merge(scene, paths[::-1], threads=1)
    assert merged.stats["passes"] == 12 and merged.stats["samples"] == whole.stats["samples"]
    for v in whole.images:
        assert np.array_equal(whole.images[v], plain.images[v])  # passes 0:12 is the 12-spp render
        assert np.array_equal(merged.images[v], again.images[v])  # one order of addition
        assert np.array_equal(merged.variance[v], again.variance[v])
        assert np.array_equal(merged.sample_count[v], whole.sample_count[v])
        # The same samples, summed in another grouping: equal up to the rounding of the sums.
        np.testing.assert_allclose(merged.images[v], whole.images[v], rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(merged.variance[v], whole.variance[v], rtol=1e-4, atol=1e-12)


@pytest.mark.parametrize("method, rfilter", [("mvpt", "box"), ("pt", "gaussian")])
def test_merged_pass_estimates_combine_the_ranges(tmp_path, method, rfilter):
    """Multi-view path tracing, and path tracing under a splatted filter, add pass estimates:
    the merged mean and variance are the ranges' combined (Chan et al.)."""
    scene = mvpt.load_file(SCENES / "cornell_phong9.xml", res=16, filter=rfilter)
    paths = _ranges(scene, tmp_path, method, [(0, 6), (6, 3)])
    a, b = (mvpt.merge(scene, [p]) for p in paths)
    merged = mvpt.merge(scene, paths)
    na, nb = 6, 3
    for v in merged.images:
        ma, mb = a.images[v].astype(np.float64), b.images[v].astype(np.float64)
        m2a = a.variance[v] * na * (na - 1.0)
        m2b = b.variance[v] * nb * (nb - 1.0)
        n = na + nb
        m2 = m2a + m2b + (mb - ma) ** 2 * na * nb / n
        np.testing.assert_allclose(merged.images[v], (na * ma + nb * mb) / n, rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(merged.variance[v], m2 / (n * (n - 1.0)), rtol=1e-3, atol=1e-9)
        assert np.array_equal(merged.sample_count[v], a.sample_count[v] + b.sample_count[v])


def test_multiview_merge_is_unbiased(tmp_path):
    """Merged ranges (each with its own control variate and adaptive maps) against path tracing."""
    scene = mvpt.load_file(SCENES / "cornell_phong9.xml", res=24)
    ids = [v["id"] for v in scene.views]
    seeds = range(8)
    pt = [mvpt.render(scene, spp=32, seed=500 + s, method="pt") for s in seeds]
    merged = []
    for s in seeds:
        paths = _ranges(scene, tmp_path, "mvpt", [(0, 7), (7, 7)], seed=600 + s, tag=f"s{s}_")
        merged.append(mvpt.merge(scene, paths))
    assert merged[0].stats["views"][ids[0]]["multiview"]["mean_sharing"] > 1.3
    rows = [(i, v, estimate_from_seeds([r.images[v] for r in merged], v),
             estimate_from_seeds([r.images[v] for r in pt], v)) for i, v in enumerate(ids)]
    res = compare_estimates("merged mvpt ranges vs pt", rows, mean_tol=0.0)
    print(res.summary())
    assert res.passed, res.summary()


def test_merge_refuses_what_does_not_fit(tmp_path):
    scene = mvpt.load_string(slow_scene(2, res=16))
    a, b = _ranges(scene, tmp_path, "mvpt", [(0, 4), (2, 4)])
    with pytest.raises(mvpt.StateError, match="passes 0:4 of seed 1.*passes 2:4 of seed 1.*share samples"):
        mvpt.merge(scene, [a, b])
    (other,) = _ranges(scene, tmp_path, "mvpt", [(2, 4)], seed=9, tag="seed9_")
    assert mvpt.merge(scene, [a, other]).stats["passes"] == 8  # other seeds: other samples
    (pt,) = _ranges(scene, tmp_path, "pt", [(4, 4)], tag="pt_")
    with pytest.raises(mvpt.StateError, match="method: 'mvpt' then, 'pt' now"):
        mvpt.merge(scene, [a, pt])
    plain = tmp_path / "plain.mvpt-state"
    mvpt.render(scene, spp=4, seed=1, method="mvpt", state=plain)
    with pytest.raises(mvpt.StateError, match="passes 0:all of seed 1"):
        mvpt.merge(scene, [plain, a])


def test_cli_ranges_and_merge(tmp_path, capsys):
    path = tmp_path / "room.xml"
    path.write_text(slow_scene(2, res=16))
    for first, out in ((0, "a"), (4, "b")):
        assert cli.main(["render", str(path), "--passes", f"{first}:4", "--method", "mvpt", "--seed", "2", "-q",
                         "--aovs", "-o", str(tmp_path / out)]) == 0
        assert (tmp_path / out / "room.mvpt-state").exists()  # a range keeps its state
    assert cli.main(["merge", str(tmp_path / "a"), str(tmp_path / "b"), "-o", str(tmp_path / "m"), "-q"]) == 0
    data = json.loads((tmp_path / "m" / "room.json").read_text())
    assert data["passes"] == 8 and len(data["settings"]["merged_from"]) == 2
    direct = mvpt.merge(mvpt.load_file(path), [tmp_path / "a" / "room.mvpt-state", tmp_path / "b" / "room.mvpt-state"])
    img = mvpt._core.read_image(str(tmp_path / "m" / "room_v0.exr"))
    assert np.array_equal(img, direct.images["v0"])
    capsys.readouterr()
    assert cli.main(["render", "--resume", str(tmp_path / "m"), "-q"]) == 1
    assert "it is a merge of 2 states" in capsys.readouterr().err
    assert cli.main(["merge", str(tmp_path / "a"), str(tmp_path / "a"), "-o", str(tmp_path / "x"), "-q"]) == 1
    assert "share samples" in capsys.readouterr().err
    assert cli.main(["render", str(path), "--passes", "0:4", "--spp", "4"]) == 2
    assert cli.main(["render", str(path), "--passes", "4"]) == 2


def test_merge_refuses_an_interrupted_range(tmp_path):
    """A range stopped before its end (here 0:4 whole and 4:400 after some passes) is resumed,
    not merged: the merge names the passes missing and writes no state."""
    scene = mvpt.load_string(slow_scene(2, res=16))
    (a,) = _ranges(scene, tmp_path, "mvpt", [(0, 4)])
    b = tmp_path / "b.mvpt-state"

    def stop_soon(progress):  # once a pass is done, whatever the machine's speed
        if progress["pass"] >= 1:
            raise KeyboardInterrupt

    cut = mvpt.render(scene, seed=1, method="mvpt", passes=(4, 396), state=b, progress=stop_soon, poll=0.001)
    assert cut.stats["cancelled"] and 0 < cut.stats["passes"] < 396
    merged = tmp_path / "m.mvpt-state"
    with pytest.raises(mvpt.StateError, match=rf"hold {4 + cut.stats['passes']} of the 400 passes .* interrupted"):
        mvpt.merge(scene, [a, b], state=merged)
    assert not merged.exists() and not list(tmp_path.glob("m.mvpt-state*"))
    done = mvpt.render(scene, seed=1, method="mvpt", passes=(4, 396), state=b, resume=b)
    assert not done.stats["cancelled"]
    whole = mvpt.merge(scene, [a, b], state=merged)
    assert whole.stats["passes"] == 400 and merged.exists()
    assert whole.stats["settings"]["passes"] is None and whole.stats["settings"]["parts"] == [[1, 0, 4], [1, 4, 396]]
