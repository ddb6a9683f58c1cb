"""The `mvpt compare` and `mvpt bench-equal-time` subcommands (registered by cli.py)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._core import SceneError
from .cli_common import EXIT_ERROR, EXIT_OK
from .cli_common import count as _count, define as _define, error as _error, seed as _seed, threads as _threads

COMMANDS = ("compare", "bench-equal-time")


def _positive_seconds(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not v > 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got '{text}'")
    return v


def _fractions(text: str) -> tuple:
    try:
        v = tuple(float(t) for t in text.split(","))
    except ValueError:
        v = ()
    if not v or any(not 0 < f <= 1 for f in v):
        raise argparse.ArgumentTypeError(f"expected comma-separated fractions in (0, 1], got '{text}'")
    return v


def add_commands(sub) -> None:
    """Register the subcommands on cli.py's subparsers."""

    p = sub.add_parser("compare", help="RMSE, relMSE and FLIP of runs against a reference, per view and overall",
                       description="Runs are output directories of `mvpt render`, their <stem>.json, multi-view "
                                   "EXRs (one part per view) or single EXRs; views are matched by id.")
    p.add_argument("runs", nargs="+", type=Path, help="runs to evaluate")
    p.add_argument("--reference", "-r", type=Path, required=True, help="the reference run")
    p.add_argument("--json", type=Path, default=None, help="also write the numbers to this JSON file")
    p.add_argument("--no-flip", action="store_true", help="skip FLIP (RMSE and relMSE only)")

    b = sub.add_parser("bench-equal-time", help="render each method for the same time; write an HTML report",
                       description="Renders the reference (or reuses a matching one in <output>/reference, or "
                                   "takes --reference), then each method at the budgets time x --curve, and writes "
                                   "<output>/index.html (self-contained) and <output>/bench.json.")
    b.add_argument("scene", type=Path)
    b.add_argument("--time", type=_positive_seconds, required=True, help="wall-clock seconds per method")
    b.add_argument("--methods", default="pt,mvpt", help="comma-separated methods (default: pt,mvpt)")
    g = b.add_mutually_exclusive_group()
    g.add_argument("--reference", type=Path, default=None, help="a reference run (directory, JSON or EXR)")
    g.add_argument("--reference-spp", type=_count, default=None,
                   help="samples per pixel of the reference render (default: 1024)")
    b.add_argument("--curve", type=_fractions, default=None,
                   help="fractions of --time for the convergence curve (default: 0.125,0.25,0.5,1)")
    b.add_argument("-D", "--define", action="append", type=_define, metavar="NAME=VALUE",
                   help="override a <default> of the scene (repeatable)")
    b.add_argument("--seed", type=_seed, default=None, help="random seed (default: each sampler's seed)")
    b.add_argument("--threads", type=_threads, default=0, help="worker threads (default: all cores)")
    b.add_argument("--views", default=None, metavar="LIST", help="comma-separated view ids or indices")
    b.add_argument("-o", "--output", type=Path, default=Path("bench"), help="report directory (default: bench)")
    b.add_argument("-q", "--quiet", action="store_true", help="no progress lines")


def _compare(args) -> int:
    from . import compare
    from .output import write_json_atomic

    try:
        ref, results = compare.compare_paths(args.runs, args.reference, with_flip=not args.no_flip)
    except (ValueError, RuntimeError, ImportError) as e:
        _error(str(e))
        return EXIT_ERROR
    sys.stdout.write(compare.format_table(results))
    if args.json is not None:
        try:
            write_json_atomic(args.json, compare.as_json(ref, results))
        except OSError as e:
            _error(f"cannot write '{args.json}': {e}")
            return EXIT_ERROR
    return EXIT_OK


def _bench(args) -> int:
    from . import bench, report

    cfg = bench.BenchConfig(scene=args.scene, time=args.time,
                            methods=tuple(m.strip() for m in args.methods.split(",") if m.strip()),
                            reference=args.reference, defines=dict(args.define or []), seed=args.seed,
                            threads=args.threads, views=args.views.split(",") if args.views else None,
                            output=args.output)
    if args.reference_spp is not None:
        cfg.reference_spp = args.reference_spp
    if args.curve is not None:
        cfg.curve = args.curve
    log = (lambda *a: None) if args.quiet else (lambda msg: print(msg, flush=True))
    try:
        result = bench.run_bench(cfg, log=log)
        path = report.write_report(result)
    except SceneError as e:
        _error(str(e))
        return EXIT_ERROR
    except (ValueError, RuntimeError, OSError, ImportError) as e:
        _error(str(e))
        return EXIT_ERROR
    if not args.quiet:
        noise = result.reference_noise.get("overall")
        if noise is not None:
            print(f"reference's own noise: relMSE {noise:.4g} (subtracted below)")
        for m, r in result.methods.items():
            o = r.errors.overall
            corrected = f" ({r.corrected['overall']:.4g} without the reference's noise)" if r.corrected else ""
            d = r.display
            shown = (f"; as a display shows the views {d['relmse']:.4g}"
                     + (f" ({d['relmse_corrected']:.4g})" if d.get("relmse_corrected") is not None else "")
                     if d else "")
            print(f"{m}: relMSE {o.relmse:.4g}{corrected}, FLIP {o.flip:.4g}, RMSE {o.rmse:.4g}{shown}")
        print(f"wrote {path}")
    for w in result.warnings:
        print(f"mvpt: warning: {w}", file=sys.stderr)
    return EXIT_OK


def run(args) -> int:
    """Run the subcommand `args.command`."""
    return _compare(args) if args.command == "compare" else _bench(args)
