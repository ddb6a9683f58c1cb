"""Equal-time benchmarks: every method renders the same views for the same wall-clock time,
with a convergence series (relMSE against time) and a reference rendered once and reused.

Used by `mvpt bench-equal-time scene.xml --time T [--methods pt,mvpt]
[--reference R | --reference-spp N]`; report.py turns the result into an HTML page."""
from __future__ import annotations

import hashlib
import inspect
import json
import os
import platform
import shlex
import sys
import time as _time
from dataclasses import dataclass, field
from pathlib import Path

from . import __version__, api, metrics
from .output import write_outputs
from .runs import Run, load_run, match_views

CURVE_FRACTIONS = (0.125, 0.25, 0.5, 1.0)
DEFAULT_REFERENCE_SPP = 1024


@dataclass
class BenchConfig:
    """What one equal-time benchmark renders, and where it writes (see `mvpt bench-equal-time -h`)."""

    scene: Path
    time: float
    methods: tuple = ("pt", "mvpt")
    reference: Path | None = None
    reference_spp: int = DEFAULT_REFERENCE_SPP
    defines: dict = field(default_factory=dict)
    seed: int | None = None
    threads: int = 0
    views: list | None = None
    curve: tuple = CURVE_FRACTIONS
    output: Path = Path("bench")

    def command(self) -> list:
        """The `mvpt bench-equal-time` command line that reproduces this benchmark."""
        cmd = ["mvpt", "bench-equal-time", str(self.scene), "--time", f"{self.time:g}",
               "--methods", ",".join(self.methods), "-o", str(self.output)]
        if self.reference is not None:
            cmd += ["--reference", str(self.reference)]
        else:
            cmd += ["--reference-spp", str(self.reference_spp)]
        for k, v in self.defines.items():
            cmd += ["-D", f"{k}={v}"]
        if self.seed is not None:
            cmd += ["--seed", str(self.seed)]
        if self.threads:
            cmd += ["--threads", str(self.threads)]
        if self.views:
            cmd += ["--views", ",".join(map(str, self.views))]
        if tuple(self.curve) != CURVE_FRACTIONS:
            cmd += ["--curve", ",".join(f"{f:g}" for f in self.curve)]
        return cmd


@dataclass
class MethodRun:
    """One method's equal-time render (the last curve point) and its convergence series."""

    method: str
    run: Run
    errors: metrics.Errors
    # [{"budget", "seconds", "samples", "relmse", "relmse_corrected", "views": {id: relmse}}]
    curve: list = field(default_factory=list)
    directory: str = ""
    command: list = field(default_factory=list)
    #: relMSE with the reference's own noise subtracted, per view and "overall" (empty: unknown)
    corrected: dict = field(default_factory=dict)
    #: the error a display shows (each view blended with its neighbours along its row,
    #: metrics.display_relmse): {"relmse", "relmse_corrected"}; empty for one view
    display: dict = field(default_factory=dict)


@dataclass
class BenchResult:
    """Everything a report shows: the configuration, the reference, each method's runs and errors."""

    config: BenchConfig
    reference: Run
    reference_command: list
    methods: dict = field(default_factory=dict)  # method name -> MethodRun
    environment: dict = field(default_factory=dict)
    #: the relMSE the reference's own noise adds, per view and "overall" (metrics.reference_noise)
    reference_noise: dict = field(default_factory=dict)
    #: what a reader must know before trusting the numbers (a reference too noisy to judge, ...)
    warnings: list = field(default_factory=list)
    #: the relMSE the reference's noise adds to the display-blended error (None: unknown)
    display_noise: float | None = None

    def as_json(self) -> dict:
        c = self.config
        return {
            "command": self.config.command(),
            "config": {"scene": str(c.scene), "time": c.time, "methods": list(c.methods),
                       "reference": str(c.reference) if c.reference else None, "reference_spp": c.reference_spp,
                       "defines": c.defines, "seed": c.seed, "threads": c.threads, "views": c.views,
                       "curve": list(c.curve)},
            "reference": {"source": self.reference.source, "command": self.reference_command,
                          "noise_relmse": self.reference_noise, "display_noise_relmse": self.display_noise},
            "environment": self.environment,
            "warnings": self.warnings,
            "methods": {m: {"directory": r.directory, "command": r.command, "errors": r.errors.as_dict(),
                            "relmse_corrected": r.corrected, "display": r.display, "curve": r.curve,
                            "stats": r.run.stats}
                        for m, r in self.methods.items()},
        }


def render_supports_method() -> bool:
    """Whether api.render takes `method=` (multi-view path tracing); without it only "pt" exists."""
    return "method" in inspect.signature(api.render).parameters


def render_method(scene, method: str, **kwargs):
    """api.render with `method`, or without it for "pt" when this build's render has no methods."""
    if render_supports_method():
        return api.render(scene, method=method, **kwargs)
    if method != "pt":
        raise ValueError(f"method '{method}' is not available: this build's mvpt.render has no 'method' "
                         f"parameter, so only 'pt' can be benchmarked")
    return api.render(scene, **kwargs)


def _render_command(cfg: BenchConfig, out: Path, method: str | None, spp: int = 0, time: float = 0.0) -> list:
    """The `mvpt render` command line of one of the benchmark's renders."""
    cmd = ["mvpt", "render", str(cfg.scene)]
    for k, v in cfg.defines.items():
        cmd += ["-D", f"{k}={v}"]
    if spp:
        cmd += ["--spp", str(spp)]
    if time:
        cmd += ["--time", f"{time:g}"]
    if method is not None and render_supports_method():
        cmd += ["--method", method]
    if cfg.seed is not None:
        cmd += ["--seed", str(cfg.seed)]
    if cfg.threads:
        cmd += ["--threads", str(cfg.threads)]
    if cfg.views:
        cmd += ["--views", ",".join(map(str, cfg.views))]
    return cmd + ["-o", str(out)]


def _reference_settings(cfg: BenchConfig) -> dict:
    """What a saved reference must match to be reused: among them the scene file's bytes (an
    edited scene renders its reference again; the files it refers to are not hashed)."""
    scene = Path(cfg.scene)
    return {"scene": str(scene.resolve()), "scene_sha1": hashlib.sha1(scene.read_bytes()).hexdigest(),
            "defines": {str(k): str(v) for k, v in cfg.defines.items()},
            "reference_spp": int(cfg.reference_spp), "seed": cfg.seed, "views": cfg.views, "variance": True}


def _reuse_reference(ref_dir: Path, stem: str, settings: dict) -> Run | None:
    summary = ref_dir / f"{stem}.json"
    try:
        saved = json.loads(summary.read_text())["settings"].get("bench_reference")
    except (OSError, ValueError, KeyError, AttributeError):
        return None
    if saved != settings:
        return None
    try:
        return load_run(summary)
    except ValueError:
        return None


def reference_run(cfg: BenchConfig, scene, stem: str, log=print) -> tuple:
    """(reference Run, command that made it): the given one, a matching earlier one, or a new spp render."""
    if cfg.reference is not None:
        return load_run(cfg.reference), ["(given)", str(cfg.reference)]
    ref_dir = Path(cfg.output) / "reference"
    settings = _reference_settings(cfg)
    command = _render_command(cfg, ref_dir, "pt", spp=cfg.reference_spp)
    reused = _reuse_reference(ref_dir, stem, settings)
    if reused is not None:
        log(f"reusing the reference in {ref_dir}")
        return reused, command
    log(f"rendering the reference ({cfg.reference_spp} spp, method pt) into {ref_dir}")
    result = render_method(scene, "pt", spp=cfg.reference_spp, seed=cfg.seed, threads=cfg.threads, views=cfg.views)
    if result.stats.get("cancelled"):
        raise KeyboardInterrupt
    write_outputs(result, ref_dir, stem, aovs=True,  # the variance: the reference's own noise
                  settings={"scene": str(cfg.scene), "defines": cfg.defines, "bench_reference": settings})
    return load_run(ref_dir / f"{stem}.json"), command


def environment() -> dict:
    """Where the benchmark ran: versions, machine, date."""
    return {"mvpt": __version__, "python": sys.version.split()[0], "platform": platform.platform(),
            "machine": platform.machine(), "cpus": os.cpu_count(),
            "date": _time.strftime("%Y-%m-%d %H:%M:%S UTC", _time.gmtime())}


def run_bench(cfg: BenchConfig, log=print) -> BenchResult:
    """Render the reference (or reuse it) and every method at each curve budget; write each
    method's equal-time images to <output>/<method>/ and return the numbers."""
    if not cfg.time > 0:
        raise ValueError(f"the time budget must be > 0 seconds, got {cfg.time}")
    if not cfg.methods:
        raise ValueError("no methods to benchmark")
    if any(not 0 < f <= 1 for f in cfg.curve) or not cfg.curve:
        raise ValueError(f"curve fractions must lie in (0, 1], got {list(cfg.curve)}")
    curve = sorted(set(float(f) for f in cfg.curve) | {1.0})
    unavailable = [m for m in cfg.methods if m != "pt"] if not render_supports_method() else []
    if unavailable:
        raise ValueError(f"method {', '.join(map(repr, unavailable))} is not available: this build's mvpt.render "
                         f"has no 'method' parameter, so only 'pt' can be benchmarked")
    scene = api.load_file(cfg.scene, **cfg.defines)
    stem = Path(cfg.scene).stem
    out = Path(cfg.output)
    out.mkdir(parents=True, exist_ok=True)
    reference, ref_command = reference_run(cfg, scene, stem, log)
    result = BenchResult(config=cfg, reference=reference, reference_command=ref_command, environment=environment())
    noise = {}
    for method in cfg.methods:
        points, final = [], None
        for f in curve:
            budget = cfg.time * f
            log(f"{method}: rendering for {budget:g} s")
            r = render_method(scene, method, time=budget, seed=cfg.seed, threads=cfg.threads, views=cfg.views)
            if r.stats.get("cancelled"):
                raise KeyboardInterrupt
            test, ref = match_views(r.images, reference.images)
            errs = metrics.errors(test, ref, with_flip=False)
            if not noise:
                noise = metrics.reference_noise(ref, {k: reference.variance.get(rk) for k, rk in
                                                      zip(test, _reference_ids(test, reference.images))
                                                      if rk in reference.variance})
            points.append({"budget": budget, "seconds": r.stats["wall_time"], "samples": r.stats["samples"],
                           "relmse": errs.overall.relmse,
                           "relmse_corrected": errs.overall.relmse - noise["overall"] if noise else None,
                           "views": {k: v.relmse for k, v in errs.views.items()}})
            final = r
        mdir = out / method
        write_outputs(final, mdir, stem, settings={"scene": str(cfg.scene), "defines": cfg.defines, "method": method})
        run = load_run(mdir / f"{stem}.json")
        run.name = method
        test, ref = match_views(run.images, reference.images)
        errs = metrics.errors(test, ref)
        corrected = {k: errs.views[k].relmse - noise[k] for k in errs.views} if noise else {}
        if noise:
            corrected["overall"] = errs.overall.relmse - noise["overall"]
        display = _display_error(test, ref, reference, result)
        result.methods[method] = MethodRun(method=method, run=run, errors=errs, curve=points, directory=str(mdir),
                                           command=_render_command(cfg, mdir, method, time=cfg.time),
                                           corrected=corrected, display=display)
    result.reference_noise = noise
    result.warnings = reference_warnings(result)
    return result


def _display_error(test: dict, ref: dict, reference: Run, result: BenchResult) -> dict:
    """The relMSE a display shows (metrics.display_relmse: each view blended with its neighbours
    along its row), raw and with the reference's blended noise subtracted; sets
    result.display_noise. Empty for one view, which a display shows as it is."""
    if len(ref) < 2:
        return {}
    ids = _reference_ids(test, reference.images)
    variance = {k: reference.variance[rk] for k, rk in zip(test, ids) if rk in reference.variance}
    raw, noise = metrics.display_relmse(test, ref, variance if len(variance) == len(ref) else None)
    result.display_noise = noise
    return {"relmse": raw, "relmse_corrected": raw - noise if noise is not None else None}


def _reference_ids(test: dict, ref: dict) -> list:
    """The reference's view id that each of `test`'s views is compared with (match_views' rule)."""
    if len(test) == 1 and len(ref) == 1:
        return [next(iter(ref))]
    return list(test)


#: The reference's noise may be at most this share of a method's own error for a fair judgement.
NOISE_SHARE_LIMIT = 0.1


def reference_warnings(result: BenchResult) -> list:
    """Warnings about the reference: noise unknown, or too large to judge the methods by."""
    if not result.reference_noise:
        return ["the reference has no variance channels (render it with --aovs): its own noise cannot be "
                "measured or subtracted, and every relMSE here includes it"]
    out = []
    n = result.reference_noise["overall"]
    for m, r in result.methods.items():
        own = r.corrected.get("overall", float("nan"))
        if not own > 0 or n > NOISE_SHARE_LIMIT * own:
            share = f"{n / own:.0%} of" if own > 0 else "more than"
            out.append(f"the reference's own noise (relMSE {n:.3g}) is {share} {m}'s error: too noisy to judge "
                       f"the methods; render it with more samples (--reference-spp)")
    return out


def shell(cmd: list) -> str:
    """A command list as one shell-quoted line."""
    return shlex.join(str(c) for c in cmd)
