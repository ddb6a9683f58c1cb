"""Python API: load scenes, render them (cancellable, GIL released), get NumPy images."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np

from . import _core


def _defines(kwargs: dict) -> dict:
    out = {}
    for k, v in kwargs.items():
        if isinstance(v, bool):
            v = "true" if v else "false"
        out[str(k)] = str(v)
    return out


def load_file(path: str | os.PathLike, **defines) -> _core.Scene:
    """Load a Mitsuba 3 XML scene; keyword arguments override its <default> values.

    Raises mvpt.SceneError (a ValueError) naming file:line:col on bad input."""
    return _core.load_file(os.fspath(path), _defines(defines))


def load_string(xml: str, base_dir: str | os.PathLike = ".", **defines) -> _core.Scene:
    """Load a scene from an XML string; relative file names resolve in `base_dir`."""
    return _core.load_string(xml, os.fspath(base_dir), _defines(defines))


@dataclass
class RenderResult:
    """Images and statistics of one render, keyed by view id (in scene order)."""

    images: dict = field(default_factory=dict)
    variance: dict = field(default_factory=dict)
    sample_count: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)

    @property
    def view_ids(self) -> list:
        return list(self.images.keys())


def render(scene: _core.Scene, spp: int = 0, time: float = 0.0, seed: Optional[int] = None,
           threads: int = 0, views: Optional[Sequence] = None,
           progress: Optional[Callable[[dict], None]] = None, poll: float = 0.1) -> RenderResult:
    """Render all views (or `views`: indices or ids) of `scene`.

    spp: samples per pixel (0: each sensor's sample_count); time: wall-clock budget in
    seconds (0: none). The render runs natively with the GIL released; Ctrl-C (or an
    exception from `progress`) cancels it at the next pass boundary and the images of
    the passes finished so far are returned, with stats["cancelled"] set."""
    info = scene.views
    ids = [v["id"] for v in info]
    index = []
    for v in views or []:
        if isinstance(v, (int, np.integer)):
            index.append(int(v))
        elif str(v) in ids:
            index.append(ids.index(str(v)))
        else:
            raise ValueError(f"unknown view {v!r}; the scene's views are {ids}")
    job = _core.RenderJob(scene, spp=int(spp), time=float(time), seed=seed, threads=int(threads), views=index)
    job.start()
    interrupted = None
    try:
        while not job.wait(poll):
            if progress is not None:
                progress(job.progress())
    except BaseException as e:  # KeyboardInterrupt included: stop cleanly, keep the passes done
        interrupted = e
        job.cancel()
        while not job.wait(poll):
            pass
    result = RenderResult()
    for r in job.results():
        result.images[r["id"]] = r["image"]
        result.variance[r["id"]] = r["variance"]
        result.sample_count[r["id"]] = r["sample_count"]
    stats = job.stats()
    if interrupted is not None:
        stats["cancelled"] = True
    stats["views"] = {r["id"]: {"samples": int(r["samples"]),
                                "spp": float(r["samples"]) / max(1, r["image"].shape[0] * r["image"].shape[1]),
                                "mean": [float(x) for x in r["image"].reshape(-1, 3).mean(axis=0)]}
                      for r in job.results()}
    s = stats["seconds"]
    stats["samples_per_second"] = stats["samples"] / s if s > 0 else 0.0
    stats["rays_per_second"] = (stats["rays"] + stats["shadow_rays"]) / s if s > 0 else 0.0
    stats["integrator"] = scene.integrator
    result.stats = stats
    if interrupted is not None and not isinstance(interrupted, KeyboardInterrupt):
        raise interrupted
    return result
