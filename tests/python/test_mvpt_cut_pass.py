"""A first pass of multi-view path tracing cut short (Ctrl-C, a time budget shorter than one
pass) keeps the regions it finished, scaled by the inverse of their share
(docs/multiview-path-tracing.md, "A first pass cut short"): its image is an unbiased estimate, its
native sample counts say which pixels sampled, and a time budget shorter than a pass is met.
Passes thinned to what is left of a time budget ("Passes thinned to the budget") are unbiased
too, and the budget is used.

The statistical test renders many seeds of a pass cut after its first chunk (the probe stops
the render there, so that the share kept depends on the thread count alone), averages them in
groups, and compares the groups with whole passes of multi-view path tracing: Welch tests of
every 8x8 block's mean and of each image's mean, Sidak-corrected, no tolerance. A cut pass's
pixels are not independent (a region is in or out as a whole), so the variances come from the
spread of the groups' block means themselves, not from pixel variances pooled over a block."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

import mvpt
from scipy import stats
from small_scenes import slow_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes" / "mv"
RES = 32          # 2 x 2 regions of 16^2 tiles in each of the 9 views
# 256 cut passes: the missing scale-up (a mean 4 or 9 times too low) is found with p ~ 1e-29
# at a level of 2e-5, the thinned passes' missing weights and a mean 2 % low with p < 1e-10.
GROUPS, PER_GROUP = 16, 16


def _cut_runs(xml: str, seeds):
    probes = pytest.importorskip("mvpt._probes")
    return probes.render_cut_first_pass(xml, list(seeds), 1)


def _summaries(images) -> np.ndarray:
    """Per image (RES x RES x 3): its 8x8 blocks' means and its own mean, per channel."""
    a = np.asarray(images, dtype=np.float64)
    blocks = a.reshape(len(a), RES // 8, 8, RES // 8, 8, 3).mean(axis=(2, 4)).reshape(len(a), -1)
    return np.concatenate([blocks, a.mean(axis=(1, 2))], axis=1)


def _welch_p(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Two-sided p-values of Welch's t-test between the rows of a and of b, per column."""
    va, vb = a.var(0, ddof=1) / len(a), b.var(0, ddof=1) / len(b)
    se2 = va + vb
    assert (se2 > 0).all()
    t = (a.mean(0) - b.mean(0)) / np.sqrt(se2)
    nu = se2 ** 2 / (va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1))
    return 2 * stats.t.sf(np.abs(t), nu)


def _min_p(runs, whole, ids, scale: float = 1.0):
    """The smallest p-value over every view's blocks and means, and the number of tests."""
    ps = []
    for i, v in enumerate(ids):
        cut = np.stack([np.asarray(r[0][i]).reshape(RES, RES, 3) * scale for r in runs])
        groups = cut.reshape(GROUPS, -1, RES, RES, 3).mean(axis=1)
        ps.append(_welch_p(_summaries(groups), _summaries([r.images[v] for r in whole])))
    ps = np.concatenate(ps)
    return ps.min(), ps.size


def _cornell(rfilter: str):
    """The 9-view Phong Cornell box at RES^2 with the filter `rfilter`: its XML, scene and view ids."""
    xml = (SCENES / "cornell_phong9.xml").read_text()
    xml = xml.replace('<default name="res" value="32"/>', f'<default name="res" value="{RES}"/>')
    xml = xml.replace('<default name="filter" value="box"/>', f'<default name="filter" value="{rfilter}"/>')
    assert rfilter in xml
    scene = mvpt.load_string(xml, SCENES)
    return xml, scene, [v["id"] for v in scene.views]


@pytest.mark.parametrize("rfilter", ["box", "gaussian"])
def test_cut_first_pass_is_unbiased(rfilter):
    xml, scene, ids = _cornell(rfilter)
    runs = _cut_runs(xml, range(100, 100 + GROUPS * PER_GROUP))
    share = runs[0][1]
    # One chunk of one thread (two tiles) ends with the first region: one of the 4 (box) or
    # of the 9 of the sample windows grown by the gaussian's reach.
    assert all(r[1] == share for r in runs) and share == (0.25 if rfilter == "box" else 1 / 9), share
    whole = [mvpt.render(scene, spp=16, seed=7000 + i, method="mvpt") for i in range(8)]
    p, tests = _min_p(runs, whole, ids)
    level = 1.0 - (1.0 - 0.01) ** (1.0 / tests)  # Sidak: 1 % false alarms over all tests
    print(f"cut first pass ({rfilter}, share {share:.3f}): smallest p {p:.3g} of {tests} tests, level {level:.3g}")
    assert p > level
    # The test can fail: the same passes not scaled up are found out.
    assert _min_p(runs, whole, ids, share)[0] < level


THIN = 0.3  # the share of its native samples the thinned last pass takes


@pytest.mark.parametrize("rfilter,passes,thinned,runs", [("box", 2, 1, 256), ("gaussian", 2, 1, 256), ("box", 6, 4, 128)])
def test_thinned_passes_are_unbiased(rfilter, passes, thinned, runs):
    """Whole passes and `thinned` last passes thinned to 30 % of their native samples, their
    sums scaled by 1/0.3 and weighing 0.3 (docs/multiview-path-tracing.md, "Passes thinned to
    the budget"), against whole passes. With 2 passes the thinned one folds with the held
    first (each the other's control variate); with 6, passes 3-6 are thinned, each numbering
    its samples on from those the last took, and the last two take adaptive maps (1.25 native
    samples per pixel on average, from the fifth pass on). The same renders with the thinned
    passes weighing one and not scaled fail, and so do those whose mean is 2 % too low."""
    probes = pytest.importorskip("mvpt._probes")
    xml, scene, ids = _cornell(rfilter)
    runs = probes.render_thinned_last_pass(xml, list(range(300, 300 + runs)), passes, THIN, thinned)
    assert all(r[2] == THIN for r in runs)
    if passes == 2:
        # Each pixel took its first pass's native sample and each of the thinned pass's with
        # probability 0.3: the mean share over all runs, views and pixels is 0.3 within 5 sigma.
        taken = np.array([[s - RES * RES for s in r[1]] for r in runs], dtype=np.float64) / (RES * RES)
        draws = taken.size * RES * RES
        assert abs(taken.mean() - THIN) < 5.0 * np.sqrt(THIN * (1 - THIN) / draws), taken.mean()
    whole = [mvpt.render(scene, spp=16, seed=8000 + i, method="mvpt") for i in range(8)]
    p, tests = _min_p(runs, whole, ids)
    level = 1.0 - (1.0 - 0.01) ** (1.0 / tests)
    print(f"thinned passes ({rfilter}, {thinned} of {passes}, share {THIN}): smallest p {p:.3g} of {tests} tests, "
          f"level {level:.3g}")
    assert p > level
    # The test can fail: the thinned passes weighing one, unscaled, give (passes - thinned +
    # 0.3 thinned) / passes of the mean; a mean 2 % low is found out too.
    assert _min_p(runs, whole, ids, (passes - thinned + thinned * THIN) / passes)[0] < level
    assert _min_p(runs, whole, ids, 0.98)[0] < level


# 32 views of 96^2 of the closed room: one pass is about a second on two cores.
VIEWS, SLOW_RES = 32, 96


@pytest.fixture(scope="module")
def many_views():
    # Two splits: under a time budget `auto` would choose its splits by the budget, and with
    # them the length of a pass that the budgets below are set from.
    xml = slow_scene(VIEWS, res=SLOW_RES, spp=64)
    assert '<integrator type="path">' in xml
    return mvpt.load_string(xml.replace('<integrator type="path">',
                                        '<integrator type="mvpath"><integer name="splits" value="2"/>', 1))


def _regions_sampled(r) -> int:
    """The 16^2 regions of every view sampled once (the others not at all), checked so."""
    sampled = 0
    for count in r.sample_count.values():
        for y in range(0, SLOW_RES, 16):
            for x in range(0, SLOW_RES, 16):
                tile = count[y:y + 16, x:x + 16]
                assert (tile == tile[0, 0]).all() and tile[0, 0] in (0, 1)
                sampled += int(tile[0, 0])
    return sampled


@pytest.fixture(scope="module")
def whole_pass(many_views):
    return mvpt.render(many_views, spp=1, method="mvpt", seed=3)


def test_time_budget_shorter_than_a_pass(many_views, whole_pass):
    budget = 0.3 * whole_pass.stats["max_pass_seconds"]
    r = mvpt.render(many_views, time=budget, method="mvpt", seed=3)
    assert r.stats["seconds"] <= budget + 0.5, (r.stats["seconds"], budget)
    share = r.stats["cut_pass_share"]
    assert r.stats["passes"] == 1 and 0.0 < share < 1.0 and not r.stats["cancelled"], r.stats
    sampled = _regions_sampled(r)
    assert sampled == round(share * VIEWS * (SLOW_RES // 16) ** 2)
    assert r.stats["samples"] == sampled * 16 * 16
    # Every pixel has an estimate: the regions not sampled received what other views shared.
    for v, img in r.images.items():
        assert np.isfinite(img).all() and img.mean() > 0.2 * whole_pass.images[v].mean(), v


def test_time_budget_thins_passes(many_views, whole_pass):
    """With 2.5 passes' time, the render does not stop after two: after the first, passes
    thinned to what is left run, at least three in all, and use the budget."""
    budget = 2.5 * whole_pass.stats["max_pass_seconds"]
    # What a thinned pass takes is judged from the passes before it; when this machine's load
    # slows a pass after that judgement, the pass would end past the budget and is dropped
    # (by design), leaving two. So up to three renders, the first that ran three checked.
    runs = []
    for seed in (3, 4, 5):
        r = mvpt.render(many_views, time=budget, method="mvpt", seed=seed)
        assert 0.85 * budget <= r.stats["seconds"] <= budget + 0.5, (r.stats["seconds"], budget)
        assert not r.stats["cancelled"] and r.stats["passes"] >= 1, r.stats
        runs.append(r.stats["passes"])
        if r.stats["passes"] >= 3:
            break
    thinned, shares, passes = r.stats["thinned_passes"], r.stats["thinned_shares"], r.stats["passes"]
    assert passes >= 3 and thinned >= 1, (runs, r.stats)
    # Thinned shares lie in [MinThinShare, 1): where they fall depends on how long this
    # machine's passes take under its load at the time, which the budget was measured without.
    assert 0.1 * thinned <= shares < thinned, r.stats
    # Every pixel took one native sample in each whole pass; in a thinned one, some did.
    whole = passes - thinned
    counts = np.stack(list(r.sample_count.values()))
    assert counts.min() >= whole and counts.max() <= passes and r.stats["samples"] == counts.sum()
    assert abs((counts - whole).mean() - shares) < 0.02, ((counts - whole).mean(), shares)
    for v, img in r.images.items():
        assert np.isfinite(img).all() and abs(img.mean() / whole_pass.images[v].mean() - 1.0) < 0.2, v


def test_ctrl_c_in_the_first_pass_keeps_its_regions_and_resumes(many_views, whole_pass, tmp_path):
    if whole_pass.stats["max_pass_seconds"] < 0.6:
        pytest.skip("one pass is too short here to be interrupted in its middle")

    def stop(p):
        if p["samples"] > 0:  # the first chunk is done
            raise KeyboardInterrupt

    state = tmp_path / "cut.mvpt-state"
    r = mvpt.render(many_views, spp=2, method="mvpt", seed=3, poll=0.02, progress=stop, state=state)
    share = r.stats["cut_pass_share"]
    assert r.stats["cancelled"] and r.stats["passes"] == 1 and 0.0 < share < 1.0, r.stats
    assert _regions_sampled(r) == round(share * VIEWS * (SLOW_RES // 16) ** 2)
    # Resumed, it renders whole passes until the mean reaches 2 native samples per pixel: two,
    # after the cut one, each pixel's next samples.
    more = mvpt.render(many_views, spp=2, method="mvpt", seed=3, resume=state)
    assert more.stats["passes"] == 3 and more.stats["cut_pass_share"] == 0.0, more.stats
    for v, count in more.sample_count.items():
        assert np.array_equal(count, r.sample_count[v] + 2), v
