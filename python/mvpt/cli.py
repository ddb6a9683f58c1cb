"""The `mvpt` command line: `mvpt render scene.xml -D spp=64 -o out/`, `mvpt demo`."""
from __future__ import annotations

import argparse
import sys
import time
from importlib import resources
from pathlib import Path

from . import api
from ._core import SceneError
from .output import write_outputs


class ProgressBar:
    """One-line progress bar with ETA on a terminal (silent when not a TTY unless forced)."""

    def __init__(self, stream=sys.stderr, enabled=None):
        self.stream = stream
        self.enabled = stream.isatty() if enabled is None else enabled
        self.start = time.monotonic()

    def __call__(self, p: dict) -> None:
        if not self.enabled:
            return
        frac = min(max(p["fraction"], 0.0), 1.0)
        elapsed = time.monotonic() - self.start
        eta = elapsed * (1 - frac) / frac if frac > 0 else float("nan")
        width = 30
        bar = "#" * int(frac * width) + "." * (width - int(frac * width))
        self.stream.write(f"\r[{bar}] {100 * frac:5.1f}%  pass {p['pass']}  "
                          f"{elapsed:6.1f}s elapsed  ETA {eta:6.1f}s ")
        self.stream.flush()

    def finish(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()


def _parse_defines(items):
    out = {}
    for item in items or []:
        if "=" not in item:
            raise SystemExit(f"mvpt: -D expects name=value, got '{item}'")
        k, v = item.split("=", 1)
        out[k] = v
    return out


def _print_summary(result, stream=sys.stdout) -> None:
    s = result.stats
    stream.write(f"{'view':>12} {'spp':>8} {'mean R':>10} {'mean G':>10} {'mean B':>10}\n")
    for vid, v in s["views"].items():
        m = v["mean"]
        stream.write(f"{vid:>12} {v['spp']:8.1f} {m[0]:10.4f} {m[1]:10.4f} {m[2]:10.4f}\n")
    stream.write(f"{s['passes']} passes, {s['seconds']:.2f} s, {s['samples_per_second'] / 1e6:.3f} M samples/s, "
                 f"{s['rays_per_second'] / 1e6:.2f} M rays/s, {s['threads']} threads"
                 f"{', cancelled' if s.get('cancelled') else ''}\n")
    if s.get("nonfinite_samples"):
        f = s.get("first_nonfinite", {})
        stream.write(f"warning: {s['nonfinite_samples']} non-finite samples were dropped "
                     f"(first: view {f.get('view')}, pixel ({f.get('x')}, {f.get('y')}), sample {f.get('sample')})\n")


def _render(scene_path: Path, args, stem: str) -> int:
    try:
        scene = api.load_file(scene_path, **_parse_defines(args.define))
    except SceneError as e:
        print(f"mvpt: error: {e}", file=sys.stderr)
        return 2
    views = [v for v in args.views.split(",")] if args.views else None
    bar = ProgressBar(enabled=False if args.quiet else None)
    try:
        result = api.render(scene, spp=args.spp, time=args.time, seed=args.seed, threads=args.threads,
                            views=views, progress=bar)
    except ValueError as e:
        bar.finish()
        print(f"mvpt: error: {e}", file=sys.stderr)
        return 2
    bar.finish()
    settings = {"scene": str(scene_path), "defines": _parse_defines(args.define), "spp": args.spp,
                "time": args.time, "seed": args.seed, "threads": args.threads, "views": views}
    paths = write_outputs(result, args.output, stem, aovs=args.aovs, settings=settings)
    if not args.quiet:
        _print_summary(result)
        print(f"wrote {len(paths)} files to {args.output}/")
    return 130 if result.stats.get("cancelled") and args.time == 0 and args.spp == 0 else 0


def _add_render_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("-D", "--define", action="append", metavar="NAME=VALUE",
                   help="override a <default> of the scene (repeatable)")
    p.add_argument("--spp", type=int, default=0, help="samples per pixel (default: the scene's sample_count)")
    p.add_argument("--time", type=float, default=0.0, help="wall-clock budget in seconds")
    p.add_argument("--seed", type=int, default=None, help="random seed (default: the sampler's seed)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (default: all cores)")
    p.add_argument("--views", default=None, help="comma-separated view ids or indices to render")
    p.add_argument("-o", "--output", default="out", help="output directory (default: out)")
    p.add_argument("--aovs", action="store_true", help="add variance and sample-count channels to the EXRs")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="mvpt", description="Render many views of one scene (Mitsuba 3 XML).")
    sub = parser.add_subparsers(dest="command", required=True)
    p_render = sub.add_parser("render", help="render every view of a scene")
    p_render.add_argument("scene", type=Path)
    _add_render_options(p_render)
    p_demo = sub.add_parser("demo", help="render the built-in 9-view demo scene")
    _add_render_options(p_demo)
    args = parser.parse_args(argv)

    if args.command == "render":
        return _render(args.scene, args, args.scene.stem)
    with resources.as_file(resources.files("mvpt") / "data" / "demo.xml") as demo:
        return _render(demo, args, "demo")


if __name__ == "__main__":
    sys.exit(main())
