"""Multi-view path tracing on Mitsuba 3 (--backend mitsuba) against path tracing on the same
variant and against the C++ renderer, at equal wall-clock time.

    python bench/bench_gpu.py                          # llvm_ad_rgb (cuda_ad_rgb where a GPU is)
    python bench/bench_gpu.py --variant cuda_ad_rgb --time 10 --res 256

For each scene: a reference by the C++ path tracer (`--ref-spp`, cached as in
bench_mvpt_equal_time.py, whose noise is estimated from its variance and subtracted), then
`--rounds` rounds, interleaved, each rendering every view for `--time` seconds with the backend's
pt, the backend's mvpt and the C++ mvpt (all cores). The first render of each backend method
compiles its kernels and is not timed. Printed per scene: native samples per second and the
median pooled relMSE of each, and the ratios backend pt / backend mvpt (the method's gain on the
variant) and C++ mvpt / backend mvpt (quality per second against the C++ method).
"""
from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

import mvpt  # noqa: E402
from bench_mvpt_equal_time import pooled_relmse, reference  # noqa: E402

SCENES = [  # (file, rig) at --res; the light field's and Cornell box's Phong BSDF is not a Mitsuba 3 plugin
    (ROOT / "scenes" / "glossy-ggx-9.xml", None),
    (ROOT / "scenes" / "glossy-ggx-9.xml", "grid:5x5,spacing=0.1,focus_distance=4.3"),
    (ROOT.parent / "shared" / "scenes" / "m3data-matpreview" / "matpreview.xml", "grid:5x5,spacing=0.05"),
]


def run(path: Path, rig, args) -> dict:
    defines = {"res": str(args.res)}
    scene = mvpt.load_file(path, rig=rig, **({} if "matpreview" in path.name else defines))
    if "matpreview" in path.name:  # (its film size is fixed in the file: a rig's views keep it)
        defines = {}
    ref, noise = reference(path, rig, defines, args.ref_spp, 0, args.cache)
    backend = f"mitsuba:{args.variant}" if args.variant else "mitsuba"
    for method in ("pt", "mvpt"):  # compile the kernels
        mvpt.render(scene, spp=1, method=method, backend=backend)
    rows = {"backend pt": [], "backend mvpt": [], "C++ mvpt": []}
    rates = {k: [] for k in rows}
    for r in range(args.rounds):
        order = list(rows) if r % 2 == 0 else list(reversed(rows))
        for name in order:
            kw = dict(time=args.time, seed=1000 + r)
            if name == "C++ mvpt":
                res = mvpt.render(scene, method="mvpt", **kw)
            else:
                res = mvpt.render(scene, method=name.split()[1], backend=backend, **kw)
            rows[name].append(max(pooled_relmse(res.images, ref) - statistics.mean(
                v for k, v in noise.items() if k != "display"), 1e-12))
            rates[name].append(res.stats["samples"] / res.stats["seconds"])
    med = {k: statistics.median(v) for k, v in rows.items()}
    out = {"scene": path.name + (f"@{rig}" if rig else ""), "views": len(scene.views),
           "relmse": med, "samples_per_second": {k: statistics.median(v) for k, v in rates.items()},
           "gain_on_variant": med["backend pt"] / med["backend mvpt"],
           "vs_cpp_mvpt": med["C++ mvpt"] / med["backend mvpt"]}
    print(f"{out['scene']} ({out['views']} views): relMSE " +
          ", ".join(f"{k} {v:.3e}" for k, v in med.items()) +
          f"; native samples/s " + ", ".join(f"{k} {v / 1e6:.2f} M" for k, v in out["samples_per_second"].items()) +
          f"; backend pt/mvpt {out['gain_on_variant']:.2f}, C++ mvpt / backend mvpt {out['vs_cpp_mvpt']:.2f}",
          flush=True)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variant", default=None, help="cuda_ad_rgb or llvm_ad_rgb (default: cuda where present)")
    ap.add_argument("--time", type=float, default=5.0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / "bench-cache")
    ap.add_argument("--scenes", type=int, default=len(SCENES), help="the first N scenes only")
    args = ap.parse_args(argv)
    for path, rig in SCENES[:args.scenes]:
        if not path.exists():
            print(f"{path}: not here (../shared/scenes), skipped")
            continue
        run(path, rig, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
