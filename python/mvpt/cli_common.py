"""What the command line's subcommands share: exit codes, the error line, argument types, and
writing a render's outputs as one set."""
from __future__ import annotations

import argparse
import math
import sys

from . import displays, stop_signals
from .output import staged_outputs, write_outputs

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2


def failure_text(e: BaseException) -> str:
    """The error line's text for an exception out of a load or a render: memory exhausted (a
    bare std::bad_alloc, threads that could not start) said as such."""
    text = str(e)
    if isinstance(e, MemoryError) or text in ("std::bad_alloc", "bad_alloc"):
        return "out of memory" + (f" ({text})" if text and "bad_alloc" not in text else "") + \
            " (is a memory limit set, by ulimit -v or a container?)"
    if "Resource temporarily unavailable" in text:
        return f"cannot start the worker threads: {text} (a limit on processes or memory?)"
    return text or type(e).__name__


def error(msg: str) -> None:
    print(f"mvpt: error: {msg}", file=sys.stderr)


def count(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got '{text}'")
    if not 0 <= v < 2**31:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer below 2^31, got {v}")
    return v


def threads(text: str) -> int:
    """--threads: 0 (one per core) to api.MAX_THREADS."""
    from .api import MAX_THREADS
    v = count(text)
    if v > MAX_THREADS:
        raise argparse.ArgumentTypeError(f"at most {MAX_THREADS} threads (0: one per core), got {v}")
    return v


def seconds(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got '{text}'")
    if not (v >= 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError(f"expected a non-negative number of seconds, got {text}")
    return v


def seed(text: str) -> int:
    v = count(text)
    if v >= 2**32:
        raise argparse.ArgumentTypeError(f"expected a seed below 2^32, got {v}")
    return v


def splits(text: str) -> int | str:
    """--splits: 'auto' or an integer in [1, 64]."""
    if text == "auto":
        return text
    try:
        v = int(text)
    except ValueError:
        v = 0
    if not 1 <= v <= 64:
        raise argparse.ArgumentTypeError(f"expected 'auto' or an integer in [1, 64], got '{text}'")
    return v


def define(text: str) -> tuple:
    name, eq, value = text.partition("=")
    if not eq or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got '{text}'")
    return name.strip(), value


def write_all(result, args, stem: str, settings: dict):
    """The per-view files, the JSON and the displays asked for in args.output, as one set
    (output.staged_outputs); their paths, or None after printing the error. Ctrl-C, SIGTERM and
    SIGHUP while writing do not interrupt it: they are reported, and the exit code says so
    (stop_signals.finishing)."""
    staging, before = None, stop_signals.stopped_by
    with stop_signals.finishing("writing the outputs"):
        try:
            with staged_outputs(args.output) as (staging, paths):
                paths += write_outputs(result, staging, stem, aovs=bool(args.aovs), settings=settings)
                if displays.wants_displays(args):
                    paths += displays.write_displays(result, args, staging, stem)
        except (OSError, RuntimeError, ValueError, ImportError) as e:
            error(str(e).replace(f"{staging}/", f"{args.output}/") if staging else str(e))
            return None
        if stop_signals.stopped_by is not before:  # (the line after "finishing writing the outputs")
            print(f"mvpt: wrote the outputs ({len(paths)} files to {args.output})", file=sys.stderr)
    return paths
