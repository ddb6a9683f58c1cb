"""Python API: load scenes, render them (cancellable, GIL released), get NumPy images."""
from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import threading
from time import monotonic as _monotonic
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np

from . import _core
from . import state as state_file


def _text(s: str, what: str) -> str:
    """`s` if it is text the native code can take (command-line bytes that are not UTF-8 arrive
    as lone surrogates); a ValueError naming `what` and showing the bytes escaped otherwise, or
    naming the type of what is not a str."""
    if not isinstance(s, str):
        raise ValueError(f"{what} must be text (str), got {type(s).__name__}")
    try:
        s.encode("utf-8")
    except UnicodeEncodeError:
        raise ValueError(f"{what} is not UTF-8 text: {shown(s)}") from None
    return s


def _scene(scene, what: str) -> _core.Scene:
    """`scene` if it is a loaded scene; a ValueError saying how to make one otherwise."""
    if not isinstance(scene, _core.Scene):
        raise ValueError(f"{what} takes a scene from mvpt.load_file or mvpt.load_string, got {type(scene).__name__}")
    return scene


def _path(p, what: str) -> str:
    """A file path given as str or os.PathLike, as text; a ValueError naming `what` otherwise."""
    if not isinstance(p, (str, os.PathLike)):
        raise ValueError(f"{what} must be a path (str or os.PathLike), got {type(p).__name__}")
    return _text(os.fspath(p), what)


#: The most worker threads a render may ask for (0: one per core).
MAX_THREADS = 1024


def _threads(threads) -> int:
    if not 0 <= int(threads) <= MAX_THREADS:
        raise ValueError(f"threads must lie in [0, {MAX_THREADS}] (0: one per core), got {threads}")
    return int(threads)


def _rig(rig) -> str:
    """A rig specification for the native loader: "" for none; an empty or blank one is an error
    (it would silently render the scene's own sensors)."""
    if rig is None:
        return ""
    rig = _text(rig, "the rig")
    if not rig.strip():
        raise ValueError("the rig is empty: give one such as 'stereo', 'linear:n=9' or 'grid:5x5', or none")
    return rig


def shown(s: str) -> str:
    """`s` for a message: bytes that are not UTF-8 (lone surrogates from the command line) as \\xNN."""
    return s.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


@contextlib.contextmanager
def _interrupts_ignored():
    """Ctrl-C does nothing inside (in the main thread; elsewhere Python delivers none)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, lambda signum, frame: None)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _defines(kwargs: dict) -> dict:
    out = {}
    for k, v in kwargs.items():
        if isinstance(v, bool):
            v = "true" if v else "false"
        out[_text(str(k), "a define's name")] = _text(str(v), f"the define {k!r}")
    return out


def load_file(path: str | os.PathLike, rig: Optional[str] = None, **defines) -> _core.Scene:
    """Load a Mitsuba 3 XML scene; keyword arguments override its <default> values.

    `rig` (e.g. "stereo:ipd=0.064", "grid:5x5,spacing=0.05,focus_distance=3",
    "path:keys.json,frames=100,fps=24,shutter=0.5"; the CLI's --rig) replaces the scene's
    sensors by the views generated from its first sensor (README, "Camera rigs and shots").
    Raises mvpt.SceneError (a ValueError) naming file:line:col on bad input; the error
    also has the attributes file, line, column and message. The load runs natively with the
    GIL released: Ctrl-C (KeyboardInterrupt) stops it within a fraction of a second."""
    return load_scene(path, rig, defines)


def load_string(xml: str, base_dir: str | os.PathLike = ".", rig: Optional[str] = None, **defines) -> _core.Scene:
    """Load a scene from an XML string; relative file names resolve in `base_dir`."""
    job = _core.LoadJob(_text(xml, "the scene"), False, _text(os.fspath(base_dir), "base_dir"), _defines(defines),
                        _rig(rig))
    return _loaded(job, None)


def load_scene(path: str | os.PathLike, rig: Optional[str] = None, defines: Optional[dict] = None,
               every_view_rendered: bool = False, stop: Optional[Callable[[], bool]] = None) -> _core.Scene:
    """load_file with its options as arguments (no define can be named like them).

    every_view_rendered: the caller renders all the views at once (the command line without
    --views): a rig whose views' images cannot all be in memory is refused (mvpt.SceneError)
    before its views are made, where the render's own check would refuse it after a load of
    seconds and GiB. stop: polled while the scene loads; once it returns True the load stops
    and KeyboardInterrupt is raised."""
    job = _core.LoadJob(_text(os.fspath(path), "the scene path"), True, ".", _defines(defines or {}), _rig(rig),
                        bool(every_view_rendered))
    return _loaded(job, stop)


def _loaded(job, stop) -> _core.Scene:
    """The scene of a load job, waited for a twentieth of a second at a time with the GIL
    released, so that signal handlers run: KeyboardInterrupt (from one, or from `stop`)
    cancels the load and is raised once the load has stopped."""
    job.start()
    try:
        while not job.wait(0.05):
            if stop is not None and stop():
                raise KeyboardInterrupt
    except BaseException:
        _cancel(job, 0.05)
        raise
    return job.scene()


@dataclass
class RenderResult:
    """Images and statistics of one render, keyed by view id (in scene order)."""

    images: dict = field(default_factory=dict)
    variance: dict = field(default_factory=dict)
    sample_count: dict = field(default_factory=dict)
    #: multi-view path tracing only: contributions received per pixel (own native samples included)
    contributions: dict = field(default_factory=dict)
    #: multi-view path tracing only: mean per pass of the sum of the contributions' weights
    #: W = 1/D (1 in expectation with the balance estimator: a check of the weights)
    weight_sum: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)

    @property
    def view_ids(self) -> list:
        return list(self.images.keys())


def resolve_views(scene: _core.Scene, views: Optional[Sequence]) -> list:
    """Scene indices of `views` (ids, or indices as ints or digit strings), without repeats.

    A string is an id when a view has that id, otherwise a digit string is an index."""
    ids = [v["id"] for v in scene.views]
    if isinstance(views, (str, int, np.integer)):
        views = [views]
    index = []
    for v in views or []:
        if isinstance(v, (bool, np.bool_)):
            raise ValueError(f"unknown view {v!r}")
        if isinstance(v, (int, np.integer)):
            i = int(v)
        elif str(v) in ids:
            i = ids.index(str(v))
        elif str(v).strip().isdigit():
            i = int(str(v))
        else:
            raise ValueError(f"unknown view '{shown(str(v))}'; the scene's views are {', '.join(ids)}")
        if not 0 <= i < len(ids):
            raise ValueError(f"view index {i} is out of range: the scene has {len(ids)} views (0..{len(ids) - 1})")
        if i not in index:
            index.append(i)
    return index


def render(scene: _core.Scene, spp: int = 0, time: float = 0.0, seed: Optional[int] = None,
           threads: int = 0, views: Optional[Sequence] = None,
           progress: Optional[Callable[[dict], None]] = None, poll: float = 0.1,
           method: str = "scene", state: Optional[str | os.PathLike] = None, checkpoint: float = 0.0,
           resume: Optional[str | os.PathLike] = None, state_at_end: bool = True,
           state_extra: Optional[dict] = None, passes: Optional[Sequence[int]] = None,
           splits: Optional[int | str] = None, backend: Optional[str] = None) -> RenderResult:
    """Render all views (or `views`: ids or indices) of `scene`.

    method: "pt" (independent path tracing of every view), "mvpt" (multi-view path tracing,
    sharing paths between the views; its settings come from an `mvpath` integrator in the
    scene, or its defaults), "auto" (mvpt where its pilot predicts a gain over pt at equal time,
    else pt: choose_method; stats["auto"] says which and why, stats["method"] is what ran; a
    time budget includes the pilot) or "scene" (whatever the scene's integrator is). With "mvpt",
    sample_count holds native samples and `contributions` what each pixel received; spp is
    the mean number of native samples per pixel.

    spp: samples per pixel (0: each sensor's sample_count); time: wall-clock budget in
    seconds (0: none; passes stop when the next would end past it, and it is not overrun by
    more than about half a second, except by path tracing's first pass; multi-view path
    tracing cuts its first pass, as on Ctrl-C below, thins the passes after it so that at
    least three fit, and when less than a pass is left thins its last pass to what fits:
    stats["thinned_passes"] counts the thinned passes, stats["thinned_shares"] sums the shares
    of native samples they took, stats["thinned_pass_share"] is the last one's, if thinned to fit). The render runs natively with the GIL
    released; `progress(dict)` is called every `poll` seconds and once at the end, with
    the passes finished, fraction done, elapsed seconds and samples so far. Ctrl-C (or
    KeyboardInterrupt raised by `progress`) cancels within about half a second (path tracing
    at the end of its current quarter-second chunk of short passes, or between the tiles of a
    pass longer than half a second, keeping the finished tiles: their sample counts say so;
    multi-view path tracing between tiles, dropping the unfinished pass, except the first,
    which it cuts at the end of a chunk and keeps, its finished regions scaled to an unbiased
    estimate: stats["cut_pass_share"] is their share) and the images are returned with
    stats["cancelled"] set (stats["passes"] == 0: none finished); any other exception from
    `progress` cancels the render and is re-raised.

    state: a file for the render's state (docs/checkpoints.md), written at a pass boundary
    every `checkpoint` seconds (0: not periodically), when the render is interrupted and, with
    `state_at_end`, when it ends; `state_extra` (JSON-able) is stored in its header. resume: a
    state file of the same scene and settings to continue from: the images are bit-identical
    to those of a render that was never stopped, unless it kept a cut first pass (with
    `time`, the budget is the total of all runs). A state of another scene, setting or mvpt version raises mvpt.StateError naming
    what differs, as does a file that is truncated or corrupt.

    passes: (first, count) renders one range of a render split over processes or machines
    (docs/distributed.md): `count` passes of every view, taking the samples of passes
    first .. first + count - 1 (spp is ignored); the states of ranges that do not overlap
    (or of other seeds) combine with `merge`.

    splits: with "mvpt", the splits of the shared vertex instead of the scene's `mvpath`
    setting (whose default is "auto"): 1 to 64, or "auto" (chosen per render; stats["splits"]
    says which).

    backend: None (this library's renderer) or "mitsuba[:VARIANT]": Dr.Jit on Mitsuba 3
    (docs/mitsuba-backend.md), cuda_ad_rgb where a GPU is present, else llvm_ad_rgb; it
    renders "pt" and "mvpt" ("scene" and "auto": mvpt for several views, else pt) with spp,
    time, seed, views and progress, and refuses states, ranges and splits."""
    _scene(scene, "render")
    if backend is not None:
        return _render_on_mitsuba(scene, backend, spp=spp, time=time, seed=seed, views=views, progress=progress,
                                  method=method, refused=dict(state=state, resume=resume, passes=passes, splits=splits,
                                                              checkpoint=checkpoint or None))
    if state is not None:  # checked before the render, which would otherwise be lost at its end
        state = _path(state, "state")
        folder = os.path.dirname(os.path.abspath(state))
        if not os.path.isdir(folder):
            raise ValueError(f"state: the folder {shown(folder)} of {shown(state)} does not exist")
    splits_option = _splits_option(splits)
    if not 0 <= int(spp) < 2**31:
        raise ValueError(f"spp must lie in [0, 2^31), got {spp}")
    if not 0.0 <= float(time) < math.inf:  # (a render of infinite time would never end)
        raise ValueError(f"time must be a finite number of seconds >= 0, got {time}")
    _threads(threads)
    if not float(poll) > 0.0:
        raise ValueError(f"poll must be > 0 seconds, got {poll}")
    if seed is not None and not 0 <= int(seed) < 2**32:
        raise ValueError(f"seed must lie in [0, 2^32), got {seed}")
    if method not in ("scene", "pt", "mvpt", "auto"):
        raise ValueError(f"method must be 'pt', 'mvpt', 'auto' or 'scene', got {method!r}")
    for path, what in ((state, "the state path"), (resume, "the resume path")):
        if path is not None:
            _text(os.fspath(path), what)
    if not (float(checkpoint) >= 0.0):
        raise ValueError(f"checkpoint must be >= 0 seconds, got {checkpoint}")
    if passes is not None:
        first, count = (int(x) for x in passes)
        if not (0 <= first and 1 <= count and first + count < 2**31):
            raise ValueError(f"passes must be (first >= 0, count >= 1) within 2^31, got {tuple(passes)}")
        passes = [first, count]
    index = resolve_views(scene, views)
    auto = None
    run_method, run_time = method, float(time)
    if method == "auto":  # (a function of the settings: a resumed render and a range choose the same)
        auto = choose_method(scene, index, seed, threads, splits_option, poll)
        run_method = auto["method"]
        if run_time > 0.0:  # the pilot's seconds are the budget's too
            run_time = max(run_time - auto["seconds"], MinRunSeconds)
    header = None
    if state is not None or resume is not None:  # (a state names the method that ran: it merges)
        ids = [v["id"] for v in scene.views]
        settings = dict(method=run_method, spp=0 if passes else int(spp), time=float(time),
                        seed=None if seed is None else int(seed), views=[ids[i] for i in index] or ids, passes=passes,
                        splits=splits)
        header = state_file.make_header(scene, settings, state_extra)
    if resume is not None:
        state_file.check_resumable(resume, header)
    job = _core.RenderJob(scene, spp=int(spp), time=run_time, seed=None if seed is None else int(seed),
                          threads=int(threads), views=index, method=run_method,
                          state_path=os.fspath(state) if state is not None else "",
                          state_header=json.dumps(header) if state is not None else "",
                          checkpoint_interval=float(checkpoint), state_at_end=bool(state_at_end),
                          resume_path=os.fspath(resume) if resume is not None else "",
                          first_pass=passes[0] if passes else 0, pass_count=passes[1] if passes else 0,
                          splits=splits_option)
    job.start()
    interrupted = None
    try:
        while not job.wait(poll):
            if progress is not None:
                progress(job.progress())
        if progress is not None:
            progress(job.progress())  # the final state
    except BaseException as e:  # KeyboardInterrupt included: stop cleanly, keep the passes done
        # A second Ctrl-C must not abandon the passes already done: the render stops within a
        # fraction of a second anyway.
        interrupted = e
        _cancel(job, poll)
    result = _result(scene, job, index, dict(spp=int(spp), time=float(time), seed=seed, threads=int(threads),
                                             method=method, passes=passes, splits=splits))
    if auto is not None:
        result.stats["auto"] = auto
    if interrupted is not None:
        result.stats["cancelled"] = True
        if not isinstance(interrupted, KeyboardInterrupt):
            raise interrupted
    return result


def _render_on_mitsuba(scene, backend: str, method: str, refused: dict, **kwargs) -> RenderResult:
    """render(..., backend="mitsuba[:VARIANT]") (docs/mitsuba-backend.md)."""
    name, _, variant = str(backend).partition(":")
    if name != "mitsuba":
        raise ValueError(f"backend must be 'mitsuba' or 'mitsuba:VARIANT', got {backend!r}")
    for what, value in refused.items():
        if value is not None:
            raise ValueError(f"the mitsuba backend has no {what} (docs/mitsuba-backend.md)")
    if method not in ("scene", "pt", "mvpt", "auto"):
        raise ValueError(f"method must be 'pt', 'mvpt', 'auto' or 'scene', got {method!r}")
    if method in ("scene", "auto"):
        several = len(resolve_views(scene, kwargs["views"]) or scene.views) > 1
        method = "mvpt" if several and (method == "auto" or scene.integrator == "mvpath") else "pt"
    from . import mitsuba_backend
    return mitsuba_backend.render(scene, method=method, variant=variant or None, **kwargs)


# method="auto" (docs/multiview-path-tracing.md, "Choosing the method"): multi-view path tracing
# where its pilot predicts at least this gain over path tracing at equal time, else path tracing.
AutoGain = 1.0
# A time budget that the pilot spent whole still renders (at least one pass runs).
MinRunSeconds = 1e-3


def choose_method(scene: _core.Scene, index: list, seed, threads: int, splits_option: int = -1,
                  poll: float = 0.1) -> dict:
    """What method="auto" renders `scene`'s views `index` with: multi-view path tracing's pilot
    alone (its native samples and two path-traced samples at a fixed set of pixels, from
    seeds of its own) predicts pt / mvpt at equal time; mvpt where that is at least AutoGain
    (or where the pilot cannot tell), else pt. A function of the scene, the views, the seed
    and the splits: every range and resume of a render chooses the same. Returns {"method",
    "predicted_gain" (None without a prediction), "reason", "seconds" (the pilot's)}."""
    t0 = _monotonic()
    views = len(index) or len(scene.views)
    if views < 2:
        return {"method": "pt", "predicted_gain": None, "seconds": 0.0,
                "reason": "one view: multi-view path tracing has nothing to share"}
    try:
        raw = _pilot_stats(scene, index, seed, threads, splits_option, poll)
    except RuntimeError as e:  # multi-view path tracing's films refused: path tracing's may fit
        if "need about" not in str(e):
            raise
        return {"method": "pt", "predicted_gain": None, "seconds": _monotonic() - t0,
                "reason": f"multi-view path tracing cannot run here ({e})"}
    seconds = _monotonic() - t0
    if raw["method"] != "mvpt":  # nothing can be shared in time (the renderer's own rule)
        return {"method": "pt", "predicted_gain": None, "seconds": seconds,
                "reason": raw["notes"][-1] if raw["notes"] else "nothing to share"}
    gain = float(raw["predicted_gain"])
    if not gain > 0.0:
        return {"method": "mvpt", "predicted_gain": None, "seconds": seconds,
                "reason": "the pilot saw too few pixels to predict the gain: multi-view path tracing"}
    if gain >= AutoGain:
        return {"method": "mvpt", "predicted_gain": gain, "seconds": seconds,
                "reason": f"the pilot predicts {gain:.2f}x path tracing's efficiency"}
    return {"method": "pt", "predicted_gain": gain, "seconds": seconds,
            "reason": f"the pilot predicts multi-view path tracing at {gain:.2f}x path tracing's efficiency: "
                      "sharing does not pay here"}


def _pilot_stats(scene, index: list, seed, threads: int, splits_option: int, poll: float) -> dict:
    """The raw statistics of multi-view path tracing's pilot alone (RenderOptions::pilot_only)."""
    job = _core.RenderJob(scene, spp=1, seed=None if seed is None else int(seed), threads=int(threads), views=index,
                          method="mvpt", splits=splits_option, pilot_only=True)
    job.start()
    try:
        while not job.wait(poll):
            pass
    except BaseException:
        _cancel(job, poll)
        raise
    return job.stats()


def _cancel(job, poll: float) -> None:
    """Cancel a running job and wait for it to stop; a second Ctrl-C (people press it twice)
    does not abandon it."""
    with _interrupts_ignored():
        job.cancel()
        while not job.wait(poll):
            pass


def _splits_option(splits) -> int:
    """render(splits=...) for the renderer: -1 (the scene's), 0 (auto) or 1 to 64."""
    if splits is None:
        return -1
    if splits == "auto":
        return 0
    if isinstance(splits, bool) or not isinstance(splits, int) or not 1 <= splits <= 64:
        raise ValueError(f"splits must be 'auto' or an integer in [1, 64], got {splits!r}")
    return splits


def merge(scene: _core.Scene, states: Sequence[str | os.PathLike], threads: int = 0,
          state: Optional[str | os.PathLike] = None, images: bool = True,
          identity: Optional[dict] = None, unfinished: bool = False) -> Optional[RenderResult]:
    """The images of the state files `states`, ranges (or seeds) of one render of `scene`
    (render(passes=...)), as if one process had rendered them all: their accumulators are
    added in the order of their ranges (whatever order they are given in) and developed with the estimator's own arithmetic. States that
    differ in anything but their ranges and seeds, or that share samples, raise
    mvpt.StateError naming what differs. `state`: where to write the merged state (which can
    be merged further, not resumed). With images=False only that state is written (merging
    it with the next state then gives the same bits as merging all at once); `identity` is
    state.scene_identity(scene) if already known (it reads every file of the scene). A range
    stopped before its end raises mvpt.StateError (resume it first) unless `unfinished`, as
    for ranges that a time budget stops on purpose (mvpt.distributed)."""
    _scene(scene, "merge")
    _threads(threads)
    if isinstance(states, (str, bytes, os.PathLike)):  # one state, not the characters of its path
        states = [states]
    paths = [_path(p, "a state to merge") for p in states]
    if not paths:
        raise ValueError("merge needs at least one state file")
    # In the order of their parts (seed, first pass), whatever order they are given in, so
    # that the sums are added in one order.
    headers = state_file.check_mergeable(paths)
    order = sorted(range(len(paths)), key=lambda i: state_file.part_key(headers[i]["parts"][0]))
    paths, headers = [paths[i] for i in order], [headers[i] for i in order]
    first = headers[0]
    ids = [v["id"] for v in scene.views]
    settings = first["settings"]
    current = state_file.make_header(scene, dict(settings, passes=None), identity=identity)
    diff = [d for d in state_file.differences(dict(first, settings=current["settings"]), current)]
    if diff:
        raise state_file.StateError(f"cannot merge '{paths[0]}' for this scene: " + "; ".join(diff))
    index = resolve_views(scene, settings["views"])
    if index == list(range(len(ids))):
        index = []
    merged = state_file.merged_header(headers)
    # The merged state is written beside its place and moved there once the merge is whole.
    unchecked = None if state is None else os.fspath(state) + ".unchecked"
    job = _core.RenderJob(scene, spp=int(settings["spp"] or 0), time=0.0, threads=int(threads), views=index,
                          method=settings["method"], state_path=unchecked or "", state_header=json.dumps(merged))
    try:
        job.merge(paths, images)
        if not unfinished:
            _check_ranges_finished(merged["parts"], job.stats()["passes"])
        if unchecked is not None:
            os.replace(unchecked, state)
    finally:
        if unchecked is not None and os.path.exists(unchecked):
            os.unlink(unchecked)
    if not images:
        return None
    return _result(scene, job, index, dict(settings, passes=None, parts=merged["parts"], threads=int(threads),
                                           merged=len(paths)))


def _check_ranges_finished(parts: list, passes: int) -> None:
    """A StateError unless states whose parts name their pass counts hold all of those passes
    (a range interrupted before its end is resumed, not merged)."""
    counts = [p[2] for p in parts]
    if None not in counts and passes < sum(counts):
        raise state_file.StateError(
            f"the states hold {passes} of the {sum(counts)} passes their ranges name: a range was interrupted; "
            f"finish it first (mvpt render --resume, or mvpt.render(..., resume=...))")


def _result(scene, job, index: list, settings: dict) -> RenderResult:
    """The images and statistics of a finished job."""
    result = RenderResult()
    results = job.results()
    for r in results:
        result.images[r["id"]] = r["image"]
        result.variance[r["id"]] = r["variance"]
        result.sample_count[r["id"]] = r["sample_count"]
        if "contributions" in r:
            result.contributions[r["id"]] = r["contributions"]
            result.weight_sum[r["id"]] = r["weight_sum"]
    result.stats = _stats(scene, job.stats(), results, index, settings)
    return result


def _warnings(scene, raw: dict, results: list) -> list:
    """What the scene lost while it was read, the renderer's warnings, and one when every view
    came out black although the scene has an emitter (the cameras see nothing lit)."""
    out = list(raw["warnings"])
    if not out and raw["passes"] > 0 and results and not any(r["image"].any() for r in results):
        out.append("every view is black: no light reaches the cameras (do they look at the scene?)")
    if raw["state_error"]:
        out.append(f"{raw['state_error']}: the render went on without its state")
    return list(scene.warnings) + out


def _stats(scene, raw: dict, results: list, index: list, settings: dict) -> dict:
    """The statistics of one render, as returned in RenderResult.stats and written to JSON."""
    ids = [v["id"] for v in scene.views]
    seconds = raw["seconds"]
    rate = (lambda n: n / seconds if seconds > 0 else 0.0)
    total_rays = raw["rays"] + raw["shadow_rays"]
    views = {}
    for i, r in zip(index or range(len(ids)), results):
        pixels = max(1, r["width"] * r["height"])
        views[r["id"]] = {
            "id": r["id"], "index": i, "width": r["width"], "height": r["height"],
            "spp": float(r["samples"]) / pixels, "samples": int(r["samples"]),
            "mean": [float(x) for x in r["mean"]],
            "nonfinite_samples": int(r["nonfinite"]),
        }
        if "multiview" in r:
            views[r["id"]]["multiview"] = dict(r["multiview"], contributions_per_pixel=r["contributions_total"] / pixels,
                native_samples_per_second=rate(r["multiview"]["native_samples"]))
    settings = dict(settings, views=list(views), integrator=scene.integrator)
    first = raw.get("first_nonfinite")
    if first is not None:
        first = dict(first, view_id=ids[first["view"]])
    return {
        "settings": settings,
        "wall_time": seconds, "seconds": seconds, "max_pass_seconds": raw["max_pass_seconds"],
        "max_chunk_seconds": raw["max_chunk_seconds"],
        "between_passes_seconds": raw["between_passes_seconds"],
        "estimated_bytes": raw["estimated_bytes"],
        "passes": raw["passes"], "cut_pass_share": raw["cut_pass_share"],
        "thinned_pass_share": raw["thinned_pass_share"], "thinned_passes": raw["thinned_passes"],
        "thinned_shares": raw["thinned_shares"], "resumed_from_pass": raw["first_pass"],
        "cancelled": bool(raw["cancelled"]), "threads": raw["threads"],
        "samples": raw["samples"], "samples_per_second": rate(raw["samples"]),
        "rays": {"camera": raw["camera_rays"], "intersect": raw["rays"], "shadow": raw["shadow_rays"],
                 "total": total_rays},
        "rays_per_second": rate(total_rays),
        "nonfinite_samples": raw["nonfinite_samples"],
        "first_nonfinite": first,
        "integrator": scene.integrator,
        "method": raw["method"],
        "notes": list(scene.notes) + list(raw["notes"]),
        "warnings": _warnings(scene, raw, results),
        "state_error": raw["state_error"] or None,
        "views": views,
    } | ({"estimator": raw["estimator"], "splits": raw["splits"], "delta_splits": raw["delta_splits"],
          "predicted_gain": raw["predicted_gain"], "multiview": dict(raw["multiview"])}
         if raw["method"] == "mvpt" else {}) \
      | ({"split_pilot": dict(raw["split_pilot"])} if "split_pilot" in raw else {})
