"""Renderer behaviour through the Python API: spp, time budget, per-sensor sample counts,
cancellation from the progress callback, the GIL, non-finite samples, statistics."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import mvpt

from small_scenes import overflow_scene, scene, sensor, slow_scene, views


@pytest.fixture(scope="module")
def small():
    return mvpt.load_string(scene(views(2, res=16, spp=4)))


SLOW_RES = 128  # the `slow` scene's film size


@pytest.fixture(scope="module")
def slow():
    """12 views of a closed room: one pass takes roughly 0.05-0.1 s on the 2-core development
    machine (at 64 px the path tracer's speed-ups brought it down to the 0.02 s floor below)."""
    return mvpt.load_string(slow_scene(12, res=SLOW_RES, spp=4))


def test_spp_is_respected(small):
    r = mvpt.render(small, spp=3)
    assert r.stats["passes"] == 3
    for vid, count in r.sample_count.items():
        assert count.shape == (16, 16) and (count == 3).all()
        assert r.stats["views"][vid]["spp"] == 3.0
    assert r.stats["samples"] == 2 * 16 * 16 * 3


def test_per_sensor_sample_count():
    """Without an spp, each view takes its own sensor's sample_count."""
    s = mvpt.load_string(scene(sensor("a", spp=3) + sensor("b", spp=5, origin="1, 1, 4")))
    r = mvpt.render(s)
    assert (r.sample_count["a"] == 3).all() and (r.sample_count["b"] == 5).all()
    assert r.stats["passes"] == 5
    assert r.stats["samples"] == 16 * 16 * (3 + 5)
    # An explicit spp overrides every sensor's.
    r = mvpt.render(s, spp=2)
    assert (r.sample_count["a"] == 2).all() and (r.sample_count["b"] == 2).all()


def test_time_budget_within_one_pass(slow):
    # A budget of several passes, however loaded the machine is.
    budget = max(1.0, 4 * mvpt.render(slow, spp=1, threads=2).stats["max_pass_seconds"])
    t0 = time.monotonic()
    r = mvpt.render(slow, time=budget, threads=2)
    wall = time.monotonic() - t0
    s = r.stats
    one_pass = s["max_pass_seconds"]
    assert one_pass > 0.02, "the test scene is too fast to check the budget"
    assert s["passes"] >= 2 and not s["cancelled"]
    # The last pass starts only if it is predicted to end within the budget: the render
    # overshoots by at most the duration of one pass (plus bookkeeping between passes, and
    # scheduling delays on a loaded machine: the slack).
    assert s["wall_time"] <= budget + one_pass + 0.1, s
    assert wall <= budget + one_pass + 0.3, (wall, s)
    # ... and it does not stop early: it stops only when elapsed + last pass > budget.
    assert s["wall_time"] >= budget - one_pass, s
    counts = np.concatenate([c.ravel() for c in r.sample_count.values()])
    assert (counts == s["passes"]).all()


def test_progress_reports(small):
    seen = []
    r = mvpt.render(small, spp=3, progress=seen.append)
    assert seen, "progress is called at least once, at the end"
    assert seen[-1]["pass"] == 3 and seen[-1]["fraction"] == 1.0
    assert seen[-1]["samples"] == r.stats["samples"] and seen[-1]["elapsed"] > 0
    fractions = [p["fraction"] for p in seen]
    assert fractions == sorted(fractions)


def test_time_budget_and_spp_whichever_first(small):
    r = mvpt.render(small, spp=2, time=30.0)
    assert r.stats["passes"] == 2 and r.stats["wall_time"] < 5


def _assert_whole_tiles(r, res):
    """A path-traced render stopped early holds whole passes, or, where it cut a long pass
    (a loaded machine can make any pass long), whole 16 x 16 tiles of one pass more; the
    samples counted are those in the films."""
    total = 0
    for vid, count in r.sample_count.items():
        assert count.min() >= r.stats["passes"] and count.max() <= r.stats["passes"] + 1, vid
        for y in range(0, res, 16):
            for x in range(0, res, 16):
                tile = count[y:y + 16, x:x + 16]
                assert (tile == tile[0, 0]).all(), (vid, y, x)
        total += int(count.sum())
    assert r.stats["samples"] == total


def test_cancel_from_progress_callback(slow):
    calls = []

    def progress(p):
        calls.append(dict(p))
        if p["pass"] >= 1:
            raise KeyboardInterrupt

    t0 = time.monotonic()
    r = mvpt.render(slow, spp=1000, progress=progress, poll=0.02)
    elapsed = time.monotonic() - t0
    s = r.stats
    assert s["cancelled"] is True
    assert 1 <= s["passes"] < 1000 and elapsed < 10
    assert set(calls[-1]) >= {"pass", "fraction", "elapsed", "samples"}
    assert 0 < calls[-1]["fraction"] < 1
    _assert_whole_tiles(r, SLOW_RES)
    for vid in r.images:
        assert np.isfinite(r.images[vid]).all() and r.images[vid].mean() > 0


def test_other_exception_from_progress_cancels_and_propagates(slow):
    def progress(p):
        raise RuntimeError("stop here")

    t0 = time.monotonic()
    with pytest.raises(RuntimeError, match="stop here"):
        mvpt.render(slow, spp=1000, progress=progress, poll=0.02)
    assert time.monotonic() - t0 < 10


def test_gil_released_while_rendering(slow):
    """Another Python thread keeps running during the render: with the GIL held for a
    whole wait (poll=1 s) its loop would stall for about a second at a time."""
    stamps = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            stamps.append(time.monotonic())
            time.sleep(0.005)

    t = threading.Thread(target=ticker)
    t.start()
    try:
        t0 = time.monotonic()
        r = mvpt.render(slow, time=1.0, threads=1, poll=1.0)
        t1 = time.monotonic()
    finally:
        stop.set()
        t.join()
    during = np.array([x for x in stamps if t0 <= x <= t1])
    duration = t1 - t0
    assert duration > 0.5 and r.stats["passes"] >= 1
    assert len(during) > 20, "the other thread hardly ran during the render"
    # Holding the GIL in wait(1 s) would leave one gap as long as the whole render.
    assert np.diff(np.concatenate([[t0], during, [t1]])).max() < duration / 2


@pytest.mark.parametrize("method", ["pt", "mvpt"])
def test_nonfinite_samples_counted_not_written(method):
    """Non-finite samples (multi-view: contributions) are dropped, counted, and the first one
    located for replay, under either method."""
    s = mvpt.load_string(overflow_scene())
    r = mvpt.render(s, threads=2, method=method)
    st = r.stats
    assert st["nonfinite_samples"] > 0
    assert st["views"]["cam"]["nonfinite_samples"] == st["nonfinite_samples"]
    assert np.isfinite(r.images["cam"]).all()
    first = st["first_nonfinite"]
    assert first["view"] == 0 and first["view_id"] == "cam"
    assert 0 <= first["x"] < 16 and 0 <= first["y"] < 16 and 0 <= first["sample"] < 2
    # The first non-finite sample (in sample, view, y, x order) does not depend on the threads.
    assert mvpt.render(s, threads=1, method=method).stats["first_nonfinite"] == first
    # A well-behaved scene has none.
    ok = mvpt.render(mvpt.load_string(scene()), spp=2, method=method).stats
    assert ok["nonfinite_samples"] == 0 and ok["first_nonfinite"] is None


def test_stats_content(small):
    r = mvpt.render(small, spp=2, seed=3, threads=2)
    s = r.stats
    assert s["settings"] == {"spp": 2, "time": 0.0, "seed": 3, "threads": 2, "views": ["v0", "v1"], "passes": None,
                             "integrator": "path", "method": "scene", "splits": None}
    assert s["method"] == "pt" and s["notes"] == []
    assert s["passes"] == 2 and s["samples"] == 2 * 16 * 16 * 2
    assert s["wall_time"] > 0 and s["samples_per_second"] == pytest.approx(s["samples"] / s["wall_time"])
    rays = s["rays"]
    assert rays["camera"] == s["samples"]
    assert rays["intersect"] >= rays["camera"] and rays["shadow"] > 0
    assert rays["total"] == rays["intersect"] + rays["shadow"]
    assert s["rays_per_second"] == pytest.approx(rays["total"] / s["wall_time"])
    assert s["nonfinite_samples"] == 0
    for i, vid in enumerate(["v0", "v1"]):
        v = s["views"][vid]
        assert v["id"] == vid and v["index"] == i and (v["width"], v["height"]) == (16, 16)
        assert v["spp"] == 2.0 and v["samples"] == 512
        assert v["mean"] == pytest.approx(r.images[vid].reshape(-1, 3).mean(axis=0), rel=1e-5)
        assert 0 < v["mean"][0] < 10


def test_views_argument(small):
    ids = [v["id"] for v in small.views]
    assert ids == ["v0", "v1"]
    assert list(mvpt.render(small, spp=1, views=["v1"]).images) == ["v1"]
    assert list(mvpt.render(small, spp=1, views=[1]).images) == ["v1"]
    assert list(mvpt.render(small, spp=1, views=["1"]).images) == ["v1"]  # a digit string that is no id: index
    assert list(mvpt.render(small, spp=1, views=[1, "v1", "1"]).images) == ["v1"]  # no repeats
    assert list(mvpt.render(small, spp=1, views="v1").images) == ["v1"]  # one id, not its characters
    with pytest.raises(ValueError, match="unknown view 'v7'"):
        mvpt.render(small, views=["v7"])
    with pytest.raises(ValueError, match="out of range"):
        mvpt.render(small, views=[2])
    with pytest.raises(ValueError, match="out of range"):
        mvpt.render(small, views=[-1])


def test_digit_ids_win_over_indices():
    s = mvpt.load_string(scene(sensor("1") + sensor("7", origin="1, 1, 4") + sensor("3", origin="-1, 1, 4")))
    assert list(mvpt.render(s, spp=1, views=["1"]).images) == ["1"]   # the id "1", not index 1
    assert list(mvpt.render(s, spp=1, views=["2"]).images) == ["3"]   # no id "2": index 2
    assert list(mvpt.render(s, spp=1, views=[1]).images) == ["7"]     # an int is always an index


@pytest.mark.parametrize("kwargs, match", [(dict(spp=-1), "spp"), (dict(time=-1.0), "time"),
                                           (dict(time=float("nan")), "time"), (dict(threads=-2), "threads"),
                                           (dict(seed=-1), "seed"), (dict(seed=2**32), "seed"),
                                           (dict(spp=2**31), "spp"), (dict(threads=2**31), "threads"),
                                           (dict(passes=(0, 0)), "passes"), (dict(passes=(-1, 4)), "passes"),
                                           (dict(checkpoint=-1.0), "checkpoint"),
                                           (dict(time=float("inf")), "finite"),  # once rendered forever
                                           (dict(state=b"x.mvpt-state"), "state must be a path"),
                                           (dict(state="nodir/x.mvpt-state"), "does not exist")])
def test_bad_render_arguments(small, kwargs, match):
    with pytest.raises(ValueError, match=match):
        mvpt.render(small, **kwargs)


@pytest.mark.parametrize("call, match", [
    (lambda: mvpt.load_string(123), "must be text"),  # once AttributeError
    (lambda: mvpt.load_string(None), "must be text"),
    (lambda: mvpt.load_string(b"<scene/>"), "must be text"),
    (lambda: mvpt.load_string(scene(views(1)), ".", rig=5), "rig must be text"),
    (lambda: mvpt.load_string(scene(views(1)), ".", rig=""), "the rig is empty"),
    (lambda: mvpt.render("scene.xml"), "mvpt.load_file"),
    (lambda: mvpt.render(None), "mvpt.load_file"),
    (lambda: mvpt.write_outputs(None, "out", "x"), "result of mvpt.render"),
])
def test_wrong_types_are_one_clear_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_merge_of_one_path_is_not_its_characters(small, tmp_path):
    # Once each character of the path was taken for a state file of its own.
    with pytest.raises(Exception, match="a.mvpt-state") as info:
        mvpt.merge(small, str(tmp_path / "a.mvpt-state"))
    assert not isinstance(info.value, (AttributeError, TypeError))


def test_scene_info():
    s = mvpt.load_string(scene(sensor("a", res=8, spp=3)))
    (v,) = s.views
    assert (v["id"], v["width"], v["height"], v["spp"]) == ("a", 8, 8, 3)
    assert s.integrator == "path" and s.shape_count == 3 and s.light_count == 1


def test_film_too_large_for_memory(tmp_path, capsys):
    """A 65536^2 film would need hundreds of GiB: a clear error before anything is allocated."""
    s = mvpt.load_string(scene(sensor(res=65536)))
    for method in ("pt", "mvpt"):
        with pytest.raises(RuntimeError, match=r"the films of the 1 views need about \d+ MiB but the machine leaves "
                                               r"\d+ MiB"):
            mvpt.render(s, spp=1, method=method)
    from mvpt import cli
    path = tmp_path / "huge.xml"
    path.write_text(scene(sensor(res=65536)))
    assert cli.main(["render", str(path), "-o", str(tmp_path / "out"), "-q"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mvpt: error: the films")


def test_ctrl_c_during_render(slow):
    """SIGINT (Ctrl-C) in the main thread while render() waits: cancelled at a pass boundary."""
    import os
    import signal

    # A process started in the background by a non-interactive shell inherits SIGINT ignored
    # (and Python then installs no KeyboardInterrupt handler): install it for this test.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    try:
        # Only the interrupt can end this render (10^6 passes), so it arrives while rendering.
        r = mvpt.render(slow, spp=1_000_000)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert r.stats["cancelled"] is True and r.stats["passes"] >= 1
    assert time.monotonic() - t0 < 10
    _assert_whole_tiles(r, SLOW_RES)


def test_ray_embree_cannot_trace_is_a_miss():
    """A camera 1e19 away gives rays that Embree rejects (|origin| > 1.8e18; its debug builds
    abort on them): they count as misses, the process survives and the image is finite.
    Run in a subprocess so that a regression fails this test instead of killing the session."""
    import os
    import subprocess
    import sys
    code = ("import sys, numpy as np, mvpt; sys.path.insert(0, sys.argv[1]); from small_scenes import scene, sensor; "
            "r = mvpt.render(mvpt.load_string(scene(sensor(origin='1e19, 1, 4'))), spp=2); "
            "assert np.isfinite(r.images['cam']).all(); print('ok')")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    proc = subprocess.run([sys.executable, "-c", code, os.path.dirname(__file__)], capture_output=True, text=True,
                          timeout=60, env=env)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]


def test_render_splits_option():
    """render(splits=...) overrides the scene's `mvpath` setting: a number as given, "auto" chosen
    per render (with the pilot's statistics), anything else refused before rendering."""
    s = mvpt.load_string(scene(views(3, res=16, spp=2)))
    assert mvpt.render(s, method="mvpt", splits=3).stats["splits"] == 3
    auto = mvpt.render(s, method="mvpt", splits="auto").stats
    assert 1 <= auto["splits"] <= 16 and auto["split_pilot"]["r"] > 0.0
    assert auto["settings"]["splits"] == "auto"
    assert "split_pilot" in mvpt.render(s, method="mvpt").stats  # the scene's: the default, auto
    assert "split_pilot" not in mvpt.render(s, method="mvpt", splits=2).stats
    for bad in (0, 65, "many", 2.5, True):
        with pytest.raises(ValueError, match="splits must be 'auto' or an integer"):
            mvpt.render(s, method="mvpt", splits=bad)
