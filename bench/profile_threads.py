"""Where CPU time per native sample grows with the thread count: a sampling profile of one
render per thread count, function by function.

    python bench/profile_threads.py record --case lf9x9 --threads 2,16 --out prof/   # the many-core machine
    python bench/profile_threads.py report prof/ --so build/unstripped/_core*.so        # here

`record` renders a case of bench_scaling.py (its scene, rig, resolution and spp) once per
thread count, each in a child process with bench/cpu_sampler.c preloaded (built here with cc):
every thread's CPU time is sampled (one stack per --period µs of the thread's CPU; Linux
delivers at most one per scheduler tick, 4 ms at 250 Hz), between the start and the end of
the render. It writes <case>_<method>_<threads>.bin (+ .maps) and a .json of the render's
native samples and rusage per thread count. `report` resolves each sample's interrupted
address (self time) to a function with addr2line: in the module `_core` against --so (a
build of the same sources linked without stripping, e.g. with -g: the wheel's module is
stripped, and its local functions have no names), elsewhere to the library's name. It prints
each function's CPU time per native sample (samples x period / native samples, with the
period measured as CPU seconds over samples) at every thread count and the ratio of the last
to the first, largest growth first.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from bench_scaling import CASES, QUICK  # noqa: E402

DEPTH = 14
RECORD = struct.Struct("<II" + "Q" * DEPTH)

CHILD = r"""
import ctypes, json, resource, sys
import mvpt
scene_path, rig, defines, spp, method, threads, out, period = sys.argv[1:9]
scene = mvpt.load_file(scene_path, rig=rig or None, **json.loads(defines))
sampler = ctypes.CDLL(None)
before = resource.getrusage(resource.RUSAGE_SELF)
sampler.cpu_sampler_start(out.encode(), int(period))
r = mvpt.render(scene, spp=int(spp), method=method, threads=int(threads), seed=1)
sampler.cpu_sampler_stop()
after = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"samples": r.stats["samples"], "seconds": r.stats["seconds"],
                  "user": after.ru_utime - before.ru_utime, "sys": after.ru_stime - before.ru_stime}))
"""


def build_sampler(folder: Path) -> Path:
    lib = folder / "libcpu_sampler.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", str(HERE / "cpu_sampler.c"), "-o", str(lib), "-ldl", "-lrt"],
                   check=True)
    return lib


def record(args) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scene, rig, defines, spp = CASES[args.case]
    if args.quick:
        defines = dict(defines, **QUICK[args.case])
    with tempfile.TemporaryDirectory() as tmp:
        lib = build_sampler(Path(tmp))
        runs = {}
        for threads in (int(t) for t in args.threads.split(",")):
            name = f"{args.case}_{args.method}_{threads}"
            env = dict(os.environ, LD_PRELOAD=str(lib), OPENBLAS_NUM_THREADS="1")
            p = subprocess.run([sys.executable, "-c", CHILD, str(scene), rig, json.dumps(defines), str(spp),
                                args.method, str(threads), str(out / f"{name}.bin"), str(args.period)],
                               capture_output=True, text=True, env=env)
            if p.returncode != 0:
                sys.exit(f"{name} failed:\n{p.stderr}")
            runs[threads] = json.loads(p.stdout.strip().splitlines()[-1])
            r = runs[threads]
            print(f"{name}: {r['samples'] / r['seconds'] / 1e6:.3f} M native samples/s, "
                  f"{(r['user'] + r['sys']) / r['samples'] * 1e6:.3f} us CPU/sample", flush=True)
        (out / f"{args.case}_{args.method}.json").write_text(json.dumps(runs, indent=1))


def load(path: Path):
    data = path.read_bytes()
    n = struct.unpack_from("<Q", data)[0]
    pcs = [RECORD.unpack_from(data, 8 + i * RECORD.size)[2] for i in range(n)]
    maps = []
    for line in Path(f"{path}.maps").read_text().splitlines():
        f = line.split()
        if len(f) >= 6 and "x" in f[1]:
            lo, hi = (int(x, 16) for x in f[0].split("-"))
            maps.append((lo, hi, int(f[2], 16), f[5]))
    return pcs, maps


def functions(so: str, offsets: set[int]) -> dict[int, str]:
    """addr2line's function of each offset into `so`: the outermost of its inline chain (the
    output is, per address, its line and then a function and a file:line per inlined level)."""
    names, offs = {}, sorted(offsets)
    for i in range(0, len(offs), 5000):
        lines = subprocess.run(["addr2line", "-f", "-i", "-C", "-a", "-e", so] + [hex(o) for o in offs[i:i + 5000]],
                               capture_output=True, text=True, check=True).stdout.splitlines()
        current, function_line = None, True
        for line in lines:
            if line.startswith("0x") and all(c in "0123456789abcdef" for c in line[2:]):
                current, function_line = int(line, 16), True
            else:
                if function_line:
                    names[current] = line
                function_line = not function_line
    return names


def self_times(path: Path, so: str, native: int, cpu: float) -> dict[str, float]:
    pcs, maps = load(path)
    where = []
    for pc in pcs:
        module = next(((name, pc - lo + off) for lo, hi, off, name in maps if lo <= pc < hi), ("?", pc))
        where.append(module)
    names = functions(so, {off for name, off in where if "_core" in name})
    counts = collections.Counter(names.get(off, "??") if "_core" in name else Path(name).name for name, off in where)
    period = cpu / max(len(pcs), 1)  # CPU seconds per sample
    return {k: v * period / native * 1e6 for k, v in counts.items()}


def report(args) -> None:
    folder = Path(args.folder)
    for meta in sorted(folder.glob("*.json")):
        runs = {int(t): r for t, r in json.loads(meta.read_text()).items()}
        table = {t: self_times(folder / f"{meta.stem}_{t}.bin", args.so, r["samples"], r["user"] + r["sys"])
                 for t, r in sorted(runs.items())}
        first, last = min(table), max(table)
        print(f"\n{meta.stem}: us CPU per native sample (self), by thread count")
        print("  ".join(f"{t:>7d}t" for t in table) + "      x  function")
        print("  ".join(f"{sum(v.values()):8.3f}" for v in table.values()) +
              f"  {sum(table[last].values()) / sum(table[first].values()):5.2f}  (all)")
        keys = set().union(*table.values())
        for k in sorted(keys, key=lambda k: -(table[last].get(k, 0) - table[first].get(k, 0)))[:args.top]:
            a, b = table[first].get(k, 0.0), table[last].get(k, 0.0)
            print("  ".join(f"{table[t].get(k, 0.0):8.3f}" for t in table) + f"  {b / a if a else 0:5.2f}  {k[:100]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="render and sample (on the machine measured)")
    rec.add_argument("--case", default="lf9x9", choices=sorted(CASES))
    rec.add_argument("--method", default="mvpt", choices=["pt", "mvpt"])
    rec.add_argument("--threads", default="2,16")
    rec.add_argument("--period", type=int, default=1000, help="µs of a thread's CPU time between samples (< 10^6)")
    rec.add_argument("--out", default="profile")
    rec.add_argument("--quick", action="store_true", help="bench_scaling.py's small films")
    rep = sub.add_parser("report", help="resolve and tabulate a recorded folder")
    rep.add_argument("folder")
    rep.add_argument("--so", required=True, help="the _core module of the same sources, unstripped")
    rep.add_argument("--top", type=int, default=30)
    args = ap.parse_args()
    record(args) if args.command == "record" else report(args)


if __name__ == "__main__":
    main()
