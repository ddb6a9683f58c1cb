"""Rendering stays responsive however long one pass is (a pass of many large views lasts
seconds): a pass runs in chunks of about a quarter of a second with a progress report after
each, Ctrl-C stops between tiles (multi-view path tracing drops the unfinished pass, path
tracing keeps its finished tiles, and a resumed render renders only the others), and a time
budget is not overrun. Generous margins: these are checks of the mechanism, not timings."""
from __future__ import annotations

import time

import pytest

import mvpt

from small_scenes import slow_scene

pytestmark = pytest.mark.serial  # latencies and time budgets are measured: never beside other tests

# 32 views of 96^2 of the closed room: one pass is about a second on two cores.
VIEWS, RES = 32, 96


@pytest.fixture(scope="module")
def many_views():
    return mvpt.load_string(slow_scene(VIEWS, res=RES, spp=64))


def _one_pass_seconds(scene, method: str) -> float:
    r = mvpt.render(scene, spp=1, method=method)
    assert r.stats["passes"] == 1
    return r.stats["max_pass_seconds"]


@pytest.fixture(scope="module")
def pass_seconds(many_views):
    return _one_pass_seconds(many_views, "mvpt")


def test_progress_within_a_pass(many_views, pass_seconds):
    reports = []
    r = mvpt.render(many_views, spp=2, method="mvpt", poll=0.02, progress=lambda p: reports.append(dict(p)))
    assert r.stats["max_chunk_seconds"] <= 0.75, r.stats  # chunks aim at 0.25 s
    # While the first pass runs, the samples done so far grow in several reports.
    during = {p["samples"] for p in reports if p["pass"] == 0 and p["samples"] > 0}
    if pass_seconds > 0.6:
        assert len(during) >= 2, (pass_seconds, reports)
    assert r.stats["passes"] == 2 and not r.stats["cancelled"]


def test_ctrl_c_drops_the_unfinished_pass(many_views, pass_seconds):
    raised = []

    def stop(p):
        if p["pass"] >= 1 and not raised:  # the second pass is under way
            raised.append(time.monotonic())
            raise KeyboardInterrupt

    r = mvpt.render(many_views, spp=8, method="mvpt", poll=0.02, progress=stop)
    latency = time.monotonic() - raised[0]
    assert r.stats["cancelled"] and r.stats["passes"] == 1
    assert latency < max(0.5, 0.5 * pass_seconds), (latency, pass_seconds)
    # The image is that of the finished pass alone: the spp=1 render, bit for bit.
    one = mvpt.render(many_views, spp=1, method="mvpt")
    for v in one.images:
        assert one.images[v].tobytes() == r.images[v].tobytes()


def test_time_budget_is_not_overrun(many_views, pass_seconds):
    budget = 2.5 * pass_seconds
    r = mvpt.render(many_views, time=budget, method="mvpt")
    assert r.stats["passes"] >= 1
    assert r.stats["seconds"] <= budget + 0.5, (r.stats["seconds"], budget)


# Path tracing: 32 views of 256^2, about a second per pass on two cores.
PT_RES = 256


@pytest.fixture(scope="module")
def pt_views():
    return mvpt.load_string(slow_scene(VIEWS, res=PT_RES, spp=64))


@pytest.fixture(scope="module")
def pt_pass_seconds(pt_views):
    return _one_pass_seconds(pt_views, "pt")


def test_path_tracing_stops_between_tiles_and_resumes(tmp_path, pt_views, pt_pass_seconds):
    raised = []

    def stop(p):
        if p["pass"] >= 1 and not raised:  # the second pass is under way
            raised.append(time.monotonic())
            raise KeyboardInterrupt

    state = tmp_path / "cut.mvpt-state"
    r = mvpt.render(pt_views, spp=2, seed=5, method="pt", poll=0.02, progress=stop, state=state)
    latency = time.monotonic() - raised[0]
    assert r.stats["cancelled"] and r.stats["passes"] == 1
    assert latency < max(0.5, 0.5 * pt_pass_seconds), (latency, pt_pass_seconds)
    # The finished tiles of the second pass are kept: whole 16 x 16 tiles of 2 samples.
    twos = 0
    for vid, count in r.sample_count.items():
        for y in range(0, PT_RES, 16):
            for x in range(0, PT_RES, 16):
                tile = count[y:y + 16, x:x + 16]
                assert (tile == tile[0, 0]).all() and tile[0, 0] in (1, 2), (vid, y, x)
                twos += tile[0, 0] == 2
    if pt_pass_seconds > 0.6:
        assert 0 < twos < VIEWS * (PT_RES // 16) ** 2, twos
    # Resumed, it renders the other tiles' second sample: the render that was never stopped.
    done = mvpt.render(pt_views, spp=2, seed=5, method="pt", resume=state)
    whole = mvpt.render(pt_views, spp=2, seed=5, method="pt")
    for v in whole.images:
        assert whole.images[v].tobytes() == done.images[v].tobytes(), v
        assert (done.sample_count[v] == 2).all(), v
    assert done.stats["samples"] == whole.stats["samples"] == 2 * VIEWS * PT_RES * PT_RES


def test_path_tracing_time_budget_is_not_overrun(pt_views, pt_pass_seconds):
    budget = 1.5 * pt_pass_seconds
    r = mvpt.render(pt_views, time=budget, method="pt")
    assert r.stats["passes"] >= 1
    assert r.stats["seconds"] <= budget + 0.5, (r.stats["seconds"], budget)

