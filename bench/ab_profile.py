"""Interleaved one-thread CPU-time A/B of two mvpt_profile builds on the same scene.

    python bench/profile_paths.py cbox-rgb --res 128 --write-xml /tmp/cbox.xml   # prints BASE
    cp build/prof/mvpt_profile /tmp/profile_a      # before the change; rebuild, then:
    python bench/ab_profile.py /tmp/profile_a build/prof/mvpt_profile /tmp/cbox.xml BASE --spp 16 --pairs 15

Runs A and B alternately (A, B, A, B, ...), one thread each, and reads the CPU seconds that
bench/profile_paths.cpp prints, so that load changes on a shared machine hit both alike.
Reports both medians, the median of the per-pair ratios B/A (below 1: B is faster), in how
many pairs B was faster, and whether the two builds' image hashes agree (a pure optimisation
must leave them equal). Differences of a percent or two are within the noise of a loaded
2-core machine at 15 pairs: confirm them with instruction counts (profile_paths.py's docstring).

    python bench/ab_profile.py --module SITE_A SITE_B /tmp/cbox.xml BASE --spp 16 [--method mvpt]

does the same with two builds of the Python module (each SITE a folder holding an `mvpt`
package, as scripts/dev-build.sh makes under build/dev/site): one `mvpt.render` per process,
one thread, its CPU time. The module is what users and bench_vs_mitsuba.py run, and as a
shared library it pays costs that the static profile driver does not (every use of a
thread_local called __tls_get_addr there, which the driver's linker relaxed away).
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys

CPU = re.compile(r"\(([0-9.]+) s CPU\)")
HASH = re.compile(r"image hash ([0-9a-f]+)")


def run(binary: str, xml: str, base: str, spp: int, method: str = "scene") -> tuple[float, str]:
    """One render of `binary`: its CPU seconds and image hash."""
    out = subprocess.run([binary, xml, base, str(spp), "1"], check=True, capture_output=True, text=True).stdout
    cpu, digest = CPU.search(out), HASH.search(out)
    if not cpu or not digest:
        sys.exit(f"unexpected output of {binary}: {out!r}")
    return float(cpu.group(1)), digest.group(1)


# One render through the Python module, printed in the profile driver's format.
MODULE_RUN = r"""
import hashlib, sys, time
import numpy as np
import mvpt
xml, base, spp, method = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
scene = mvpt.load_string(open(xml).read(), base)
t0 = time.process_time()
r = mvpt.render(scene, spp=spp, seed=1, threads=1, method=method)
cpu = time.process_time() - t0
img = np.ascontiguousarray(np.asarray(r.images[r.view_ids[0]], np.float32))
print(f"({cpu:.4f} s CPU), image hash {hashlib.sha256(img.tobytes()).hexdigest()[:16]}")
"""


def run_module(site: str, xml: str, base: str, spp: int, method: str = "scene") -> tuple[float, str]:
    """One render through the module under `site`: its CPU seconds and image hash."""
    env = dict(os.environ, PYTHONPATH=site, OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", MODULE_RUN, xml, base, str(spp), method], check=True, capture_output=True,
                         text=True, env=env).stdout
    cpu, digest = CPU.search(out), HASH.search(out)
    if not cpu or not digest:
        sys.exit(f"unexpected output of the module under {site}: {out!r}")
    return float(cpu.group(1)), digest.group(1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", help="the reference mvpt_profile binary (with --module: a site folder)")
    ap.add_argument("b", help="the candidate mvpt_profile binary (with --module: a site folder)")
    ap.add_argument("xml", help="a scene written by profile_paths.py --write-xml")
    ap.add_argument("base", help="the scene's base directory (printed by profile_paths.py)")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--pairs", type=int, default=15)
    ap.add_argument("--module", action="store_true", help="A and B are folders holding builds of the Python module")
    ap.add_argument("--method", default="scene", choices=["scene", "pt", "mvpt"],
                    help="with --module: the render method (default: the scene's integrator)")
    args = ap.parse_args(argv)
    render = run_module if args.module else run

    a_cpu, b_cpu, hashes = [], [], set()
    for _ in range(args.pairs):
        for binary, times in ((args.a, a_cpu), (args.b, b_cpu)):
            t, digest = render(binary, args.xml, args.base, args.spp, args.method)
            times.append(t)
            hashes.add((binary, digest))
    ratios = [b / a for a, b in zip(a_cpu, b_cpu)]
    same = len({d for _, d in hashes}) == 1
    print(f"A median {statistics.median(a_cpu):.4f} s, B median {statistics.median(b_cpu):.4f} s, "
          f"median B/A {statistics.median(ratios):.4f} ({args.pairs} pairs, B faster in "
          f"{sum(r < 1.0 for r in ratios)}); image hashes {'equal' if same else 'DIFFER'}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
