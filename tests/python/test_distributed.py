"""Rendering on a Ray cluster (docs/distributed.md) with two local nodes of one CPU each
(ray.cluster_utils.Cluster): the distributed render equals the single-process render and
merge of the same ranges bit for bit, also when a worker process is killed mid-task (Ray runs
the range again); the scene travels packed through the object store; the CLI's --ray."""
from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

ray = pytest.importorskip("ray", reason='Ray is an optional dependency: pip install "mvpt[ray]"')
psutil = pytest.importorskip("psutil", reason="psutil (installed with Ray) finds the worker processes")

import mvpt
from mvpt import cli, distributed

from small_scenes import slow_scene

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))

pytestmark = pytest.mark.serial  # local Ray clusters start and stop: never beside other tests


@pytest.fixture(scope="module")
def cluster():
    from ray.cluster_utils import Cluster
    c = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    c.add_node(num_cpus=1)
    ray.init(address=c.address, include_dashboard=False, log_to_driver=False,
             runtime_env={"env_vars": {"PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}})
    yield c
    ray.shutdown()
    c.shutdown()


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "room.xml"
    path.write_text(slow_scene(3, res=32))
    return path


def _local(scene_file, tmp_path, method, ranges, seed):
    scene = mvpt.load_file(scene_file)
    paths = []
    for first, count in ranges:
        p = tmp_path / f"local_{first}.mvpt-state"
        mvpt.render(scene, seed=seed, method=method, passes=(first, count), state=p)
        paths.append(p)
    return mvpt.merge(scene, paths)


def _same(a, b):
    for v in a.images:
        assert np.array_equal(a.images[v], b.images[v]), v
        assert np.array_equal(a.variance[v], b.variance[v]), v
        assert np.array_equal(a.sample_count[v], b.sample_count[v]), v


@pytest.mark.parametrize("method,shared", [("pt", False), ("mvpt", False), ("mvpt", True), ("auto", False)])
def test_distributed_equals_local_ranges(cluster, scene_file, tmp_path, method, shared):
    # ("auto": chosen once on the driver; each local range chooses the same for itself.)
    assert len(ray.nodes()) == 2
    r = distributed.render(scene_file, spp=32, seed=5, method=method, workers=2, tasks_per_worker=2, shared=shared)
    if method == "auto":
        assert r.stats["auto"]["method"] == r.stats["method"] in ("pt", "mvpt"), r.stats["auto"]
    d = r.stats["distributed"]
    assert d["tasks"] == 4 and (d["scene_pack_bytes"] == 0) == shared and d["state_bytes_returned"] > 0
    _same(r, _local(scene_file, tmp_path, method, distributed.plan_ranges(32, 4), seed=5))


def _kill_one_range_worker(stop: threading.Event, killed: list):
    """SIGKILL the first worker process seen running a range (Ray's process title)."""
    while not stop.is_set() and not killed:
        for p in psutil.process_iter(["pid", "cmdline"]):
            cmd = " ".join(p.info["cmdline"] or [])
            if "ray::render_range" in cmd and p.info["pid"] != os.getpid():
                os.kill(p.info["pid"], signal.SIGKILL)
                killed.append(p.info["pid"])
                break
        time.sleep(0.02)


def test_killed_worker_gives_the_same_image(cluster, scene_file, tmp_path):
    stop, killed = threading.Event(), []
    killer = threading.Thread(target=_kill_one_range_worker, args=(stop, killed))
    killer.start()
    try:
        r = distributed.render(scene_file, spp=48, seed=6, method="mvpt", workers=2, tasks_per_worker=2)
    finally:
        stop.set()
        killer.join()
    assert killed, "no worker was killed: the test saw no range running"
    _same(r, _local(scene_file, tmp_path, "mvpt", distributed.plan_ranges(48, 4), seed=6))


def test_plan_ranges():
    assert distributed.plan_ranges(32, 4) == [(0, 8), (8, 8), (16, 8), (24, 8)]
    assert distributed.plan_ranges(20, 8) == [(0, 10), (10, 10)]  # ranges of 8 passes or more
    assert distributed.plan_ranges(5, 4) == [(0, 5)]
    for total, tasks in ((100, 7), (9, 2), (64, 64)):
        ranges = distributed.plan_ranges(total, tasks)
        assert sum(c for _, c in ranges) == total and ranges[0][0] == 0
        assert all(a + c == b for (a, c), (b, _) in zip(ranges, ranges[1:]))


def test_cli_ray(cluster, scene_file, tmp_path):
    out = tmp_path / "out"
    assert cli.main(["render", str(scene_file), "--spp", "16", "--seed", "2", "--method", "mvpt", "--ray", "auto",
                     "--workers", "2", "-q", "-o", str(out)]) == 0
    data = json.loads((out / "room.json").read_text())
    assert data["distributed"]["tasks"] == 2 and data["passes"] == 16
    img = mvpt._core.read_image(str(out / "room_v1.exr"))
    assert np.array_equal(img, _local(scene_file, tmp_path, "mvpt", [(0, 8), (8, 8)], seed=2).images["v1"])
    assert cli.main(["render", str(scene_file), "--ray", "--passes", "0:4", "-o", str(out)]) == 2


def test_cli_ray_refuses_a_missing_wheel(scene_file, tmp_path, capsys):
    """Checked before Ray starts, as one line (not Ray's RuntimeEnvSetupError)."""
    assert cli.main(["render", str(scene_file), "--spp", "1", "--ray", "--wheel", str(tmp_path / "nothere.whl"),
                     "-q", "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nothere.whl' is not a wheel file" in err[0], err


@pytest.mark.parametrize("address,message", [
    ("127.0.0.1:1", "cannot reach a Ray cluster there"),
    ("ray://127.0.0.1:1", "cannot reach a Ray cluster there" if importlib.util.find_spec("grpc") else
     "a ray:// address needs Ray's client"),
    ("head", "expected HOST:PORT, ray://HOST:PORT or auto"),
])
def test_an_unreachable_cluster_is_one_line_at_once(scene_file, tmp_path, address, message):
    """Not Ray's minute of retries and pages of logs: the address is tried first (a fresh
    process, as a user's: Ray is not started in it)."""
    run = subprocess.run([sys.executable, "-m", "mvpt.cli", "render", str(scene_file), "--spp", "1", "--ray", address,
                          "-q", "-o", str(tmp_path / "out")], capture_output=True, text=True, timeout=50, env=ENV)
    err = run.stderr.strip().splitlines()
    assert run.returncode == 1 and len(err) == 1, run.stderr[-2000:]
    assert f"--ray {address}: {message}" in err[0], err


def test_time_budget_covers_the_cluster(cluster, scene_file):
    """--time is the whole render's budget: ranges are submitted while it lasts and stop at it."""
    r = distributed.render(scene_file, spp=100000, time=3.0, seed=1, method="mvpt", workers=2)
    d = r.stats["distributed"]
    assert d["wall_seconds"] < 3.0 + 10.0, d  # generous: a check of the mechanism, not a timing
    assert 1 <= r.stats["passes"] < 100000 and d["tasks"] >= 2
    for img in r.images.values():
        assert np.isfinite(img).all() and img.mean() > 0
