"""Image error metrics against a reference: RMSE, relMSE and FLIP, per view and over all views.

Definitions (x: test, r: reference, both linear RGB, N = pixels x 3 channels):

- RMSE   = sqrt( (1/N) sum (x - r)^2 )
- relMSE = (1/N) sum (x - r)^2 / (r^2 + eps),  eps = RELMSE_EPS = 1e-2
  (per channel, as in Rousselle et al. 2011 "Adaptive sampling and reconstruction
  using greedy error minimization"; eps keeps dark pixels from dominating).
- FLIP   = mean of the HDR-FLIP error map [Andersson et al. 2021, "Visualizing Errors
  in Rendered High Dynamic Range Images"], computed by the `flip-evaluator` package
  with its defaults (67 pixels per degree; exposure range from the reference).
  Negative values are clipped to 0 first (FLIP expects non-negative radiance).

"Overall" pools every pixel of every view: RMSE and relMSE are the metric of all
pixels together (so larger views weigh more) and FLIP is the pixel-weighted mean of
the per-view FLIP means. Non-finite test pixels make a metric NaN rather than hiding."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .images import as_rgb

RELMSE_EPS = 1e-2


def _pair(test, ref):
    x = np.asarray(test, dtype=np.float64)
    r = np.asarray(ref, dtype=np.float64)
    if x.shape != r.shape:
        raise ValueError(f"test image has shape {x.shape} but the reference has {r.shape}")
    return x, r


def squared_error(test, ref) -> np.ndarray:
    """(x - r)^2 per pixel and channel."""
    x, r = _pair(test, ref)
    return (x - r) ** 2


def relative_squared_error(test, ref, eps: float = RELMSE_EPS) -> np.ndarray:
    """(x - r)^2 / (r^2 + eps) per pixel and channel."""
    x, r = _pair(test, ref)
    return (x - r) ** 2 / (r * r + eps)


def mse(test, ref) -> float:
    """Mean squared error over pixels and channels."""
    return float(np.mean(squared_error(test, ref)))


def rmse(test, ref) -> float:
    """Root of the mean squared error over pixels and channels."""
    return float(np.sqrt(mse(test, ref)))


def relmse(test, ref, eps: float = RELMSE_EPS) -> float:
    """Mean over pixels and channels of (x - r)^2 / (r^2 + eps)."""
    return float(np.mean(relative_squared_error(test, ref, eps)))


def _flip_module():
    try:
        import flip_evaluator
    except ImportError as e:  # an optional dependency: pip install "mvpt[reports]"
        raise ImportError("FLIP needs the 'flip-evaluator' package (pip install flip-evaluator)") from e
    return flip_evaluator


def flip_map(test, ref) -> tuple:
    """(per-pixel HDR-FLIP error (H, W) float32, its mean) of linear RGB `test` against `ref`."""
    x, r = _pair(as_rgb(test), as_rgb(ref))
    x = np.ascontiguousarray(np.clip(np.nan_to_num(x, nan=0.0), 0.0, None), dtype=np.float32)
    r = np.ascontiguousarray(np.clip(np.nan_to_num(r, nan=0.0), 0.0, None), dtype=np.float32)
    error, mean, _ = _flip_module().evaluate(r, x, "HDR", applyMagma=False)
    error = np.asarray(error, dtype=np.float32)
    return error.reshape(error.shape[0], error.shape[1]), float(mean)


def flip(test, ref) -> float:
    """Mean HDR-FLIP error of linear RGB `test` against `ref` (0 = identical, 1 = worst)."""
    return flip_map(test, ref)[1]


@dataclass
class ViewErrors:
    """The metrics of one view, with the pixel count used to pool them."""

    rmse: float
    relmse: float
    flip: float
    pixels: int

    def as_dict(self) -> dict:
        return {"rmse": self.rmse, "relmse": self.relmse, "flip": self.flip, "pixels": self.pixels}


@dataclass
class Errors:
    """Per-view metrics (keyed by view id) and the overall ones."""

    views: dict = field(default_factory=dict)
    overall: ViewErrors | None = None

    def as_dict(self) -> dict:
        return {"views": {k: v.as_dict() for k, v in self.views.items()},
                "overall": self.overall.as_dict() if self.overall else None}


def view_errors(test, ref, with_flip: bool = True) -> ViewErrors:
    """RMSE, relMSE and (unless `with_flip` is False: NaN) FLIP of one view."""
    x, r = _pair(as_rgb(test), as_rgb(ref))
    return ViewErrors(rmse=rmse(x, r), relmse=relmse(x, r), flip=flip(x, r) if with_flip else float("nan"),
                      pixels=int(x.shape[0] * x.shape[1]))


def pool(views: dict) -> ViewErrors:
    """Overall metrics of per-view ones: pixel-weighted means of MSE (then the root), relMSE and FLIP."""
    if not views:
        raise ValueError("no views to pool")
    n = np.array([v.pixels for v in views.values()], dtype=np.float64)
    w = n / n.sum()
    mse_all = float(np.sum(w * np.array([v.rmse ** 2 for v in views.values()])))
    return ViewErrors(rmse=float(np.sqrt(mse_all)),
                      relmse=float(np.sum(w * np.array([v.relmse for v in views.values()]))),
                      flip=float(np.sum(w * np.array([v.flip for v in views.values()]))),
                      pixels=int(n.sum()))


def reference_noise(ref: dict, variance: dict, eps: float = RELMSE_EPS) -> dict:
    """The relMSE that a reference's own noise adds to any estimate measured against it, per view
    and pooled ("overall"): mean of Var(r) / (r^2 + eps) over pixels and channels, with Var(r) the
    variance of the reference's pixel means. An estimate x independent of the reference has
    E[(x - r)^2] = E[(x - I)^2] + Var(r), so subtracting it leaves the estimate's own error.
    Empty when a view's variance is unknown."""
    if not ref or any(k not in variance for k in ref):
        return {}
    out, weights = {}, {}
    for k, r in ref.items():
        r = as_rgb(r).astype(np.float64)
        v = as_rgb(variance[k]).astype(np.float64)
        out[k] = float(np.mean(v / (r * r + eps)))
        weights[k] = r.shape[0] * r.shape[1]
    total = sum(weights.values())
    out["overall"] = sum(out[k] * (weights[k] / total) for k in ref)  # (one view: exactly its own)
    return out


def errors(test: dict, ref: dict, with_flip: bool = True) -> Errors:
    """Metrics of every view of `test` ({view id: image}) against the same view of `ref`.

    Raises ValueError naming the views that `ref` lacks."""
    missing = [k for k in test if k not in ref]
    if missing:
        raise ValueError(f"the reference has no view {', '.join(map(repr, missing))} "
                         f"(its views: {', '.join(map(str, ref)) or 'none'})")
    out = Errors(views={k: view_errors(img, ref[k], with_flip) for k, img in test.items()})
    out.overall = pool(out.views)
    return out


def display_rows(views) -> list:
    """The views as a display lays them out, in rows: a grid rig's `r{row}c{col}` views by row
    (columns in order), any other set of views in the order given as one row."""
    import re
    grid = [re.fullmatch(r"r(\d+)c(\d+)", str(v)) for v in views]
    if views and all(grid):
        rows: dict = {}
        for v, m in zip(views, grid):
            rows.setdefault(int(m[1]), []).append((int(m[2]), v))
        return [[v for _, v in sorted(r)] for _, r in sorted(rows.items())]
    return [list(views)]


def display_weights(n: int) -> np.ndarray:
    """(n, n) weights of a row of n views as a lenticular panel's crosstalk shows them: each view
    blended with its neighbours, 1/4, 1/2, 1/4, the ends clamped (a view at an end counts its
    missing neighbour as itself); the identity for one view."""
    w = np.zeros((n, n))
    for i in range(n):
        for j, a in ((i - 1, 0.25), (i, 0.5), (i + 1, 0.25)):
            w[i, min(max(j, 0), n - 1)] += a
    return w


def display_images(images: dict, rows=None) -> dict:
    """Each view as a display shows it (display_weights along its row of display_rows)."""
    out = {}
    for row in rows if rows is not None else display_rows(list(images)):
        stack = np.stack([np.asarray(images[v], dtype=np.float64) for v in row])
        blended = np.tensordot(display_weights(len(row)), stack, axes=1)
        out.update(zip(row, blended))
    return out


def display_relmse(test: dict, ref: dict, variance: dict | None = None, eps: float = RELMSE_EPS) -> tuple:
    """relMSE of what a display shows, pooled over every pixel of every view: the test's views and
    the reference's blended alike (display_images, the reference's rows). Second, the part of it
    that the reference's own noise adds (its views independent: the blended variance is the sum
    of the squared weights times each view's variance), None without `variance`."""
    rows = display_rows(list(ref))
    t, r = display_images(test, rows), display_images(ref, rows)
    num = sum(relative_squared_error(t[v], r[v], eps).sum() for v in r)
    den = sum(np.asarray(r[v]).size for v in r)
    if variance is None:
        return float(num / den), None
    noise = 0.0
    for row in rows:
        w2 = display_weights(len(row)) ** 2
        var = np.tensordot(w2, np.stack([np.asarray(variance[v], dtype=np.float64) for v in row]), axes=1)
        noise += sum(float(np.sum(var[i] / (r[v] ** 2 + eps))) for i, v in enumerate(row))
    return float(num / den), noise / den
