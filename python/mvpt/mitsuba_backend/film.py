"""The films of the Mitsuba backend: one pass's sums of every view's pixels on the device
(splatted with the sensor's reconstruction filter, docs/multiview-path-tracing.md §5 "Pixel
filters"), and the accumulators over passes on the host, with the balance estimator's
control variate (the first two passes each the other's, docs/multiview-path-tracing.md §5)."""
from __future__ import annotations

import math

import numpy as np


#: Contributions are summed as integers in units of 2^-30 (as render/splat_film.h): integer
#: addition is associative, so a pass's sums do not depend on how it is chunked or scheduled.
#: A term beyond 2^32 in magnitude is dropped (and counted).
Scale = float(1 << 30)
Largest = float(1 << 32)


class PassFilm:
    """Σ h W L + h E (RGB) and Σ h W of every view-pixel (crop windows, view after view), as
    fixed-point integers."""

    def __init__(self, ctx, models: list):
        mi, dr = ctx.mi, ctx.dr
        self.mi, self.dr, self.views = mi, dr, ctx.views
        self.size = int(ctx.views.pixel_offsets[-1])
        radius = models[0]["filter_radius"]
        table = models[0]["filter_table"]
        if any(m["filter_radius"] != radius or list(m["filter_table"]) != list(table) for m in models):
            raise ValueError("the mitsuba backend needs one reconstruction filter for every view")
        self.box = len(table) == 0
        self.radius = radius
        self.table = mi.Float(np.asarray(table, dtype=np.float32)) if not self.box else None
        self.bins = len(table)
        self.signed = (not self.box) and min(table) < 0.0
        self.taps = 1 if self.box else int(math.ceil(2.0 * radius)) + 1
        self.clear()

    def clear(self):
        dr, mi = self.dr, self.mi
        self.sum = [dr.zeros(mi.Int64, self.size) for _ in range(3)]
        self.weight = dr.zeros(mi.Int64, self.size)
        self.dropped = mi.UInt32(0)

    def _h(self, d):
        """The filter's 1-D table at offset d (pixels), 0 beyond its radius."""
        dr, mi = self.dr, self.mi
        x = (d + self.radius) * (self.bins / (2.0 * self.radius))
        inside = (x >= 0.0) & (x < self.bins)
        return dr.select(inside, dr.gather(mi.Float, self.table, mi.UInt32(dr.clip(x, 0, self.bins - 1)), inside), 0.0)

    def splat(self, view, pos, value, weight, active):
        """Add h_i(pos) (value, weight) to every pixel i of `view` whose filter covers `pos`."""
        dr, mi, v = self.dr, self.mi, self.views
        cx, cy = dr.gather(mi.Int32, v.crop_x, view), dr.gather(mi.Int32, v.crop_y, view)
        cw, ch = dr.gather(mi.Int32, v.crop_w, view), dr.gather(mi.Int32, v.crop_h, view)
        base = dr.gather(mi.UInt32, v.pixel_offset, view)
        if self.box:
            starts = (mi.Int32(dr.floor(pos.x)), mi.Int32(dr.floor(pos.y)))
        else:
            starts = (mi.Int32(dr.floor(pos.x - 0.5 - self.radius)) + 1, mi.Int32(dr.floor(pos.y - 0.5 - self.radius)) + 1)
        for ty in range(self.taps):
            py = starts[1] + ty
            hy = 1.0 if self.box else self._h(mi.Float(py) + 0.5 - pos.y)
            for tx in range(self.taps):
                px = starts[0] + tx
                h = hy if self.box else hy * self._h(mi.Float(px) + 0.5 - pos.x)
                ok = active & (px >= cx) & (px < cx + cw) & (py >= cy) & (py < cy + ch) & (h != 0.0)
                index = base + mi.UInt32((py - cy) * cw + (px - cx))
                terms = [value[0] * h, value[1] * h, value[2] * h, weight * h]
                fine = dr.all(dr.isfinite(mi.Vector4f(*terms))) & (dr.max(dr.abs(mi.Vector4f(*terms))) <= Largest)
                self.dropped += dr.count(ok & ~fine)
                ok &= fine
                for target, term in zip(self.sum + [self.weight], terms):
                    dr.scatter_reduce(dr.ReduceOp.Add, target, mi.Int64(dr.round(mi.Float64(term) * Scale)), index, ok)

    def host(self):
        """The pass's sums as numpy arrays: (pixels, 3) and (pixels,)."""
        self.dr.eval(self.sum, self.weight)
        s = np.stack([np.asarray(s, dtype=np.int64) for s in self.sum], axis=1) / Scale
        return s, np.asarray(self.weight, dtype=np.int64) / Scale


class Accumulator:
    """Pass estimates v = S + β (1 − W) summed over passes (mean and Welford spread), β the
    mean of the earlier passes' estimates; the first pass is held until the second, and the
    two take each other's ratio S/W as β. With a filter of negative lobes a ratio counts only
    where W ≥ 1/4 (as Film::signed_filter)."""

    def __init__(self, size: int, control_variate: bool, signed: bool):
        self.size, self.cv, self.signed = size, control_variate, signed
        self.passes = 0
        self.total = np.zeros((size, 3))
        self.m2 = np.zeros((size, 3))
        self.held = None
        self.weight_total = np.zeros(size)  # Σ W over passes (1 per pass in expectation)

    def _ratio(self, s, w):
        ok = (w >= 0.25) if self.signed else (w > 0.0)
        return np.where(ok[:, None], s / np.where(ok, w, 1.0)[:, None], 0.0)

    def _add(self, v):
        self.passes += 1
        delta = v - (self.total / max(self.passes - 1, 1) if self.passes > 1 else v)
        self.total += v
        self.m2 += delta * (v - self.total / self.passes)

    def fold(self, s, w):
        self.weight_total += w
        if not self.cv:
            self._add(s)
        elif self.passes == 0 and self.held is None:
            self.held = (s, w)
        elif self.held is not None:
            s1, w1 = self.held
            self.held = None
            self._add(s1 + self._ratio(s, w) * (1.0 - w1)[:, None])
            self._add(s + self._ratio(s1, w1) * (1.0 - w)[:, None])
        else:
            self._add(s + (self.total / self.passes) * (1.0 - w)[:, None])

    def finish(self):
        """A pass still held (a render of one pass) is added without β."""
        if self.held is not None:
            self._add(self.held[0])
            self.held = None

    def image(self):
        n = max(self.passes, 1)
        var = self.m2 / (n * (n - 1)) if n > 1 else np.zeros_like(self.m2)
        return self.total / n, var
