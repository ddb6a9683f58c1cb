"""Per-view outputs: float EXR (RGB plus optional AOVs), sRGB PNG preview, JSON summary."""
from __future__ import annotations

import json
import os
import re
import tempfile
from pathlib import Path

import numpy as np

from . import _core


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name)


def write_json_atomic(path: Path, data: dict) -> None:
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix="." + path.name, dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(data, f, indent=2, sort_keys=True)
            f.write("\n")
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_outputs(result, out_dir, stem: str, aovs: bool = False, settings: dict | None = None) -> list:
    """Write <stem>_<view>.exr/.png for every view and <stem>.json; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for vid, img in result.images.items():
        base = out / f"{_safe(stem)}_{_safe(vid)}"
        img = np.ascontiguousarray(img, dtype=np.float32)
        channels = {"R": np.ascontiguousarray(img[..., 0]), "G": np.ascontiguousarray(img[..., 1]),
                    "B": np.ascontiguousarray(img[..., 2])}
        if aovs:
            var = result.variance[vid]
            channels["variance.R"] = np.ascontiguousarray(var[..., 0])
            channels["variance.G"] = np.ascontiguousarray(var[..., 1])
            channels["variance.B"] = np.ascontiguousarray(var[..., 2])
            channels["sample_count.Y"] = np.ascontiguousarray(result.sample_count[vid], dtype=np.float32)
        _core.write_exr(str(base) + ".exr", channels)
        _core.write_png(str(base) + ".png", img)
        written += [str(base) + ".exr", str(base) + ".png"]
    summary = {"settings": settings or {}, "stats": result.stats}
    write_json_atomic(out / f"{_safe(stem)}.json", summary)
    written.append(str(out / f"{_safe(stem)}.json"))
    return written
