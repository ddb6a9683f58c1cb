"""Multi-view path tracing stays responsive however long one pass is (every view takes part
in every pass, so a pass of many large views lasts seconds): the pass runs in chunks of about
a quarter of a second with a progress report after each, Ctrl-C drops the unfinished pass
between tiles, and a time budget is not overrun. Generous margins: these are checks of the
mechanism, not timings."""
from __future__ import annotations

import time

import pytest

import mvpt

from small_scenes import slow_scene

# 32 views of 96^2 of the closed room: one pass is about a second on two cores.
VIEWS, RES = 32, 96


@pytest.fixture(scope="module")
def many_views():
    return mvpt.load_string(slow_scene(VIEWS, res=RES, spp=64))


@pytest.fixture(scope="module")
def pass_seconds(many_views):
    r = mvpt.render(many_views, spp=1, method="mvpt")
    assert r.stats["passes"] == 1
    return r.stats["max_pass_seconds"]


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
