"""The `mvpt` command line: `mvpt render scene.xml -D spp=64 -o out/`, `mvpt demo`.

Exit codes: 0 done, 1 bad scene or unwritable output, 2 bad command line, 130 interrupted
by Ctrl-C (143 by SIGTERM, 129 by SIGHUP); an interrupted render stops within about half a
second and writes the samples finished so far, with "cancelled" in the JSON, and its state
(<stem>.mvpt-state), from which `mvpt render --resume OUT` continues it (nothing when no pass
had finished). A signal at any other point, from the program's start to its end (the load,
the writing of the outputs, the exit), gives the same code where the command succeeded
(docs/outputs-and-reports.md, "Signals")."""
from __future__ import annotations

import argparse
import math
import sys
import time
from importlib import resources
from pathlib import Path

from . import __version__, api, cli_common, stop_signals
from . import state as state_file
from ._core import SceneError
from . import displays, output_lock, reports_cli, state_cli
from .cli_common import EXIT_ERROR, EXIT_OK, EXIT_USAGE, write_all
from .cli_common import count as _count, define as _define, error as _error, seconds as _seconds, seed as _seed
from .cli_common import splits as _splits
from .summary import print_summary

class _Parser(argparse.ArgumentParser):
    """argparse that reports bad input as one `mvpt: error: ...` line (exit code 2)."""

    def error(self, message):
        _error(message)
        raise SystemExit(EXIT_USAGE)


def _hms(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "--:--"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60:02d}:{s % 60:02d}"


class ProgressBar:
    """One-line progress bar with elapsed time and ETA, redrawn in place on a terminal.

    Silent when the stream is not a TTY (unless `enabled` forces it)."""

    def __init__(self, stream=None, enabled=None, width: int = 30):
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.width = width
        self.start = time.monotonic()
        self.last = None

    def __call__(self, p: dict) -> None:
        self.last = p
        if self.enabled:
            self._draw(p)

    def _draw(self, p: dict) -> None:
        frac = min(max(float(p.get("fraction", 0.0)), 0.0), 1.0)
        elapsed = time.monotonic() - self.start
        eta = elapsed * (1 - frac) / frac if frac > 0 else float("nan")
        filled = int(frac * self.width)
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(f"\r[{bar}] {100 * frac:5.1f}%  pass {p.get('pass', 0)}  "
                          f"elapsed {_hms(elapsed)}  ETA {_hms(eta)} ")
        self.stream.flush()

    def finish(self, done: bool = True) -> None:
        """Draw the final state and end the line."""
        if not self.enabled:
            return
        if self.last is not None or done:
            p = dict(self.last or {})
            if done:
                p["fraction"] = 1.0
            self._draw(p)
        self.stream.write("\n")
        self.stream.flush()


def _failed(bar: "ProgressBar", e: Exception) -> int:
    """A render that raised: the progress line ended, one error line, the error exit code."""
    bar.finish(done=False)
    _error(cli_common.failure_text(e))
    return EXIT_ERROR


def _render(scene_path: Path, args, stem: str) -> int:
    # A signal stops the render where it polls for one: the load, the passes (stop_signals).
    stop_signals.interruptible = False
    try:
        api._text(str(args.output), "the output directory")
    except ValueError as e:
        _error(str(e))
        return EXIT_USAGE
    defines = dict(args.define or [])
    problem = displays.check_display_options(args)
    if problem:
        _error(problem)
        return EXIT_USAGE
    blend = scene_path.suffix.lower() == ".blend"
    if blend and getattr(args, "ray", None) is not None:
        _error("--ray renders XML scenes: convert the .blend first (mvpt render scene.blend --xml-dir DIR), "
               "then render DIR's XML file")
        return EXIT_USAGE
    if not blend and getattr(args, "frames", None) is not None:
        _error("--frames converts a range of a .blend scene's frames; an XML scene's shot is its views "
               "(or a `path` rig: --rig path:keys.json,frames=N)")
        return EXIT_USAGE
    try:
        scene = _load_blend(scene_path, args, defines) if blend else \
            api.load_scene(scene_path, args.rig, defines, every_view_rendered=not args.views,
                           stop=stop_signals.stop_requested)
    except (SceneError, ValueError, RuntimeError, MemoryError) as e:  # ValueError: arguments that are not text
        _error(cli_common.failure_text(e))
        return EXIT_ERROR
    try:
        if args.views is not None and not args.views.strip():
            raise ValueError("the list is empty: give view ids or indices such as 'left,right' or '0,2', or drop --views")
        views = api.resolve_views(scene, args.views.split(",")) if args.views else None
    except ValueError as e:
        _error(f"--views: {e}")
        return EXIT_USAGE
    if args.passes and args.spp:
        _error("--passes renders COUNT passes of every view; drop --spp")
        return EXIT_USAGE
    chosen = [scene.views[i] for i in views] if views else scene.views
    if args.method is None:  # several views of a path-traced scene: what pays (docs/multiview-path-tracing.md)
        args.method = "auto" if len(chosen) > 1 and scene.integrator in ("path", "volpath") else "scene"
    problem = displays.check_displays_for(args, [(v["width"], v["height"]) for v in chosen])
    if problem:
        _error(problem)
        return EXIT_USAGE
    if getattr(args, "ray", None) is not None and (args.passes or args.checkpoint or getattr(args, "resume", None)):
        _error("--ray splits the render into ranges itself; drop --passes, --checkpoint and --resume")
        return EXIT_USAGE
    try:
        args.output.mkdir(parents=True, exist_ok=True)
        lock = output_lock.FolderLock(args.output)
    except output_lock.FolderBusy as e:
        _error(str(e))
        return EXIT_ERROR
    except OSError as e:
        why = "it is not a directory" if args.output.exists() and not args.output.is_dir() else e.strerror or e
        _error(f"cannot use the output directory {args.output}: {why}")
        return EXIT_ERROR
    if not args.quiet:
        n = len(views) if views else len(scene.views)
        budget = [f"passes {args.passes[0]}:{args.passes[1]}" if args.passes else
                  f"{args.spp} spp" if args.spp else "each sensor's spp"] + ([f"{args.time:g} s"] if args.time else [])
        print(f"rendering {n} view{'s' if n != 1 else ''} of {scene_path.name} ({', '.join(budget)}; Ctrl-C stops "
              f"and writes the passes finished so far)", flush=True)
    bar = ProgressBar(enabled=False if args.quiet else None)
    with lock:
        if getattr(args, "ray", None) is not None:
            if args.backend:
                _error("--backend renders on this machine: it has no --ray")
                return EXIT_ERROR
            return _render_on_ray(scene_path, args, stem, views, bar)
        return _render_here(scene, scene_path, args, stem, views, bar, defines)


def _frames(text: str) -> tuple:
    """--frames A:B, Blender's frame numbers, an inclusive range."""
    first, sep, last = text.partition(":")
    try:
        a, b = int(first), int(last)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected A:B, two frame numbers (an inclusive range), got '{text}'") from None
    if not sep or b < a:
        raise argparse.ArgumentTypeError(f"expected A:B with A <= B (an inclusive range of frames), got '{text}'")
    return a, b


def _load_blend(scene_path: Path, args, defines: dict):
    """A .blend scene, converted (into --xml-dir, kept, or a temporary folder); each conversion
    warning printed as one line."""
    import atexit
    import shutil
    import tempfile
    import warnings
    from .blender.load import load_blend
    folder = getattr(args, "xml_dir", None)
    if folder is None:
        # The render's state names the scene's files by their contents, so the converted scene
        # stays until the process ends.
        folder = tempfile.mkdtemp(prefix="mvpt-blend-")
        atexit.register(shutil.rmtree, folder, True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_blend(scene_path, folder=folder, rig=args.rig, frames=getattr(args, "frames", None), **defines)
    for w in caught:
        print(f"mvpt: warning: {w.message}", file=sys.stderr)
    if getattr(args, "xml_dir", None) is not None and not args.quiet:
        print(f"converted {scene_path.name} into {args.xml_dir}/{scene_path.stem}.xml", flush=True)
    return scene


def _render_here(scene, scene_path: Path, args, stem: str, views, bar: "ProgressBar", defines: dict) -> int:
    """The render of `_render` in this process, its output folder held."""
    state = state_file.state_file(args.output, stem)
    keep_state = args.checkpoint > 0 or args.passes is not None  # a range's state is what merges
    resume = getattr(args, "resume_state", None)
    # A state already there is another render's (--resume continues it): never overwritten or removed.
    foreign = not resume and state.exists()
    if foreign and keep_state:
        _error(f"{state} holds the state of another render; continue it with `mvpt render --resume "
               f"{args.output}`, remove it, or choose another -o")
        return EXIT_ERROR
    if stop_signals.stop_requested():
        raise KeyboardInterrupt  # (before anything was rendered)

    def progress(p: dict) -> None:
        if stop_signals.stop_requested():
            raise KeyboardInterrupt  # api.render cancels the render and returns what it finished
        bar(p)

    try:
        if args.backend:  # (no state: a render on Mitsuba is not resumed)
            result = api.render(scene, spp=args.spp, time=args.time, seed=args.seed, views=views, progress=progress,
                                method=args.method, backend=args.backend, passes=args.passes, splits=args.splits,
                                resume=resume, checkpoint=args.checkpoint)
            foreign = True
        else:
            result = api.render(scene, spp=args.spp, time=args.time, seed=args.seed, threads=args.threads,
                                views=views, progress=progress, method=args.method, state=None if foreign else state,
                                checkpoint=args.checkpoint, resume=resume, state_at_end=keep_state,
                                state_extra={"command": state_cli.command_record(scene_path, args, stem)},
                                passes=args.passes, splits=args.splits)
    except (RuntimeError, MemoryError, ValueError, OSError) as e:
        return _failed(bar, e)
    cancelled = bool(result.stats.get("cancelled"))
    bar.finish(done=not cancelled)
    _say_auto(result, args)
    state_error = result.stats.get("state_error")
    for warning in result.stats.get("warnings", []):
        if not (state_error and warning.startswith(state_error)):  # said once, as the error below
            print(f"mvpt: warning: {warning}", file=sys.stderr)
    if cancelled and result.stats["passes"] == 0:
        if not resume and not foreign:
            state.unlink(missing_ok=True)
        print("mvpt: interrupted before the first pass finished; nothing written", file=sys.stderr)
        return stop_signals.exit_code()
    if not cancelled and not keep_state and not foreign:
        state.unlink(missing_ok=True)  # the render is complete: a state was not asked for
    settings = {"scene": str(scene_path), "defines": defines, "output": str(args.output)}
    if args.rig:
        settings["rig"] = args.rig
    paths = write_all(result, args, stem, settings)
    if paths is None:
        return EXIT_ERROR
    if not args.quiet:
        print_summary(result)
        print(f"wrote {len(paths)} files to {args.output}{'/' if not str(args.output).endswith('/') else ''}")
    if state_error:
        # The images are whole; only the state is missing.
        older = f", and {state.name} is an earlier checkpoint's" if state.exists() else ", without a state to resume from"
        _error(f"{state_error}; the images{' of the passes finished so far' if cancelled else ''} were written "
               f"to {args.output}{older}")
        return stop_signals.exit_code() if cancelled else EXIT_ERROR
    if cancelled:
        if args.backend:
            print("mvpt: interrupted; wrote the passes finished so far (the mitsuba backend keeps no state)",
                  file=sys.stderr)
        elif foreign:
            print(f"mvpt: interrupted; wrote the passes finished so far, without a state to resume from "
                  f"({state} is another render's)", file=sys.stderr)
        else:
            print(f"mvpt: interrupted; wrote the passes finished so far and their state; continue with: "
                  f"mvpt render --resume {args.output}", file=sys.stderr)
        return stop_signals.exit_code()
    if stop_signals.stop_requested():
        print(f"mvpt: {stop_signals.stopped_by.name} came as the render ended; its outputs are complete", file=sys.stderr)
    return stop_signals.final_code(EXIT_OK)


def _say_auto(result, args) -> None:
    """The line that says what --method auto chose and why (not with -q)."""
    auto = result.stats.get("auto")
    if auto and not args.quiet:
        print(f"method auto: {auto['method']} ({auto['reason']})", flush=True)


def _render_on_ray(scene_path: Path, args, stem: str, views, bar) -> int:
    """`mvpt render --ray [ADDRESS] --workers N` (docs/distributed.md)."""
    from . import distributed
    stop_signals.interruptible = True  # (distributed.render stops on KeyboardInterrupt)
    try:
        result = distributed.render(scene_path, spp=args.spp, time=args.time, seed=args.seed, method=args.method,
                                    views=views, rig=args.rig, defines=dict(args.define or []),
                                    address=None if args.ray == "local" else args.ray, workers=args.workers,
                                    task_cpus=args.threads, progress=bar, shared=args.shared_scene,
                                    wheel=args.wheel, splits=args.splits)
    except KeyboardInterrupt:
        bar.finish(done=False)
        print("mvpt: interrupted before the first range finished; nothing written", file=sys.stderr)
        return stop_signals.exit_code()
    except (RuntimeError, MemoryError, ValueError, OSError) as e:
        return _failed(bar, e)
    finally:
        stop_signals.interruptible = False
    cancelled = bool(result.stats.get("cancelled"))
    bar.finish(done=not cancelled)
    _say_auto(result, args)
    settings = {"scene": str(scene_path), "defines": dict(args.define or []), "output": str(args.output),
                "ray": args.ray, "workers": result.stats["distributed"]["workers"]}
    paths = write_all(result, args, stem, settings)
    if paths is None:
        return EXIT_ERROR
    if not args.quiet:
        print_summary(result)
        d = result.stats["distributed"]
        print(f"{d['tasks']} tasks on {d['workers']} workers of {d['cpus_per_task']} cores, {d['wall_seconds']:.2f} s; "
              f"wrote {len(paths)} files to {args.output}")
    if cancelled:
        print("mvpt: interrupted; wrote the ranges finished so far", file=sys.stderr)
        return stop_signals.exit_code()
    return stop_signals.final_code(EXIT_OK)


RAY_ONLY = ("workers", "shared_scene", "wheel")


def _ray_only_options(args) -> str:
    """The --ray options given without --ray: an error line, or ''."""
    stray = [f"--{k.replace('_', '-')}" for k in RAY_ONLY if k in args.given]
    if stray and getattr(args, "ray", None) is None:
        return f"{', '.join(stray)} only apply with --ray"
    return ""


def _add_render_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("-D", "--define", action="append", type=_define, metavar="NAME=VALUE",
                   help="override a <default> of the scene (repeatable)")
    p.add_argument("--spp", type=_count, default=0, help="samples per pixel (default: each sensor's sample_count)")
    p.add_argument("--time", type=_seconds, default=0.0,
                   help="wall-clock budget in seconds (passes stop when the next would end past it, and "
                        "the budget is not overrun by more than about half a second, except by path tracing's "
                        "first pass; mvpt cuts its first pass and keeps what it finished, and thins its last pass "
                        "to the time left)")
    p.add_argument("--seed", type=_seed, default=None, help="random seed (default: each sampler's seed)")
    p.add_argument("--threads", type=cli_common.threads, default=0, help="worker threads (default: all cores)")
    p.add_argument("--method", choices=("pt", "mvpt", "auto", "scene"), default=None,
                   help="pt: independent path tracing of every view; mvpt: multi-view path tracing; auto: "
                        "mvpt where its pilot predicts a gain over pt at equal time, else pt (it says which "
                        "and why); scene: the scene's integrator, 'mvpath' meaning mvpt (default: auto for "
                        "several views of a 'path' or 'volpath' scene, else scene)")
    p.add_argument("--backend", default=None, metavar="mitsuba[:VARIANT]",
                   help="render with Dr.Jit on Mitsuba 3 (docs/mitsuba-backend.md): cuda_ad_rgb where a GPU "
                        "is present, else llvm_ad_rgb; methods pt and mvpt, no states or ranges")
    p.add_argument("--splits", type=_splits, default=None, metavar="N|auto",
                   help="mvpt: light samples and bounces per shared first vertex, 1 to 64, or auto (chosen "
                        "per render); default: the scene's mvpath setting, else 2")
    p.add_argument("--rig", default=None, metavar="SPEC",
                   help="replace the sensors by a rig around the first one: stereo:ipd=0.064, "
                        "linear:n=45,baseline=0.5, grid:9x9,spacing=0.05[,focus_distance=D], "
                        "orbit:n=60,radius=4, path:keys.json,frames=100,fps=24,shutter=0.5")
    p.add_argument("--views", default=None, metavar="LIST",
                   help="comma-separated view ids or indices to render (an id wins over an index)")
    p.add_argument("-o", "--output", type=Path, default=Path("out"), help="output directory (default: out)")
    p.add_argument("--aovs", action="store_true",
                   help="add variance and sample-count channels (mvpt: native samples and contributions "
                        "received) to the EXRs")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    p.add_argument("--passes", type=state_cli.pass_range, default=None, metavar="FIRST:COUNT",
                   help="render one range of a render split over processes or machines: COUNT passes of "
                        "every view with the samples of passes FIRST..FIRST+COUNT-1 (instead of --spp); "
                        "combine the ranges' states with `mvpt merge`")
    p.add_argument("--ray", nargs="?", const="local", default=None, metavar="ADDRESS",
                   help="render on a Ray cluster (ADDRESS, e.g. auto or ray://head:10001; without one, a local "
                        "Ray instance): ranges of passes as tasks, merged in order (needs mvpt[ray])")
    p.add_argument("--workers", type=_count, default=0,
                   help="with --ray: tasks at a time (default: one per node); --threads is then each task's cores")
    p.add_argument("--shared-scene", action="store_true",
                   help="with --ray: the scene's files are at the same path on every node (else they are "
                        "packed once and sent through Ray)")
    p.add_argument("--wheel", default=None, metavar="WHL",
                   help="with --ray: a wheel from scripts/build-wheel.sh that Ray installs for the tasks on "
                        "nodes without mvpt")
    p.add_argument("--checkpoint", type=_seconds, default=0.0, metavar="SECONDS",
                   help="write the render's state (<stem>.mvpt-state in the output directory) every SECONDS "
                        "and keep it at the end (an interrupted render always writes it)")
    displays.add_display_options(p)


def command() -> int:
    """The `mvpt` program (`mvpt`, `python -m mvpt`): main() with its signal handlers kept to the
    end of the process (stop_signals.end): Python's shutdown would restore their default
    action, which kills the process with its work done and its exit status lost. A signal that
    came at any point gives its exit code (128 + its number) where the command succeeded."""
    return stop_signals.end(main(keep_handlers=True))


def main(argv=None, keep_handlers: bool = False) -> int:
    """The command line as a function: its signal handlers are restored when it returns (unless
    `keep_handlers`: the process ends with it). Exit codes: see the module's docstring."""
    previous = stop_signals.install()
    try:
        if stop_signals.stop_requested():
            raise KeyboardInterrupt  # (it came while the program started: program.py)
        return stop_signals.final_code(_command(argv))
    except KeyboardInterrupt:
        print("\nmvpt: interrupted", file=sys.stderr)
        return stop_signals.exit_code()
    finally:
        # From here on (the work is done) a signal is only recorded: it must not raise into the
        # restoring loop.
        stop_signals.interruptible = False
        if not keep_handlers:
            stop_signals.restore(previous)


def _command(argv) -> int:
    """The command of `argv`, parsed and run."""
    parser = _Parser(prog="mvpt", description="Render many views of one scene (Mitsuba 3 XML).")
    parser.add_argument("--version", action="version", version=f"mvpt {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    p_render = sub.add_parser("render", help="render every view of a scene")
    p_render.add_argument("scene", type=Path, nargs="?", help="the scene (Mitsuba 3 XML, or a .blend file)")
    p_render.add_argument("--xml-dir", type=Path, default=None, metavar="DIR",
                          help="for a .blend scene: write the converted Mitsuba 3 scene (XML and PLY meshes) "
                               "into DIR and keep it (default: a temporary folder)")
    p_render.add_argument("--frames", type=_frames, default=None, metavar="A:B",
                          help="for a .blend scene: render Blender's frames A to B (inclusive) as a shot, one "
                               "view per frame with the scene's motion blur (default: its current frame alone)")
    p_render.add_argument("--resume", metavar="OUT", default=None,
                          help="continue the interrupted render whose state is in the output directory OUT "
                               "(or the state file OUT), with its scene and settings; the images equal those of "
                               "a render that was never stopped")
    _add_render_options(p_render)
    p_demo = sub.add_parser("demo", help="render the built-in demo scene")
    _add_render_options(p_demo)
    reports_cli.add_commands(sub)
    state_cli.add_merge_command(sub)
    p_addon = sub.add_parser("blender-addon", help="write the Blender add-on (a zip to install in Blender's "
                             "preferences) that renders with mvpt")
    p_addon.add_argument("-o", "--output", type=Path, default=Path("mvpt_blender.zip"),
                         help="the zip to write (default: mvpt_blender.zip)")
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:
        return int(e.code) if isinstance(e.code, int) else EXIT_USAGE
    if args.command in ("render", "demo"):
        # The options given on the command line, as opposed to left at their defaults.
        defaults = vars((p_render if args.command == "render" else p_demo).parse_args([]))
        args.given = {k for k, v in vars(args).items() if k in defaults and k != "scene" and v != defaults[k]}
        problem = _ray_only_options(args)
        if problem:
            _error(problem)
            return EXIT_USAGE
    if args.command == "render":
        if args.resume is not None:
            return state_cli.resume(args, _render)
        if args.scene is None:
            _error("render: the scene is required (or --resume OUT)")
            return EXIT_USAGE
        return _render(args.scene, args, args.scene.stem)
    if args.command in reports_cli.COMMANDS:
        return reports_cli.run(args)
    if args.command == "merge":
        return state_cli.merge(args)
    if args.command == "blender-addon":
        from .blender.addon import addon_zip_command
        try:
            return addon_zip_command(args.output)
        except OSError as e:
            _error(f"{args.output}: {e.strerror or e}")
            return EXIT_ERROR
    with resources.as_file(resources.files("mvpt") / "data" / "demo.xml") as demo:
        return _render(demo, args, "demo")


if __name__ == "__main__":
    sys.exit(command())
