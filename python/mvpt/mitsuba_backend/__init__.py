"""Multi-view path tracing on stock Mitsuba 3 with Dr.Jit (docs/mitsuba-backend.md): the same
estimator as `--method mvpt`, with Mitsuba's geometry, BSDFs and emitters, compiled by Dr.Jit
for the CPU (`llvm_ad_rgb`) or an NVIDIA GPU (`cuda_ad_rgb`).

    result = mvpt.render(scene, spp=64, backend="mitsuba")            # cuda where present, else llvm
    result = mvpt.render(scene, spp=64, backend="mitsuba:llvm_ad_rgb")
"""
from __future__ import annotations

import math
import time as _time

import numpy as np

from . import cameras, estimator
from .film import Accumulator, PassFilm
from .scene import load_mitsuba_scene, refusal

#: Most (sample, view) pairs one chunk of a pass holds: the arrays of a launch stay within
#: about 2^22 pairs x ~300 bytes (1.2 GiB) whatever the views and their size.
PairsPerChunk = 1 << 22


#: The variants the estimator is written for (RGB, traced by Dr.Jit's JIT).
Variants = ("cuda_ad_rgb", "llvm_ad_rgb")


def _runs(mi, variant: str) -> str:
    """'' when `variant` runs here, else why not (one line)."""
    try:
        mi.set_variant(variant)
        mi.Float(0.0).numpy()  # a variant without its device or LLVM fails here
        return ""
    except Exception as e:  # (Dr.Jit raises ImportError, RuntimeError, ...)
        return str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__


def pick_variant(mi, variant: str | None) -> str:
    """`variant`, else cuda_ad_rgb where a GPU is present, else llvm_ad_rgb."""
    if variant:
        if variant not in Variants or variant not in mi.variants():
            raise ValueError(f"the mitsuba backend runs on {' or '.join(Variants)}, not {variant!r}")
        why = _runs(mi, variant)
        if why:
            raise ValueError(f"Mitsuba's {variant} does not run here: {why}")
        return variant
    for v in Variants:
        if v in mi.variants() and not _runs(mi, v):
            return v
    raise ValueError("the mitsuba backend needs Mitsuba's cuda_ad_rgb (a GPU) or llvm_ad_rgb (LLVM 19)")


class Context:
    """What every chunk reads: Mitsuba's scene, the views, the path settings and the seed."""

    def __init__(self, mi, dr, scene, models, settings, seed: int, share: bool):
        self.mi, self.dr, self.scene = mi, dr, scene
        self.views = cameras.ViewTable(mi, models)
        self.max_depth = settings["max_depth"]
        self.rr_depth = settings["rr_depth"]
        self.hide_emitters = settings["hide_emitters"]
        self.seed = seed
        self.share = mi.Bool(share)
        # First vertices hit and the views they reached (mean |S|), summed on the device.
        self.shared_vertices, self.contributions = mi.Float(0.0), mi.Float(0.0)


def render(scene, spp: int = 0, time: float = 0.0, seed=None, views=None, progress=None,
           method: str = "mvpt", variant: str | None = None, chunk: int = 0):
    """Render `scene` (an mvpt Scene read from a file) with Dr.Jit on Mitsuba 3: method "mvpt"
    (multi-view path tracing) or "pt" (each view alone, the same code without sharing).
    spp: passes of one native sample per pixel (0: the first view's sample_count); time: a
    wall-clock budget in seconds (0: none; a pass starts only if it should end within it);
    chunk: native samples per launch (0: as many as keep PairsPerChunk pairs). Ctrl-C keeps
    the finished passes (stats["cancelled"]). Returns an mvpt.RenderResult."""
    import mitsuba as mi
    before = mi.variant()
    try:  # (Mitsuba's variant is global: the caller's is left as it was)
        return _render(mi, scene, spp, time, seed, views, progress, method, variant, chunk)
    finally:
        if before is not None and mi.variant() != before:
            mi.set_variant(before)


def _render(mi, scene, spp, time, seed, views, progress, method, variant, chunk):
    from ..api import RenderResult, resolve_views
    import drjit as dr
    if method not in ("mvpt", "pt"):
        raise ValueError(f"the mitsuba backend renders method 'mvpt' or 'pt', not {method!r}")
    index = resolve_views(scene, views) or list(range(len(scene.views)))
    why = refusal(scene, index)
    if why:
        raise ValueError(f"the mitsuba backend cannot render this scene: {why}")
    mi.set_variant(pick_variant(mi, variant))
    models = [scene.camera_model(i) for i in index]
    started = _time.monotonic()
    ctx = Context(mi, dr, load_mitsuba_scene(mi, scene), models, scene.path_settings,
                  0 if seed is None else int(seed), method == "mvpt")
    film = PassFilm(ctx, models)
    acc = Accumulator(film.size, control_variate=True, signed=film.signed)
    passes = int(spp) if spp else int(scene.views[index[0]]["spp"])
    total = int(ctx.views.sample_offsets[-1])
    chunk = int(chunk) or max(1, PairsPerChunk // (len(index) if method == "mvpt" else 1))
    cancelled, last = False, 0.0
    try:
        for p in range(passes if not time else 2**31 - 1):
            elapsed = _time.monotonic() - started
            if time and p > 0 and elapsed + last > time:
                break
            t = _time.monotonic()
            film.clear()
            for start in range(0, total, chunk):
                estimator.render_chunk(ctx, start, min(total, start + chunk), p, film)
                dr.eval(film.sum, film.weight, ctx.shared_vertices, ctx.contributions)
            acc.fold(*film.host())
            last = _time.monotonic() - t
            if progress is not None:
                done = acc.passes + (acc.held is not None)
                progress({"pass": done, "passes": done, "fraction": (p + 1) / passes if not time
                          else min(1.0, (_time.monotonic() - started) / time), "seconds": _time.monotonic() - started})
    except KeyboardInterrupt:
        cancelled = True
    acc.finish()
    return _result(RenderResult(), scene, index, ctx, acc, dict(
        method=method, variant=mi.variant(), seconds=_time.monotonic() - started, cancelled=cancelled,
        spp=spp, time=time, seed=seed, chunk=chunk))


def _result(result, scene, index, ctx, acc, info):
    mean, var = acc.image()
    offsets = ctx.views.pixel_offsets
    views = {}
    for j, i in enumerate(index):
        w, h = int(ctx.views.crops[j, 2]), int(ctx.views.crops[j, 3])
        vid = scene.views[i]["id"]
        img = mean[offsets[j]:offsets[j + 1]].reshape(h, w, 3).astype(np.float32)
        result.images[vid] = img
        result.variance[vid] = var[offsets[j]:offsets[j + 1]].reshape(h, w, 3).astype(np.float32)
        result.sample_count[vid] = np.full((h, w), float(acc.passes), np.float32)
        result.weight_sum[vid] = (acc.weight_total[offsets[j]:offsets[j + 1]] / max(acc.passes, 1)).reshape(h, w)
        views[vid] = {"id": vid, "index": i, "width": w, "height": h, "spp": float(acc.passes),
                      "samples": acc.passes * w * h, "mean": [float(x) for x in img.reshape(-1, 3).mean(axis=0)],
                      "nonfinite_samples": int((~np.isfinite(img)).sum())}
    samples = sum(v["samples"] for v in views.values())
    seconds = info["seconds"]
    result.stats = {
        "settings": dict(spp=info["spp"], time=info["time"], seed=info["seed"], method=info["method"],
                         backend="mitsuba", variant=info["variant"], chunk=info["chunk"], views=list(views)),
        "backend": "mitsuba", "variant": info["variant"], "method": info["method"], "estimator": "balance",
        "wall_time": seconds, "seconds": seconds, "passes": acc.passes, "cancelled": info["cancelled"],
        "samples": samples, "samples_per_second": samples / seconds if seconds > 0 else 0.0,
        "integrator": scene.integrator, "notes": list(scene.notes), "warnings": list(scene.warnings),
        "state_error": None, "views": views,
        "multiview": {"mean_sharing": float(ctx.contributions[0]) / max(float(ctx.shared_vertices[0]), 1.0)},
    }
    return result
