"""Render state files (docs/checkpoints.md): what a render has done, to resume it.

The native renderer writes the accumulators; this module writes and checks the header that
names what they belong to: the mvpt version, the scene (every file it was read from, by
SHA-256, with its <default> overrides and rig) and the settings that determine the image.
A render resumes only from a state whose header matches its own; anything else is refused
with the differences named."""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from . import __version__, _core

SUFFIX = ".mvpt-state"
StateError = _core.StateError

# Settings that determine the image (threads do not: images are identical for any count).
IMAGE_SETTINGS = ("method", "spp", "time", "seed", "views", "passes", "splits")
# What ranges of one render may differ in (each takes other samples); the rest must be equal.
RANGE_SETTINGS = ("seed", "passes", "spp", "time")


def state_file(out_dir, stem: str) -> Path:
    """Where a render of `stem` into `out_dir` keeps its state."""
    from .output import _safe
    return Path(out_dir) / f"{_safe(stem)}{SUFFIX}"


def _sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def scene_identity(scene) -> dict:
    """The scene as a state file names it: its files by content (named relative to the scene
    file's directory, so that a copy of the scene elsewhere, as on a cluster's nodes, is the same
    scene), its overrides and rig."""
    files = scene.source_files
    root = os.path.dirname(files[0]) if files else ""
    return {"files": {os.path.relpath(p, root) if root else p: _sha256(p) for p in files},
            "defines": dict(sorted(scene.defines.items())), "rig": scene.rig,
            "views": [v["id"] for v in scene.views]}


def make_header(scene, settings: dict, extra: dict | None = None, identity: dict | None = None) -> dict:
    """The header of a state file: version, scene identity, image settings and `extra` (e.g.
    the command line's outputs, which a resume reuses but which do not change the image)."""
    first, count = settings["passes"] or (0, None)
    return {"mvpt": __version__, "scene": identity or scene_identity(scene),
            "settings": {k: settings.get(k) for k in IMAGE_SETTINGS}, "extra": extra or {},
            "parts": [[settings["seed"], first, count]]}


def read_header(path) -> dict:
    """The header of the state file at `path`; StateError if it is not a usable state file."""
    text = _core.read_state_header(os.fspath(path))
    try:
        header = json.loads(text)
    except ValueError:
        raise StateError(f"the state file '{path}' has a corrupt header") from None
    if not isinstance(header, dict) or not {"mvpt", "scene", "settings"} <= header.keys():
        raise StateError(f"the state file '{path}' has a corrupt header")
    return header


def differences(saved: dict, current: dict) -> list:
    """What differs between two headers, one phrase each (empty: the state can be resumed)."""
    out = []
    if saved["mvpt"] != current["mvpt"]:
        out.append(f"mvpt version {saved['mvpt']} wrote it, this is {current['mvpt']}")
    a, b = saved["scene"], current["scene"]
    for path in sorted(set(a.get("files", {})) | set(b.get("files", {}))):
        if path not in b.get("files", {}):
            out.append(f"the scene no longer reads {path}")
        elif path not in a.get("files", {}):
            out.append(f"the scene now reads {path}")
        elif a["files"][path] != b["files"][path]:
            out.append(f"{path} has changed")
    for key, name in (("defines", "the -D overrides"), ("rig", "the rig"), ("views", "the scene's views")):
        if a.get(key) != b.get(key):
            out.append(f"{name}: {a.get(key)!r} then, {b.get(key)!r} now")
    for key in IMAGE_SETTINGS:
        if saved["settings"].get(key) != current["settings"].get(key):
            out.append(f"{key}: {saved['settings'].get(key)!r} then, {current['settings'].get(key)!r} now")
    return out


def check_resumable(path, current: dict) -> dict:
    """The saved header of `path` if `current` may continue it; StateError naming what differs."""
    saved = read_header(path)
    if saved.get("merged"):
        raise StateError(f"cannot resume from '{path}': it is a merge of {len(saved['parts'])} states")
    diff = differences(saved, current)
    if diff:
        raise StateError(f"cannot resume from '{path}': " + "; ".join(diff))
    return saved


def _overlap(a: list, b: list) -> bool:
    """Whether two parts [seed, first pass, count or None (unbounded)] can share samples."""
    if a[0] != b[0]:
        return False  # other seeds: other sample streams
    end = lambda p: float("inf") if p[2] is None else p[1] + p[2]
    return a[1] < end(b) and b[1] < end(a)


def _part(p: list) -> str:
    seed = "the sensors' seed" if p[0] is None else f"seed {p[0]}"
    return f"passes {p[1]}:{'all' if p[2] is None else p[2]} of {seed}"


def check_mergeable(paths: list) -> list:
    """The headers of the state files `paths` if they are parts of one render that take
    disjoint samples (other pass ranges or seeds); StateError naming what differs otherwise."""
    headers = [read_header(p) for p in paths]
    first = headers[0]
    for path, h in zip(paths[1:], headers[1:]):
        a, b = dict(first), dict(h)
        a["settings"] = {k: v for k, v in first["settings"].items() if k not in RANGE_SETTINGS}
        b["settings"] = {k: v for k, v in h["settings"].items() if k not in RANGE_SETTINGS}
        diff = differences(a, b)
        if diff:
            raise StateError(f"cannot merge '{paths[0]}' and '{path}': " + "; ".join(diff))
    parts = [(path, part) for path, h in zip(paths, headers) for part in h.get("parts", [])]
    for i, (pa, a) in enumerate(parts):
        for pb, b in parts[i + 1:]:
            if _overlap(a, b):
                raise StateError(f"cannot merge '{pa}' ({_part(a)}) and '{pb}' ({_part(b)}): they share samples")
    return headers


def part_key(part: list) -> tuple:
    """Parts in order: the sensors' seed first, then by seed, then by first pass."""
    return (part[0] is not None, part[0] or 0, part[1])


def merged_header(headers: list) -> dict:
    """The header of the merge of states with `headers` (check_mergeable)."""
    out = dict(headers[0])
    out["settings"] = dict(out["settings"], seed=None, passes=None)
    out["parts"] = sorted((p for h in headers for p in h.get("parts", [])), key=part_key)
    out["merged"] = True
    return out
