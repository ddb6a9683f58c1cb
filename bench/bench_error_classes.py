"""Where multi-view path tracing's error is, and how much sharing could gain on a scene at most.

    python bench/bench_error_classes.py "bench/suite/table-hdri.xml@linear:n=45,baseline=1.8,focus_distance=3.9" \\
        --time 10 --ref-spp 512

Renders the case once with `pt` and once with `mvpt` for --time seconds each (the reference as
bench_mvpt_equal_time.py makes and caches it) and splits each view-pixel into two classes by
what multi-view path tracing did there: **never shared**, where a native sample brought fewer
than 1.5 contributions on average (its first vertex on a purely specular surface or the
environment seen directly: no other view can take it), and **shared**. Per class: its share of
the view-pixels, of each method's relMSE (summed over the class and divided by all the
view-pixels, so the classes add up to the overall relMSE) and of multi-view path tracing's
native samples.

It also prints two bounds on pt / mvpt that no sharing rule can pass while the never-shared
pixels are estimated as path tracing estimates them (one path per sample, at a path-traced
sample's cost), even if the shared pixels cost nothing and had no error. With v_p the
relative variance of one path-traced sample at pixel p (from the reference's variance of the
mean times its spp, over (r^2 + 0.01) as relMSE weighs it) and N the number of view-pixels:
  - with the samples spread evenly over the pixels:  sum_all v_p / sum_never v_p;
  - with each never-shared pixel given the samples that minimise the error (n_p in proportion
    to sqrt(v_p)):  N sum_all v_p / (sum_never sqrt(v_p))^2.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_mvpt_equal_time as eq  # noqa: E402 (the reference and its cache)

import mvpt  # noqa: E402
from mvpt import metrics  # noqa: E402


def pixel_relmse(image, ref) -> np.ndarray:
    """Per-pixel relMSE, the mean over RGB."""
    return metrics.relative_squared_error(image, ref)[..., :3].mean(axis=-1)


def classes(result) -> dict:
    """view id -> boolean map of the never-shared pixels of a multi-view render."""
    never = {}
    for v, contributions in result.contributions.items():
        native = np.asarray(result.sample_count[v], dtype=np.float64)
        per_sample = np.asarray(contributions, dtype=np.float64) / np.maximum(native, 1.0)
        never[v] = per_sample < 1.5
    return never


def one_sample_variance(ref: dict, variance: dict, spp: int) -> dict:
    """view id -> relative variance of one path-traced sample per pixel (mean over RGB)."""
    out = {}
    for v, img in ref.items():
        r = np.asarray(img, dtype=np.float64)[..., :3]
        var = np.asarray(variance[v], dtype=np.float64)
        var = var[..., :3] if var.ndim == 3 else var[..., None]
        out[v] = (spp * var / (r * r + metrics.RELMSE_EPS)).mean(axis=-1)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", help="FILE or FILE@RIG")
    ap.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--time", type=float, default=10.0)
    ap.add_argument("--ref-spp", type=int, default=512)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--cache", type=Path, default=eq.ROOT / "out" / "bench-cache")
    args = ap.parse_args(argv)
    defines = dict(d.split("=", 1) for d in args.define)
    path, rig = eq.split_spec(args.case)
    ref, variance = eq.reference_images(path, rig, defines, args.ref_spp, args.threads, args.cache)
    scene = mvpt.load_file(path, rig=rig, **defines)
    pt = mvpt.render(scene, time=args.time, seed=args.seed, threads=args.threads, method="pt")
    mv = mvpt.render(scene, time=args.time, seed=args.seed, threads=args.threads, method="mvpt")
    if not mv.contributions:
        print("multi-view path tracing path traced this case (nothing to share): no classes")
        return 0
    never = classes(mv)
    views = list(ref)
    n_all = sum(never[v].size for v in views)
    err = {m: {v: pixel_relmse(r.images[v], ref[v]) for v in views} for m, r in (("pt", pt), ("mvpt", mv))}
    native = {v: np.asarray(mv.sample_count[v], dtype=np.float64) for v in views}
    native_all = sum(native[v].sum() for v in views)
    print(f"## {args.case}: {len(views)} views, {args.time:g} s each, seed {args.seed}\n")
    print("| class | view-pixels | relMSE pt | relMSE mvpt | pt / mvpt | mvpt's native samples |")
    print("|---|---|---|---|---|---|")
    for name, pick in (("never shared", lambda m: m), ("shared", lambda m: ~m)):
        mask = {v: pick(never[v]) for v in views}
        count = sum(mask[v].sum() for v in views)
        e = {m: sum(err[m][v][mask[v]].sum() for v in views) / n_all for m in err}
        share = sum(native[v][mask[v]].sum() for v in views) / native_all
        print(f"| {name} | {count / n_all:.1%} | {e['pt']:.3e} | {e['mvpt']:.3e} | "
              f"{e['pt'] / max(e['mvpt'], 1e-300):.2f} | {share:.1%} |")
    e_pt = sum(err["pt"][v].sum() for v in views) / n_all
    e_mv = sum(err["mvpt"][v].sum() for v in views) / n_all
    print(f"| all | 100% | {e_pt:.3e} | {e_mv:.3e} | {e_pt / e_mv:.2f} | 100% |")
    # The bounds, from the reference's variance (see the module doc).
    v1 = one_sample_variance(ref, variance, args.ref_spp)
    total = sum(v1[v].sum() for v in views)
    never_sum = sum(v1[v][never[v]].sum() for v in views)
    never_sqrt = sum(np.sqrt(v1[v][never[v]]).sum() for v in views)
    print(f"\nbounds on pt / mvpt while the never-shared pixels are path traced: {total / never_sum:.2f} with "
          f"samples spread evenly, {n_all * total / never_sqrt ** 2:.2f} with them spread by sqrt(v_p)")
    print(f"pt {pt.stats['samples_per_second'] / 1e6:.3f} M samples/s, mvpt "
          f"{mv.stats['samples_per_second'] / 1e6:.3f} M native samples/s, delta splits "
          f"{mv.stats.get('delta_splits')}, splits {mv.stats.get('splits')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
