"""`mvpt compare A B ... --reference R`: per-view and overall RMSE, relMSE and FLIP of runs.

See runs.py for what a run path may be and metrics.py for the exact metric definitions."""
from __future__ import annotations

import math

from . import metrics
from .runs import Run, load_run, match_views


def compare_runs(runs: list, reference: Run, with_flip: bool = True) -> dict:
    """{run name: metrics.Errors} of every run's views against the reference's same views."""
    out = {}
    for run in runs:
        test, ref = match_views(run.images, reference.images)
        name, k = run.name, 2
        while name in out:  # two inputs with the same name (e.g. a/out and b/out)
            name, k = f"{run.name} ({k})", k + 1
        out[name] = metrics.errors(test, ref, with_flip=with_flip)
    return out


def compare_paths(paths: list, reference, with_flip: bool = True) -> tuple:
    """Load the runs at `paths` and the reference run, then compare them: (reference Run, results)."""
    ref = load_run(reference)
    runs = [load_run(p) for p in paths]
    return ref, compare_runs(runs, ref, with_flip=with_flip)


def _num(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{x:.4g}"


def format_table(results: dict) -> str:
    """Plain-text table: one row per run and view, then each run's overall row."""
    header = ["run", "view", "RMSE", "relMSE", "FLIP"]
    rows = []
    for name, errs in results.items():
        for vid, e in errs.views.items():
            rows.append([name, vid, _num(e.rmse), _num(e.relmse), _num(e.flip)])
        o = errs.overall
        rows.append([name, "(overall)", _num(o.rmse), _num(o.relmse), _num(o.flip)])
    cells = [header] + rows
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    align = "<<>>>"
    lines = ["  ".join(f"{c:{a}{w}}" for c, a, w in zip(r, align, widths)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines) + "\n"


def as_json(reference: Run, results: dict) -> dict:
    """The comparison as a JSON-ready dict (with the metric definitions, so the file stands alone)."""
    return {
        "reference": reference.source,
        "definitions": {
            "rmse": "sqrt(mean over pixels and channels of (x-r)^2)",
            "relmse": f"mean over pixels and channels of (x-r)^2/(r^2+eps), eps={metrics.RELMSE_EPS}",
            "flip": "mean HDR-FLIP error (flip-evaluator, default parameters)",
            "overall": "all pixels of all views pooled (FLIP: pixel-weighted mean of the view means)",
        },
        "runs": {name: e.as_dict() for name, e in results.items()},
    }
