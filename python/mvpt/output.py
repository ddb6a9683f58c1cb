"""Per-view outputs: float EXR (RGB plus optional AOVs), sRGB PNG preview, JSON summary.

Every file is written to a temporary name in the output directory and renamed into place,
so a reader never sees a partial file and no temporary file is left behind. A render's whole
set of outputs is first written into a hidden staging directory inside the output directory
and then moved into place, the JSON summary last (`staged_outputs`): an interruption or an
error while writing leaves the previous outputs, and a JSON that is new means every file
named in it is new."""
from __future__ import annotations

import contextlib
import json
import math
import os
import re
import secrets
import shutil
from pathlib import Path

import numpy as np

from . import _core


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def _json_clean(x):
    """JSON-safe copy: NumPy scalars to Python numbers, non-finite floats to None."""
    if isinstance(x, dict):
        return {str(k): _json_clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_clean(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, os.PathLike):
        return os.fspath(x)
    return x


def write_json_atomic(path: Path, data: dict) -> None:
    """Write `data` as JSON to `path` through a temporary file and a rename."""
    path = Path(path)
    tmp = str(path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, as for the images
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(_json_clean(data), f, indent=2, sort_keys=True, allow_nan=False)
            f.write("\n")
        os.replace(tmp, path)
    except BaseException as e:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(e, OSError):
            raise OSError(f"cannot write '{path}': {e.strerror or e}") from None
        raise


def output_paths(out_dir, stem: str, view_ids) -> dict:
    """{view id: (exr path, png path)} and the JSON path, as `write_outputs` names them."""
    out = Path(out_dir)
    per_view, used = {}, set()
    for i, vid in enumerate(view_ids):
        name = f"{_safe(stem)}_{_safe(vid)}"
        if name in used:  # ids that differ only in characters unsafe in file names
            name += f"_{i}"
        used.add(name)
        per_view[vid] = (out / f"{name}.exr", out / f"{name}.png")
    return per_view, out / f"{_safe(stem)}.json"


def write_outputs(result, out_dir, stem: str, aovs: bool = False, settings: dict | None = None) -> list:
    """Write <stem>_<view>.exr/.png for every view and <stem>.json; returns the paths.

    The EXR has channels R, G, B and, with `aovs`, variance.R/G/B (variance of the pixel
    mean) and sample_count.Y (multi-view path tracing: native samples, plus contributions.Y,
    the contributions each pixel received). The JSON holds `result.stats`, its settings updated with
    `settings` (e.g. the scene file and -D defines of the command line)."""
    if not all(hasattr(result, a) for a in ("images", "stats")):
        raise ValueError(f"write_outputs takes the result of mvpt.render, got {type(result).__name__}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    per_view, json_path = output_paths(out, stem, result.images.keys())
    written = []
    for vid, img in result.images.items():
        exr, png = per_view[vid]
        img = np.ascontiguousarray(img, dtype=np.float32)
        channels = {c: np.ascontiguousarray(img[..., i]) for i, c in enumerate("RGB")}
        if aovs:
            var = result.variance[vid]
            for i, c in enumerate("RGB"):
                channels[f"variance.{c}"] = np.ascontiguousarray(var[..., i], dtype=np.float32)
            channels["sample_count.Y"] = np.ascontiguousarray(result.sample_count[vid], dtype=np.float32)
            if vid in getattr(result, "contributions", {}):  # multi-view: sample_count counts native samples
                channels["contributions.Y"] = np.ascontiguousarray(result.contributions[vid], dtype=np.float32)
        _core.write_exr(str(exr), channels)
        _core.write_png(str(png), img)
        written += [str(exr), str(png)]
    summary = dict(result.stats)
    summary["settings"] = dict(summary.get("settings", {}), **(settings or {}))
    write_json_atomic(json_path, summary)
    written.append(str(json_path))
    return written


STEREO_NAMES = ("left", "right")


def multiview_exr_path(out_dir, stem: str) -> Path:
    """Where `write_multiview_exr` puts a run's multi-view EXR: <out>/<stem>.exr (per-view files add _<view>)."""
    return Path(out_dir) / f"{_safe(stem)}.exr"


def write_multiview_exr(result, path, stereo: bool = False, aovs: bool = False) -> str:
    """All views of `result` in one multi-part EXR: one part per view, in scene order.

    A part's name and `view` attribute are the view id, or with `stereo` (exactly two
    views) the standard names "left" (the first view) and "right"; every part lists all
    names in a `multiView` attribute, so the first view is the default view. Channels as
    in `write_outputs` (R, G, B, and with `aovs` variance.R/G/B and sample_count.Y)."""
    ids = list(result.images)
    if stereo and len(ids) != 2:
        raise ValueError(f"stereo names need exactly two views, the render has {len(ids)}")
    names = list(STEREO_NAMES) if stereo else ids
    parts = []
    for name, vid in zip(names, ids):
        img = np.asarray(result.images[vid], dtype=np.float32)
        channels = {c: np.ascontiguousarray(img[..., i]) for i, c in enumerate("RGB")}
        if aovs:
            var = np.asarray(result.variance[vid], dtype=np.float32)
            for i, c in enumerate("RGB"):
                channels[f"variance.{c}"] = np.ascontiguousarray(var[..., i])
            channels["sample_count.Y"] = np.ascontiguousarray(result.sample_count[vid], dtype=np.float32)
        parts.append((str(name), channels))
    _core.write_multiview_exr(str(path), parts)
    return str(path)


STAGING_PREFIX = ".mvpt-writing-"
# In a staging directory: the names of its files in the order they move, written (atomically)
# before the first move. A staging directory that has it holds a set that was complete.
COMMIT_RECORD = ".commit"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _move_committed(staging: Path, out: Path, names: list) -> list:
    """Moves the files `names` of `staging` into `out` in that order (those already moved are
    skipped); their final paths."""
    for name in names:
        if (staging / name).exists():
            os.replace(staging / name, out / name)
    return [str(out / name) for name in names]


def recover_outputs(out_dir) -> None:
    """Finishes the output sets that processes no longer running (killed while writing) left in
    `out_dir`: a staging directory with its commit record held a complete set, whose moves are
    completed; one without held an unfinished set, which is removed, leaving the previous
    outputs."""
    for old in Path(out_dir).glob(f"{STAGING_PREFIX}*"):
        pid = old.name[len(STAGING_PREFIX):].split("-")[0]
        if not (pid.isdigit() and not _alive(int(pid))):
            continue
        record = old / COMMIT_RECORD
        if record.is_file():
            _move_committed(old, Path(out_dir), json.loads(record.read_text(encoding="utf-8")))
        shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def staged_outputs(out_dir):
    """A staging directory inside `out_dir` for a render's outputs; on success the files
    written there (their paths appended to the yielded list) move into `out_dir`, JSON files
    last, and the list then holds their final paths. A commit record written before the first
    move makes the set atomic even under SIGKILL: recover_outputs, run first here, completes the
    moves of a killed process that had written it and removes the staging directory of one that
    had not. On an exception nothing moves and the staging directory is removed."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    recover_outputs(out)
    staging = out / f"{STAGING_PREFIX}{os.getpid()}-{secrets.token_hex(4)}"
    staging.mkdir()
    written: list = []
    try:
        yield staging, written
        names = [Path(p).name for p in sorted(written, key=lambda p: Path(p).suffix == ".json")]
        for name in names:  # what would stop a move, before anything moves
            if (out / name).is_dir():
                raise IsADirectoryError(f"cannot write '{out / name}': a directory is in the way")
        record = staging / (COMMIT_RECORD + ".tmp")
        record.write_text(json.dumps(names), encoding="utf-8")
        os.replace(record, staging / COMMIT_RECORD)
        written[:] = _move_committed(staging, out, names)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
