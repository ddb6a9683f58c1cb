"""Rendered runs read back from disk, for `mvpt compare` and the equal-time reports.

A run is given as one of
- an output directory of `mvpt render` (its one <stem>.json names the views; the images
  are the <stem>_<view>.exr files beside it),
- such a <stem>.json file (for a directory holding several runs),
- a multi-view EXR (`--multiview-exr`; one part per view, named by the view id), or
- a single-part EXR, which is one view named after the file (its stem).
Views are matched between runs by id; two single-view runs are matched whatever their ids."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import _core
from .output import output_paths


@dataclass
class Run:
    """Images of one run keyed by view id (scene order), its statistics if known, and where it came from."""

    name: str
    images: dict = field(default_factory=dict)
    stats: dict | None = None
    source: str = ""
    #: per view, the variance of each pixel's mean (RGB) where the run saved it (`--aovs`)
    variance: dict = field(default_factory=dict)


def _rgb(channels: dict, what: str) -> np.ndarray:
    if all(c in channels for c in "RGB"):
        return np.stack([channels[c] for c in "RGB"], axis=-1).astype(np.float32)
    if "Y" in channels:
        return np.repeat(channels["Y"][..., None], 3, axis=-1).astype(np.float32)
    raise ValueError(f"{what} has no R, G, B or Y channels (it has {', '.join(sorted(channels))})")


def _from_json(path: Path, name: str) -> Run:
    try:
        stats = json.loads(path.read_text())
        ids = list(stats["views"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise ValueError(f"'{path}' is not a summary written by mvpt render ({e})") from None
    per_view, _ = output_paths(path.parent, path.stem, ids)
    run = Run(name=name, stats=stats, source=str(path))
    for vid in ids:
        exr = per_view[vid][0]
        if not exr.is_file():
            raise ValueError(f"'{path}' names view '{vid}' but its image '{exr}' is missing")
        channels = dict(_core.read_multiview_exr(str(exr))[0][1])
        run.images[vid] = _rgb(channels, f"'{exr}'")
        if all(f"variance.{c}" in channels for c in "RGB"):
            run.variance[vid] = np.stack([channels[f"variance.{c}"] for c in "RGB"], axis=-1).astype(np.float32)
    return run


def _from_exr(path: Path) -> Run:
    parts = _core.read_multiview_exr(str(path))
    run = Run(name=path.stem, source=str(path))
    if len(parts) == 1:
        run.images[path.stem] = _rgb(parts[0][1], f"'{path}'")
        return run
    for name, channels in parts:
        run.images[name] = _rgb(channels, f"part '{name}' of '{path}'")
    return run


def load_run(path) -> Run:
    """Read a run from an output directory, its JSON summary, or an EXR file (see the module doc)."""
    p = Path(path)
    if p.is_dir():
        summaries = sorted(p.glob("*.json"))
        if len(summaries) != 1:
            what = "no" if not summaries else f"{len(summaries)} ({', '.join(s.name for s in summaries)})"
            raise ValueError(f"'{p}' holds {what} run summaries (*.json); name the one to use")
        return _from_json(summaries[0], p.resolve().name)
    if not p.exists():
        raise ValueError(f"'{p}' does not exist")
    if p.suffix.lower() == ".json":
        return _from_json(p, p.stem)
    if p.suffix.lower() == ".exr":
        return _from_exr(p)
    raise ValueError(f"'{p}' is neither an output directory, a run summary (.json) nor an EXR file")


def match_views(test: dict, ref: dict) -> tuple:
    """(test, ref) restricted to matching views: by id, or the only view of each if both have one."""
    if len(test) == 1 and len(ref) == 1:
        (k, x), (_, r) = next(iter(test.items())), next(iter(ref.items()))
        return {k: x}, {k: r}
    missing = [k for k in test if k not in ref]
    if missing:
        raise ValueError(f"the reference has no view {', '.join(map(repr, missing))} "
                         f"(its views: {', '.join(map(str, ref))})")
    return dict(test), {k: ref[k] for k in test}
