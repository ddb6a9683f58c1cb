"""A sample's random numbers depend only on (seed, view, pixel, sample index, dimension):
images are bit-identical for any thread count, across runs, and whichever other views are
rendered; a different seed gives a different image."""
from __future__ import annotations

import numpy as np
import pytest

import mvpt

from small_scenes import ROOM, scene, sensor, views

SAMPLERS = ["independent", "ldsampler"]


@pytest.fixture(scope="module", params=SAMPLERS)
def three_views(request):
    """Three 24x24 views of a closed room (long paths, several tiles per view)."""
    return mvpt.load_string(scene(views(3, res=24, spp=6, sampler=request.param), geometry=ROOM, max_depth=-1))


def _assert_identical(a: mvpt.RenderResult, b: mvpt.RenderResult, ids=None) -> None:
    for vid in ids or a.images:
        for name in ("images", "variance", "sample_count"):
            x, y = getattr(a, name)[vid], getattr(b, name)[vid]
            assert x.shape == y.shape
            # Bit-identical: compare the raw bytes, so that even NaN payloads or -0 would count.
            assert x.tobytes() == y.tobytes(), f"{name} of view {vid} differs"


def test_threads_1_vs_2(three_views):
    one = mvpt.render(three_views, threads=1)
    two = mvpt.render(three_views, threads=2)
    assert one.stats["threads"] == 1 and two.stats["threads"] == 2
    _assert_identical(one, two)
    for key in ("samples", "rays", "nonfinite_samples"):
        assert one.stats[key] == two.stats[key]
    assert all(img.mean() > 0 for img in one.images.values())


def test_two_runs(three_views):
    _assert_identical(mvpt.render(three_views, threads=2), mvpt.render(three_views, threads=2))


def test_subset_of_views(three_views):
    """A view's image does not depend on which other views are rendered, nor on their order."""
    full = mvpt.render(three_views, threads=2)
    only_v1 = mvpt.render(three_views, threads=2, views=["v1"])
    assert list(only_v1.images) == ["v1"]
    _assert_identical(full, only_v1, ["v1"])
    reordered = mvpt.render(three_views, threads=2, views=[2, 0])
    assert list(reordered.images) == ["v2", "v0"]
    _assert_identical(full, reordered, ["v0", "v2"])


def test_seed_changes_image(three_views):
    a = mvpt.render(three_views, seed=1)
    b = mvpt.render(three_views, seed=2)
    for vid in a.images:
        diff = np.abs(a.images[vid] - b.images[vid])
        # Independent estimates: most pixels differ (a few dark background pixels may agree).
        assert (diff > 0).mean() > 0.5, f"view {vid}: seeds 1 and 2 give nearly the same image"
    _assert_identical(a, mvpt.render(three_views, seed=1))


@pytest.mark.parametrize("sampler", SAMPLERS)
def test_seed_option_equals_sampler_seed(sampler):
    """render(seed=s) is the same as a scene whose samplers have seed s."""
    base = mvpt.load_string(scene(views(2, res=16, spp=3, sampler=sampler)))
    seeded = mvpt.load_string(scene(views(2, res=16, spp=3, sampler=sampler).replace(
        '<integer name="seed" value="0"/>', '<integer name="seed" value="7"/>')))
    _assert_identical(mvpt.render(base, seed=7), mvpt.render(seeded))
    _assert_identical(mvpt.render(base), mvpt.render(seeded, seed=0))


def test_time_budget_prefix_matches_spp():
    """Passes are the same samples whatever stops the render: a cancelled or budgeted
    render with k passes equals the spp=k render."""
    s = mvpt.load_string(scene(views(2, res=16, spp=64)))
    budget = mvpt.render(s, time=0.05, threads=2)
    k = budget.stats["passes"]
    assert k >= 1
    _assert_identical(budget, mvpt.render(s, spp=k, threads=1))


def _filtered_room(rfilter: str, spp: int):
    """Three views of the closed room with filter `rfilter`, the second with a crop window."""
    film = f'<rfilter type="{rfilter}"/>'
    crop = film + ('<integer name="crop_offset_x" value="5"/><integer name="crop_offset_y" value="3"/>'
                   '<integer name="crop_width" value="17"/><integer name="crop_height" value="14"/>')
    sensors = "".join(sensor(id=f"v{i}", res=24, spp=spp, origin=f"{0.3 * i - 0.3:.2f}, 1.2, 4",
                             film_extra=crop if i == 1 else film) for i in range(3))
    return mvpt.load_string(scene(sensors, geometry=ROOM, max_depth=-1))


@pytest.mark.parametrize("rfilter", ["box", "tent", "gaussian", "lanczos"])
def test_multiview_threads_1_2_3(rfilter):
    """Multi-view path tracing splats into shared fixed-point sums from every thread, with the
    sensor's filter over several pixels, crop windows and adaptive passes included: the
    images and sample maps are the same bits for 1, 2 and 3 threads."""
    s = _filtered_room(rfilter, spp=7)
    runs = [mvpt.render(s, method="mvpt", threads=t) for t in (1, 2, 3)]
    assert runs[0].stats["multiview"]["mean_sharing"] > 1.5  # the views do share
    assert runs[0].stats["passes"] > 4  # adaptive passes after the warm-up
    for r in runs[1:]:
        _assert_identical(runs[0], r)
        for vid in r.images:
            assert r.contributions[vid].tobytes() == runs[0].contributions[vid].tobytes()
            assert r.weight_sum[vid].tobytes() == runs[0].weight_sum[vid].tobytes()


@pytest.mark.parametrize("rfilter", ["tent", "gaussian", "lanczos"])
def test_path_tracing_splats_threads_1_2_3(rfilter):
    """Under a filter other than the box, path tracing splats each sample into every pixel the
    filter reaches, from tiles over the crop window and its margin, in shared fixed-point sums:
    the same bits for 1, 2 and 3 threads, crop windows included, and another seed differs."""
    s = _filtered_room(rfilter, spp=21)
    runs = [mvpt.render(s, method="pt", threads=t) for t in (1, 2, 3)]
    assert runs[0].stats["passes"] == 21 and not runs[0].contributions  # path tracing, no multi-view AOVs
    for r in runs[1:]:
        _assert_identical(runs[0], r)
    other = mvpt.render(s, method="pt", threads=2, seed=99)
    assert other.images["v1"].tobytes() != runs[0].images["v1"].tobytes()


def _auto_splits_room():
    return mvpt.load_string(scene(views(3, res=24, spp=6), geometry=ROOM, max_depth=-1).replace(
        '<integrator type="path">', '<integrator type="mvpath"><string name="splits" value="auto"/>'))


def test_multiview_auto_splits_threads_1_2_3():
    """With `splits` auto the render chooses its splits from a pilot of its own samples: the
    same number, and the same image bits, for 1, 2 and 3 threads."""
    s = _auto_splits_room()
    runs = [mvpt.render(s, method="mvpt", threads=t) for t in (1, 2, 3)]
    chosen = runs[0].stats["splits"]
    assert 1 <= chosen <= 16
    assert runs[0].stats["split_pilot"]["r"] > 0.0  # the pilot saw variance that splitting removes
    for r in runs[1:]:
        assert r.stats["splits"] == chosen
        assert r.stats["split_pilot"] == runs[0].stats["split_pilot"]
        _assert_identical(runs[0], r)


def test_multiview_auto_splits_are_those_of_every_range(tmp_path):
    """The pilot depends on the scene and the settings alone: ranges of passes of a render (as
    on a cluster) choose what the whole render chooses, so their states merge into it, and the
    merge reports the splits its states took."""
    s = _auto_splits_room()
    whole = mvpt.render(s, method="mvpt", passes=(0, 6), threads=2)
    states = []
    for first, count in ((0, 2), (2, 4)):
        states.append(tmp_path / f"part{first}.mvpt-state")
        part = mvpt.render(s, method="mvpt", passes=(first, count), threads=1, state=states[-1])
        assert part.stats["splits"] == whole.stats["splits"]
        assert part.stats["split_pilot"] == whole.stats["split_pilot"]
    merged = mvpt.merge(s, states)
    assert merged.stats["splits"] == whole.stats["splits"]
