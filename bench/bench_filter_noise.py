"""Noise of one view under the scene's pixel filter: mvpt's path tracing and its multi-view
machinery on that one view (samples uniform in their pixel and the filter's margin,
splatted with the filter, each pass one estimate with a control variate for the sum of the
weights) and Mitsuba 3 `llvm_ad_rgb` (splatted, normalised by the sum of the weights), at
equal samples per pixel.

    python bench/bench_filter_noise.py               # the cases below, 12 seeds of 16 spp
    python bench/bench_filter_noise.py --seeds 8 --spp 8 --cases checker

Each renderer renders --seeds independent images of --spp; the per-pixel variance over the
seeds, divided by (mean² + 0.01) of the pooled mean, is averaged over the image (relative
variance: what relMSE measures once the bias is nil). Printed: each relative variance, the
ratios to Mitsuba's, and mvpt's render seconds summed over the seeds (Mitsuba's are not
comparable: they include its JIT compilation; bench_vs_mitsuba.py times it properly, with
box filters, where the three estimators coincide).

Cases: tests/scenes/filters/checkerboard.xml (sharp edges) with each filter, and two shared
scenes at 128 px, `m3data-matpreview` (gaussian) and `bitterli-staircase2` (tent), read
from ../shared/scenes when present.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "tests" / "python"))

import mitsuba_compare as mc  # noqa: E402
import mvpt  # noqa: E402

CHECKER = ROOT / "tests" / "scenes" / "filters" / "checkerboard.xml"
SHARED = ROOT.parent / "shared" / "scenes"
REAL = [("m3data-matpreview/matpreview.xml", {"width": "128", "height": "128"}),
        ("bitterli-staircase2/scene.xml", {"integrator": "path"})]


def cases(which: str):
    """(name, scene XML, base dir, defines) of each case."""
    if which in ("all", "checker"):
        for f in ("box", "tent", "gaussian", "mitchell", "lanczos"):
            yield f"checkerboard, {f}", CHECKER.read_text(), CHECKER.parent, {"filter": f}
    if which in ("all", "real"):
        for rel, defines in REAL:
            if (SHARED / rel).exists():
                xml, base = mc.prepare_scene(SHARED / rel, defines, max_res=128, box_filter=False)
                yield rel.split("/")[0], xml, base, defines
            else:
                print(f"{rel}: skipped, ../shared/scenes is absent")


def relative_variance(images: list, reference: np.ndarray) -> float:
    return float((np.var(images, axis=0, ddof=1) / (reference**2 + 1e-2)).mean())


def run(name: str, xml: str, base: Path, defines: dict, seeds: int, spp: int) -> None:
    mi = mc._mitsuba("llvm_ad_rgb")
    s_mi = mc.load_mitsuba(xml, defines, base, variant="llvm_ad_rgb")
    images = {"mitsuba": [np.array(mi.render(s_mi, sensor=0, seed=1 + k, spp=spp), np.float64)
                          for k in range(seeds)]}
    s = mc.load_mvpt(xml, defines, base)
    view = s.views[0]["id"]
    seconds = {}
    for method in ("pt", "mvpt"):
        runs = [mvpt.render(s, spp=spp, seed=100 + k, method=method, views=[view]) for k in range(seeds)]
        images[method] = [np.asarray(r.images[view], np.float64) for r in runs]
        seconds[method] = sum(r.stats["seconds"] for r in runs)
    reference = np.mean([np.mean(v, axis=0) for v in images.values()], axis=0)
    rv = {k: relative_variance(v, reference) for k, v in images.items()}
    print(f"{name:24s} relvar Mitsuba {rv['mitsuba']:.4g}  pt {rv['pt']:.4g} (x{rv['pt'] / rv['mitsuba']:.2f})  "
          f"mvpt on one view {rv['mvpt']:.4g} (x{rv['mvpt'] / rv['mitsuba']:.2f})  "
          f"seconds pt {seconds['pt']:.2f}, mvpt {seconds['mvpt']:.2f}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--cases", choices=["all", "checker", "real"], default="all")
    args = ap.parse_args()
    for name, xml, base, defines in cases(args.cases):
        run(name, xml, base, defines, args.seeds, args.spp)


if __name__ == "__main__":
    main()
