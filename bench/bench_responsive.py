"""How promptly a render of many large views answers: progress, Ctrl-C and a time budget.

    python bench/bench_responsive.py                      # 81 views of 512², all cores
    python bench/bench_responsive.py --res 96 --threads 2 # a quick run

Renders a 9x9 light field of the still life (scenes/stereo.xml --rig grid:9x9) with `pt` and
`mvpt` and prints, per method: the length of one pass and of the whole call, the longest chunk
of tiles (between two chunks progress is reported and Ctrl-C and the budget are checked) and
the longest gap between progress reports that brought new samples; the time from a
KeyboardInterrupt raised in the progress callback 2 s into a render to the returned images; and
the time from the end of a time budget (--budgets) to the returned images, and how much of a
first pass cut short or of a last pass thinned to the budget (multi-view path tracing,
docs/multiview-path-tracing.md) they keep.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import mvpt

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "stereo.xml"


def progress_gaps(scene, method: str, threads: int) -> None:
    stamps = []
    t0 = time.monotonic()
    r = mvpt.render(scene, spp=1, method=method, threads=threads, poll=0.02,
                    progress=lambda p: stamps.append((time.monotonic(), p["samples"])))
    wall = time.monotonic() - t0
    moving = [t for (t, s), (_, s0) in zip(stamps[1:], stamps[:-1]) if s != s0]
    gaps = [b - a for a, b in zip(moving, moving[1:])]
    print(f"{method:4s}  one pass {r.stats['max_pass_seconds']:6.2f} s (the call {wall:6.2f} s), longest chunk "
          f"{r.stats['max_chunk_seconds']:.3f} s, longest gap between progress reports "
          f"{max(gaps) if gaps else float('nan'):.3f} s ({len(moving)} reports)", flush=True)


def interrupt(scene, method: str, threads: int, after: float = 2.0) -> None:
    raised = []
    t0 = time.monotonic()

    def stop(p):
        if not raised and time.monotonic() - t0 > after and p["samples"] > 0:
            raised.append(time.monotonic())
            raise KeyboardInterrupt

    r = mvpt.render(scene, spp=64, method=method, threads=threads, poll=0.02, progress=stop)
    print(f"{method:4s}  Ctrl-C {raised[0] - t0:.2f} s in: images back {time.monotonic() - raised[0]:.3f} s later "
          f"({r.stats['passes']} passes kept{_cut(r)})", flush=True)


def _cut(r) -> str:
    """The share of a first pass cut short that the images keep, and that of a last pass
    thinned to the budget (multi-view path tracing)."""
    share, thin = r.stats.get("cut_pass_share", 0.0), r.stats.get("thinned_pass_share", 0.0)
    return (f", the first cut at {share:.0%} of its regions" if share else "") + \
        (f", the last thinned to {thin:.0%} of its samples" if thin else "")


def budget(scene, method: str, threads: int, seconds: float) -> None:
    t0 = time.monotonic()
    r = mvpt.render(scene, time=seconds, method=method, threads=threads)
    wall = time.monotonic() - t0
    print(f"{method:4s}  --time {seconds:g}: images back after {wall:.2f} s ({wall - seconds:+.2f} s), "
          f"{r.stats['passes']} passes{_cut(r)}", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=512, help="each view's width and height")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--budgets", default="2,5", help="comma-separated time budgets in seconds")
    args = ap.parse_args(argv)
    scene = mvpt.load_file(str(SCENE), rig="grid:9x9,spacing=0.05", res=str(args.res))
    print(f"81 views of {args.res}², {args.threads} threads", flush=True)
    for method in ("mvpt", "pt"):
        progress_gaps(scene, method, args.threads)
        interrupt(scene, method, args.threads)
        for b in args.budgets.split(","):
            budget(scene, method, args.threads, float(b))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
