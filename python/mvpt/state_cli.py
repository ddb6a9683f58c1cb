"""The command line of render states (docs/checkpoints.md, docs/distributed.md):
`mvpt render --resume OUT`, `mvpt render --passes FIRST:COUNT` and `mvpt merge`."""
from __future__ import annotations

import argparse
import os
from pathlib import Path

from . import api
from . import state as state_file
from ._core import SceneError, StateError
from .cli_common import EXIT_ERROR, EXIT_OK, EXIT_USAGE, write_all
from .cli_common import error as _error, threads as _threads
from .summary import print_summary

# The options that make a render's image: `--resume` takes them from the state file.
IMAGE_OPTIONS = ("define", "spp", "time", "seed", "method", "rig", "views", "passes", "splits")
# What a resume or a merge reuses of the first run's command line (outputs included).
RECORDED_OPTIONS = IMAGE_OPTIONS + ("aovs", "multiview_exr", "stereo", "quilt", "contact_sheet", "gif", "mp4",
                                    "fps", "exposure")


def pass_range(text: str) -> tuple:
    """FIRST:COUNT, e.g. 0:64 (passes 0 to 63)."""
    first, colon, count = text.partition(":")
    try:
        first, count = int(first), int(count)
    except ValueError:
        first = count = -1
    if not colon or first < 0 or count < 1 or first + count >= 2**31:
        raise argparse.ArgumentTypeError(f"expected FIRST:COUNT with FIRST >= 0 and COUNT >= 1, got '{text}'")
    return first, count


def command_record(scene_path: Path, args, stem: str) -> dict:
    """The command line of a render as its state file keeps it, for `--resume` and `merge`."""
    record = {k: getattr(args, k, None) for k in RECORDED_OPTIONS}
    record["define"] = [list(d) for d in (args.define or [])]
    scene = Path(scene_path).resolve()
    # Also relative to the output folder, where the state lives: a project folder moved as a
    # whole still resumes.
    beside = os.path.relpath(scene, Path(args.output).resolve())
    return dict(record, scene=str(scene), scene_from_state=beside, stem=stem, checkpoint=args.checkpoint)


def _scene_of(record: dict, state: Path) -> Path:
    """The scene a state's record names: its absolute path, or where it lies relative to the
    state when that path is gone (the folders were moved together)."""
    scene = Path(record["scene"])
    beside = record.get("scene_from_state")
    if not scene.exists() and isinstance(beside, str) and (state.parent / beside).exists():
        return state.parent / beside
    return scene


def find_state(path: Path) -> Path:
    """The state file `path`, or the one state file in the directory `path`."""
    if not path.is_dir():
        return path
    found = sorted(path.glob(f"*{state_file.SUFFIX}"))
    if not found:
        raise StateError(f"{path} holds no render state ({state_file.SUFFIX})")
    if len(found) > 1:
        # Renders of several scenes may share a folder (their stems differ): name each, with its scene.
        raise StateError(f"{path} holds {len(found)} render states, {_described(found)}: name the one to use, "
                         f"e.g. {found[0]}")
    return found[0]


def _described(states: list) -> str:
    """'a.mvpt-state (of a.xml), b.mvpt-state (of b.xml)': each state with the scene it renders."""
    def scene(p: Path) -> str:
        try:
            return f" (of {Path(_record(p)['scene']).name})"
        except (StateError, OSError, TypeError, KeyError):
            return ""
    return ", ".join(f"{p.name}{scene(p)}" for p in states)


def _record(path: Path) -> dict:
    record = state_file.read_header(path).get("extra", {}).get("command")
    if not isinstance(record, dict) or "scene" not in record:
        raise StateError(f"the state file '{path}' was not written by `mvpt render`; use mvpt.render(resume=...) "
                         f"or mvpt.merge(...)")
    return record


def _restore(args, record: dict) -> None:
    for k in RECORDED_OPTIONS:
        setattr(args, k, record.get(k))
    args.define = [tuple(d) for d in record.get("define") or []]
    if args.passes is not None:
        args.passes = tuple(args.passes)


def resume(args, render) -> int:
    """`mvpt render --resume OUT`: continue the render whose state is in OUT (or is the file OUT)
    with `render(scene path, args, stem)`."""
    explicit = args.given  # the options on the command line (cli.main)
    given = [f"--{k.replace('_', '-')}" for k in IMAGE_OPTIONS if k in explicit]
    if args.scene is not None:
        given.insert(0, "a scene")
    if given:
        _error(f"--resume continues a render with its own scene and settings; drop {', '.join(given)}")
        return EXIT_USAGE
    try:
        path = find_state(Path(args.resume))
        record = _record(path)
    except StateError as e:
        _error(str(e))
        return EXIT_ERROR
    if "output" in explicit and Path(args.output).resolve() != path.parent.resolve():
        _error(f"--resume writes into the folder of its state, {path.parent}; drop -o {args.output}")
        return EXIT_USAGE
    checkpoint = args.checkpoint
    # Outputs given now (--aovs, --quilt ...) are added to or replace those of the first run.
    outputs = {k: getattr(args, k) for k in RECORDED_OPTIONS if k not in IMAGE_OPTIONS and k in explicit}
    _restore(args, record)
    for k, v in outputs.items():
        setattr(args, k, v)
    args.output = path.parent
    args.resume_state = path
    # Periodic checkpoints go on unless changed.
    args.checkpoint = checkpoint or float(record.get("checkpoint") or 0.0)
    return render(_scene_of(record, path), args, record["stem"])


def add_merge_command(sub) -> None:
    p = sub.add_parser("merge", help="combine the states of ranges (--passes) or seeds of one render")
    p.add_argument("states", nargs="+", type=Path, metavar="STATE",
                   help="state files (<stem>.mvpt-state), or output directories holding one each")
    p.add_argument("-o", "--output", type=Path, required=True, help="output directory of the merged render")
    p.add_argument("--threads", type=_threads, default=0, help="worker threads (default: all cores)")
    p.add_argument("-q", "--quiet", action="store_true", help="no summary")


def merge(args) -> int:
    """`mvpt merge STATE... -o OUT`: the images of the states' render as if one process had
    rendered all their passes, with the first state's outputs (and the merged state) in OUT."""
    try:
        paths = [find_state(p) for p in args.states]
        record = _record(paths[0])
        scene = api.load_file(_scene_of(record, paths[0]), rig=record.get("rig"),
                              **dict(tuple(d) for d in record.get("define") or []))
        args.output.mkdir(parents=True, exist_ok=True)
        result = api.merge(scene, paths, threads=max(0, args.threads),
                           state=state_file.state_file(args.output, record["stem"]))
    except (SceneError, StateError, RuntimeError, ValueError, OSError) as e:
        _error(str(e))
        return EXIT_ERROR
    _restore(args, record)
    settings = {"scene": record["scene"], "defines": dict(args.define), "output": str(args.output),
                "merged_from": [str(p) for p in paths]}
    written = write_all(result, args, record["stem"], settings)
    if written is None:
        return EXIT_ERROR
    if not args.quiet:
        print_summary(result)
        print(f"merged {len(paths)} states; wrote {len(written)} files to {args.output}")
    return EXIT_OK
