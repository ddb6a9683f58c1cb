"""How path tracing and multi-view path tracing scale with threads, and their memory.

    python bench/bench_scaling.py                          # --threads 1,2 (this machine's cores)
    python bench/bench_scaling.py --threads 2,4,8,16       # a many-core machine
    python bench/bench_scaling.py --quick                  # small films, one repeat

Cases (each rendered by `pt` and `mvpt` at every thread count, one render per process):
- `cbox`: the 9-view glossy Cornell box (scenes/cornell-glossy-9.xml), 256², 16 spp;
- `lf9x9`: a 9x9 light field of the still life (scenes/stereo.xml with --rig grid:9x9), 128², 4 spp;
- `mem45`: 45 views of the still life in a row (linear rig), 256², 1 spp: the memory case;
- `display100` (only when asked for with --cases): 100 views of 1920x1080 in a row, 1 spp, a
  display's light field at full resolution (mvpt: about 21 GB and half an hour on 2 cores;
  with --time 30, which cuts its first pass, the same peak in a few minutes).

Per case, method and thread count the script prints the median over --repeat runs (thread
counts interleaved, so that load changes of a shared machine hit them alike) of: native
samples per second of render time, CPU time per native sample (all threads), the process's
peak RSS and the renderer's own estimate of it; then, against the lowest thread count, the
speed-up, the ratio of CPU time per sample (1.0: no work added by threads) and of peak RSS
(1.0: memory independent of the thread count). A thread count above the machine's cores
measures oversubscription, not scaling.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# (scene file, rig, defines, spp)
CASES = {
    "cbox": (ROOT / "scenes" / "cornell-glossy-9.xml", "", {"res": "256"}, 16),
    "lf9x9": (ROOT / "scenes" / "stereo.xml", "grid:9x9,spacing=0.05", {"res": "128"}, 4),
    "mem45": (ROOT / "scenes" / "stereo.xml", "linear:n=45,baseline=0.5", {"res": "256"}, 1),
    "display100": (ROOT / "scenes" / "stereo.xml", "linear:n=100,baseline=0.5", {"width": "1920", "height": "1080"}, 1),
}
DEFAULT_CASES = ["cbox", "lf9x9", "mem45"]
QUICK = {"cbox": {"res": "64"}, "lf9x9": {"res": "48"}, "mem45": {"res": "96"},
         "display100": {"width": "192", "height": "108"}}

CHILD = r"""
import json, resource, sys, time
import mvpt
scene_path, rig, defines, spp, method, threads = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), int(sys.argv[4]), sys.argv[5], int(sys.argv[6])
budget = float(sys.argv[7])
scene = mvpt.load_file(scene_path, rig=rig or None, **defines)
before = resource.getrusage(resource.RUSAGE_SELF)
r = mvpt.render(scene, spp=0 if budget else spp, time=budget, method=method, threads=threads, seed=1)
after = resource.getrusage(resource.RUSAGE_SELF)
cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0  # Linux: KiB
print(json.dumps({"seconds": r.stats["seconds"], "samples": r.stats["samples"], "cpu": cpu, "peak": peak,
                  "estimated": r.stats["estimated_bytes"], "threads": r.stats["threads"],
                  "max_chunk": r.stats.get("max_chunk_seconds", 0.0)}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", default="1,2", help="comma-separated thread counts (default 1,2)")
    ap.add_argument("--cases", default=",".join(DEFAULT_CASES), help=f"comma-separated cases of {', '.join(CASES)}")
    ap.add_argument("--methods", default="pt,mvpt")
    ap.add_argument("--repeat", type=int, default=3, help="runs per configuration (median)")
    ap.add_argument("--quick", action="store_true", help="small films, one repeat")
    ap.add_argument("--json", type=Path, help="write every run's numbers here")
    ap.add_argument("--time", type=float, default=0.0,
                    help="render each case under this time budget instead of its spp (the peak memory of a "
                         "large case sooner: multi-view path tracing cuts its first pass; the rates then "
                         "count the preparation)")
    args = ap.parse_args()
    threads = [int(t) for t in args.threads.split(",")]
    repeat = 1 if args.quick else args.repeat
    print(f"{os.cpu_count()} cores; thread counts {threads}; {repeat} run(s) each, interleaved", flush=True)
    rows, raw = [], []
    for case in args.cases.split(","):
        for method in args.methods.split(","):
            runs = {t: [] for t in threads}
            for i in range(repeat):
                for t in (threads if i % 2 == 0 else threads[::-1]):
                    r = measure(case, method, t, args.quick, args.time)
                    runs[t].append(r)
                    raw.append(dict(r, case=case, method=method, requested_threads=t))
            base = None
            for t in threads:
                med = {k: statistics.median(r[k] for r in runs[t]) for k in ("rate", "cpu_per_sample", "rss", "estimated")}
                base = base or med
                rows.append((case, method, t, med, base))
                print(f"{case:6s} {method:5s} {t:3d} threads: {med['rate'] / 1e6:7.3f} M native samples/s  "
                      f"{med['cpu_per_sample'] * 1e6:7.3f} us CPU/sample  peak {med['rss'] / 2**20:8.1f} MiB "
                      f"(estimated {med['estimated'] / 2**20:8.1f})  |  x{med['rate'] / base['rate']:.2f} speed, "
                      f"CPU/sample x{med['cpu_per_sample'] / base['cpu_per_sample']:.3f}, "
                      f"RSS x{med['rss'] / base['rss']:.3f}", flush=True)
    if args.json:
        args.json.write_text(json.dumps(raw, indent=1))


def measure(case: str, method: str, threads: int, quick: bool, budget: float = 0.0) -> dict:
    """One render in a child process: native samples per second of render time, CPU time per
    native sample (the child's rusage around the render), the child's peak RSS."""
    scene, rig, defines, spp = CASES[case]
    if quick:
        defines = dict(defines, **QUICK[case])
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, str(scene), rig, json.dumps(defines), str(spp), method,
                          str(threads), str(budget)], capture_output=True, text=True, env=env)
    if out.returncode != 0:
        sys.exit(f"{case} {method} --threads {threads} failed:\n{out.stderr}")
    r = json.loads(out.stdout.strip().splitlines()[-1])
    return {"rate": r["samples"] / r["seconds"], "cpu_per_sample": r["cpu"] / r["samples"], "rss": r["peak"],
            "estimated": r["estimated"], "seconds": r["seconds"], "samples": r["samples"],
            "max_chunk_seconds": r["max_chunk"]}


if __name__ == "__main__":
    main()
