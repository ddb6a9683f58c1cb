"""Rendering on a Ray cluster (docs/distributed.md): the render is split into ranges of passes
(render(passes=...)), Ray runs each range as a task that renders every view with the cores it
was given, the ranges' states come back through Ray's object store and are merged in the order
of their ranges as they arrive (api.merge), so the images are exactly those of one process
rendering and merging the same ranges, whichever node rendered what and whatever failed and
ran again. Ray is optional: `pip install "mvpt[ray]"`."""
from __future__ import annotations

import hashlib
import importlib.util
import io
import math
import os
import socket
import sys
import tarfile
import tempfile
import time as _time
from pathlib import Path
from typing import Callable, Optional, Sequence

from . import api
from . import state as state_file

# Worker processes keep the scenes they unpacked and loaded, by the pack's digest.
_WORKER_SCENES: dict = {}


def _ray():
    try:
        import ray
    except ImportError:
        raise RuntimeError('distributed rendering needs Ray: pip install "mvpt[ray]"') from None
    return ray


def check_address(address: Optional[str]) -> None:
    """A RuntimeError at once, in one line, when `address` names a cluster that cannot be
    reached or a client that is not installed, where ray.init would retry for a minute with
    pages of logs. None and "auto" are left to Ray (a local instance, the cluster of this node)."""
    if address is None or address == "auto":
        return
    client = address.startswith("ray://")
    if client and importlib.util.find_spec("grpc") is None:
        raise RuntimeError(f"--ray {address}: a ray:// address needs Ray's client (grpcio): "
                           f'pip install "mvpt[ray]" (which installs "ray[client]")')
    where = address[len("ray://"):] if client else address
    host, _, port = where.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise RuntimeError(f"--ray {address}: expected HOST:PORT, ray://HOST:PORT or auto")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=5).close()
    except OSError as e:
        why = e.strerror or str(e) or type(e).__name__
        raise RuntimeError(f"--ray {address}: cannot reach a Ray cluster there ({why}); is `ray start --head` "
                           f"running on {host}?") from None


def pack_scene(scene) -> tuple:
    """The scene's files (scene.source_files) as a tar archive in memory, named relative to
    their common directory, and the scene file's name in it."""
    files = scene.source_files
    root = os.path.commonpath([os.path.dirname(f) for f in files])
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w") as tar:
        for f in files:
            tar.add(f, arcname=os.path.relpath(f, root), recursive=False)
    return buf.getvalue(), os.path.relpath(files[0], root)


def _worker_scene(pack, scene_file: str, rig: str, defines: dict, shared: bool):
    """The scene on a worker: loaded from the shared path, or unpacked once per process."""
    key = (scene_file, rig, tuple(sorted(defines.items()))) if shared else \
        (hashlib.sha256(pack).hexdigest(), rig, tuple(sorted(defines.items())))
    if key not in _WORKER_SCENES:
        path = scene_file
        if not shared:
            where = tempfile.mkdtemp(prefix="mvpt-scene-")
            with tarfile.open(fileobj=io.BytesIO(pack)) as tar:
                tar.extractall(where, filter="data")
            path = os.path.join(where, scene_file)
        _WORKER_SCENES[key] = api.load_file(path, rig=rig or None, **defines)
    return _WORKER_SCENES[key]


def render_range(pack, scene_file: str, rig: str, defines: dict, shared: bool, settings: dict,
                 first: int, count: int, threads: int, time_budget: float) -> tuple:
    """One task: passes first..first+count-1 of every view; returns (first, count, state bytes,
    seconds, where the worker's mvpt is). Deterministic: a task run again gives the same bytes."""
    scene = _worker_scene(pack, scene_file, rig, defines, shared)
    with tempfile.TemporaryDirectory(prefix="mvpt-range-") as tmp:
        path = Path(tmp) / "range.mvpt-state"
        r = api.render(scene, seed=settings["seed"], method=settings["method"], views=settings["views"],
                       threads=threads, time=time_budget, passes=(first, count), state=path,
                       splits=settings.get("splits"))
        return first, count, path.read_bytes(), r.stats["seconds"], os.path.dirname(api.__file__)


# The shortest range a plan makes: a range's first pass has no control variate and its
# adaptive maps start after a warm-up of 4 passes.
MIN_RANGE = 8


def plan_ranges(total: int, tasks: int) -> list:
    """`total` passes as up to `tasks` ranges (first, count) of nearly equal length, each of
    MIN_RANGE passes or more (or one range of all)."""
    tasks = max(1, min(tasks, total // MIN_RANGE))
    bounds = [round(i * total / tasks) for i in range(tasks + 1)]
    return [(a, b - a) for a, b in zip(bounds, bounds[1:]) if b > a]


def render(scene_path: str | os.PathLike, spp: int = 0, time: float = 0.0, seed: Optional[int] = None,
           method: str = "scene", views: Optional[Sequence] = None, rig: Optional[str] = None,
           defines: Optional[dict] = None, address: Optional[str] = None, workers: int = 0,
           task_cpus: int = 0, tasks_per_worker: int = 4, shared: bool = False, max_retries: int = 3,
           progress: Optional[Callable[[dict], None]] = None, keep_state: Optional[str | os.PathLike] = None,
           wheel: Optional[str | os.PathLike] = None, splits: Optional[int | str] = None) -> api.RenderResult:
    """Render `scene_path` on a Ray cluster: `spp` passes (0: the sensors' largest sample_count)
    in `workers` * `tasks_per_worker` ranges, `workers` at a time, each task with `task_cpus`
    cores (0: the cluster's CPUs divided among the workers). address: a running cluster
    ("auto", "ray://host:10001", ...); None starts a local Ray instance. shared: the scene's
    files are at the same path on every node; otherwise they are packed once, put in the object
    store, and unpacked by each worker process. wheel: a self-contained mvpt wheel
    (scripts/build-wheel.sh) that Ray installs on nodes for the tasks (its runtime environment's
    py_modules), for clusters whose nodes lack mvpt. time: a wall-clock budget for the whole render
    (ranges started before it ends stop at it). The result is that of api.merge of the ranges'
    states, in their order; stats["distributed"] has the tasks, their seconds and the bytes that
    crossed the network. splits: as api.render's (every range chooses the same under "auto").
    method: as api.render's; "auto" is chosen once, here (stats["auto"])."""
    ray = _ray()
    if not ray.is_initialized():
        check_address(address)
    defines = {str(k): str(v) for k, v in (defines or {}).items()}
    scene = api.load_file(scene_path, rig=rig, **defines)
    index = api.resolve_views(scene, views)
    ids = [v["id"] for v in scene.views]
    view_ids = [ids[i] for i in index] or ids
    total = int(spp) or max(v["spp"] for v in scene.views)
    # method="auto" is chosen here, once, from the pilot (the ranges then render one method).
    auto = api.choose_method(scene, index, seed, 0, api._splits_option(splits)) if method == "auto" else None
    method = auto["method"] if auto else method
    started_here = not ray.is_initialized()
    if wheel is not None and not (Path(wheel).is_file() and str(wheel).endswith(".whl")):
        raise ValueError(f"wheel: '{api.shown(os.fspath(wheel))}' is not a wheel file (.whl); make one with "
                         f"scripts/build-wheel.sh")
    if wheel is not None and not started_here:
        raise RuntimeError("a wheel for the nodes is given to Ray when it starts: call distributed.render "
                           "before ray.init, or pass runtime_env={'py_modules': [wheel]} to ray.init")
    if started_here:
        # The job's environment: the wheel for nodes without mvpt, or (a local instance) this
        # process's module path.
        runtime_env = {"py_modules": [os.fspath(Path(wheel).resolve())]} if wheel is not None else \
            {"env_vars": {"PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}} if address is None else None
        ray.init(address=address, include_dashboard=False, log_to_driver=False, runtime_env=runtime_env)
    try:
        cluster_cpus = int(ray.cluster_resources().get("CPU", 1))
        workers = int(workers) or max(1, len(ray.nodes()))
        cpus = int(task_cpus) or max(1, cluster_cpus // workers)
        pack, scene_file = (None, str(Path(scene_path).resolve())) if shared else pack_scene(scene)
        pack_ref = ray.put(pack)
        task = ray.remote(num_cpus=cpus, max_retries=int(max_retries), retry_exceptions=False)(render_range)
        settings = dict(seed=seed, method=method, views=view_ids, splits=splits)
        ranges = plan_ranges(total, workers * max(1, int(tasks_per_worker)))
        result = _run(ray, task, pack_ref, len(pack or b""), scene, scene_file, rig or "", defines, shared,
                      settings, ranges, workers, cpus, float(time), progress, keep_state)
        if auto is not None:
            result.stats["auto"] = auto
        return result
    finally:
        if started_here:
            ray.shutdown()


class _Merger:
    """The ranges' states as they come back, folded into one merged state in range order."""

    def __init__(self, scene, tmp: Path, first: int, total: int, progress):
        self.scene, self.tmp, self.first, self.total = scene, tmp, first, total
        self.next = first
        self.progress = progress
        self.identity = state_file.scene_identity(scene)
        self.merged, self.waiting, self.t0 = None, {}, _time.monotonic()
        self.seconds = 0.0  # spent merging

    def add(self, first: int, count: int, data: bytes) -> None:
        t = _time.monotonic()
        path = self.tmp / f"range_{first:010d}{state_file.SUFFIX}"
        path.write_bytes(data)
        self.waiting[first] = (count, path)
        # The ranges that continue the merged prefix, in order: the bits do not depend on which
        # task ended first.
        while self.next in self.waiting:
            count, path = self.waiting.pop(self.next)
            if self.merged is None:
                self.merged = path
            else:
                out = self.tmp / f"merged_{self.next:010d}{state_file.SUFFIX}"
                api.merge(self.scene, [self.merged, path], state=out, images=False, identity=self.identity,
                          unfinished=True)  # ranges end at the time budget
                self.merged.unlink(), path.unlink()
                self.merged = out
            self.next += count
            if self.progress is not None:
                done = self.next - self.first
                self.progress({"pass": done, "fraction": done / self.total, "elapsed": _time.monotonic() - self.t0})
        self.seconds += _time.monotonic() - t


def _run(ray, task, pack_ref, pack_bytes, scene, scene_file, rig, defines, shared, settings, ranges, workers,
         cpus, budget, progress, keep_state):
    """Submit the ranges, `workers` at a time, and merge their states as they come. Ctrl-C
    cancels the running tasks and keeps the merged ranges."""
    t0 = _time.monotonic()
    pending, running, bytes_back, task_seconds, modules = list(ranges), {}, 0, [], set()
    cancelled = False
    with tempfile.TemporaryDirectory(prefix="mvpt-merge-") as tmp:
        merger = _Merger(scene, Path(tmp), ranges[0][0], sum(c for _, c in ranges), progress)
        try:
            while pending or running:
                left = budget - (_time.monotonic() - t0) if budget > 0 else math.inf
                while pending and len(running) < workers and left > 0:
                    first, count = pending.pop(0)
                    ref = task.remote(pack_ref, scene_file, rig, defines, shared, settings, first, count, cpus,
                                      max(left, 1e-3) if budget > 0 else 0.0)
                    running[ref] = (first, count)
                if not running:
                    break  # the budget is spent
                ready, _ = ray.wait(list(running), num_returns=1)
                for ref in ready:
                    running.pop(ref)
                    first, count, data, seconds, module = ray.get(ref)
                    modules.add(module)
                    bytes_back += len(data)
                    task_seconds.append(seconds)
                    merger.add(first, count, data)
        except KeyboardInterrupt:
            cancelled = True
            for ref in running:
                ray.cancel(ref, force=True)
        if merger.merged is None:
            raise KeyboardInterrupt if cancelled else RuntimeError("no range finished within the time budget")
        result = api.merge(scene, [merger.merged], state=keep_state, identity=merger.identity, unfinished=True)
    result.stats["cancelled"] = cancelled
    result.stats["distributed"] = {
        "tasks": len(task_seconds), "workers": workers, "cpus_per_task": cpus,
        "task_seconds": task_seconds, "scene_pack_bytes": pack_bytes, "state_bytes_returned": bytes_back,
        "wall_seconds": _time.monotonic() - t0, "merge_seconds": merger.seconds, "worker_modules": sorted(modules),
    }
    return result
