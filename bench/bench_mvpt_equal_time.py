"""Multi-view path tracing against independent path tracing at equal wall-clock time.

    python bench/bench_mvpt_equal_time.py                 # 9-view glossy Cornell box + 5x5 light field
    python bench/bench_mvpt_equal_time.py --quick         # small smoke run
    python bench/bench_mvpt_equal_time.py --scenes scenes/stereo.xml --time 20
    python bench/bench_mvpt_equal_time.py --suite real     # GGX scenes, grids and a real scene with rigs
    python bench/bench_mvpt_equal_time.py --suite broad --time 10 --rounds 2 --ref-spp 512

A scene is a file, or FILE@RIG for a rig around its first camera (the CLI's --rig, e.g.
`../shared/scenes/m3data-matpreview/matpreview.xml@grid:5x5,spacing=0.05`). `--suite real` runs
the cases that the gain is judged on, each at 128^2: 9 views of GGX metals and rough plastic
in a row (scenes/glossy-ggx-9.xml), a 9x9 grid of the same, the 5x5 light field of the Phong
still life, and a 5x5 grid around the material-preview scene (an environment map, textures,
a fine mesh; skipped without ../shared/scenes). `--suite display` runs the renders users make
for displays and shots on the HDRI table-top of bench/suite; `--suite broad` runs those and
eleven more of the classes users render (wide-cone rigs of 25 and 100 views with HDRI and
glass, thin-lens views, shots with overlapping and short shutters, closed glossy rooms through
rows and grids, real scenes of ../shared/scenes through grids) and ends with one line per case,
worst first (`--summary FILE` writes them as JSON), with what `--method auto` picks there and
what that costs against the better of the two methods.

For each scene: a reference by independent path tracing (`--ref-spp` samples per pixel,
rendered once and cached under --cache as .npz), then `--rounds` rounds that render the
same views with `pt` and with `mvpt` for `--time` seconds each, interleaved (pt, mvpt,
mvpt, pt, ...) with a new seed per round, so that load changes of a shared machine hit
both methods alike. Per view and overall (pooled over views) the script prints the median
relMSE over rounds (mean over pixels and channels of (x - r)^2 / (r^2 + 0.01), as
`mvpt compare`), the ratio PT/MVPT, and the time MVPT needs to reach PT's relMSE at --time,
T * relMSE_mvpt / relMSE_pt (both estimators are unbiased, so relMSE falls as 1/time).
The reference's own noise adds its variance to every relMSE; it is estimated from the
reference's per-pixel variance of the mean and subtracted in the "corrected" columns
(the raw ratio understates the gain). It also prints where MVPT's time goes: native
samples/s, rays per native sample, mean sharing |S|.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import sys
import time
from pathlib import Path

# NumPy's BLAS threads spin after each call and would take CPU from the renders being timed.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

import mvpt
from mvpt import api, metrics

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SCENES = [str(ROOT / "scenes" / "cornell-glossy-9.xml"), str(ROOT / "scenes" / "lightfield-5x5.xml")]
SHARED = ROOT.parent / "shared" / "scenes"
# (scene spec, defines) of --suite real
REAL_SUITE = [
    (str(ROOT / "scenes" / "glossy-ggx-9.xml"), {"res": "128"}),
    (str(ROOT / "scenes" / "glossy-ggx-9.xml") + "@grid:9x9,spacing=0.1,focus_distance=4.3", {"res": "128"}),
    (str(ROOT / "scenes" / "lightfield-5x5.xml"), {"res": "128"}),
    (str(SHARED / "m3data-matpreview" / "matpreview.xml") + "@grid:5x5,spacing=0.05",
     {"width": "128", "height": "128"}),
]
SUITE = ROOT / "bench" / "suite"
# (scene spec, defines) of --suite display: the renders users make for displays and shots, on
# the HDRI table-top with glass (bench/suite; skipped without ../shared/scenes): a 45-view
# Looking-Glass-like row over +-13 degrees at the focal plane, and a 24-frame camera move with a
# rolling sphere and without.
DISPLAY_SUITE = [
    (str(SUITE / "table-hdri.xml") + "@linear:n=45,baseline=1.8,focus_distance=3.9", {}),
    (str(SUITE / "table-shot.xml"), {"moving": "1"}),
    (str(SUITE / "table-shot.xml"), {"moving": "0"}),
]
# (scene spec, defines) of --suite broad: the display suite and scenes of the same classes that
# the defaults were not tuned on.
BITTERLI = {"integrator": "path", "resx": "128", "resy": "128"}
BROAD_SUITE = DISPLAY_SUITE + [
    (str(SUITE / "table-hdri.xml") + "@linear:n=100,baseline=4,focus_distance=3.9", {"width": "60", "height": "80"}),
    (str(SUITE / "table-hdri.xml") + "@grid:5x5,spacing=0.3,focus_distance=3.9", {"width": "72", "height": "96"}),
    (str(SUITE / "table-lens.xml") + "@linear:n=9,baseline=0.8,focus_distance=3.9", {}),
    (str(SUITE / "table-shot.xml"), {"moving": "1", "shutter": "2"}),
    (str(SUITE / "table-shot.xml"), {"moving": "0", "shutter": "0.5"}),
    (str(ROOT / "scenes" / "cornell-glossy-9.xml"), {"res": "128"}),
    (str(ROOT / "scenes" / "cornell-glossy-9.xml") + "@grid:5x5,spacing=0.1,focus_distance=3.9", {"res": "128"}),
    (str(SHARED / "m3data-matpreview" / "matpreview.xml") + "@grid:5x5,spacing=0.05",
     {"width": "128", "height": "128"}),
    (str(SHARED / "bitterli-staircase2" / "scene.xml") + "@grid:3x3,spacing=0.05", BITTERLI),
    (str(SHARED / "bitterli-cornell-box" / "scene.xml") + "@grid:5x5,spacing=0.05", BITTERLI),
    (str(SHARED / "bitterli-veach-mis" / "scene.xml") + "@grid:3x3,spacing=0.05", BITTERLI),
]
SUITES = {"real": REAL_SUITE, "display": DISPLAY_SUITE, "broad": BROAD_SUITE}


def split_spec(spec: str) -> tuple:
    """(scene path, rig or None) of FILE or FILE@RIG."""
    path, _, rig = str(spec).partition("@")
    return Path(path), rig or None


def reference_images(scene_path: Path, rig, defines: dict, spp: int, threads: int, cache: Path) -> tuple:
    """Per-view reference images and their variance of the mean, rendered once and cached."""
    # The scene file's bytes, not its time stamp: a fresh copy of the same scene keeps its reference.
    key = hashlib.sha1(f"{scene_path.resolve()}|{rig}|{sorted(defines.items())}|{spp}|".encode()
                       + hashlib.sha1(scene_path.read_bytes()).digest()).hexdigest()[:12]
    path = cache / f"ref_{scene_path.stem}_{key}.npz"
    if not path.exists():
        print(f"  reference: {spp} spp of path tracing (cached in {path})", flush=True)
        t0 = time.time()
        scene = mvpt.load_file(scene_path, rig=rig, **defines)
        r = mvpt.render(scene, spp=spp, seed=12345, threads=threads, method="pt")
        data = {f"img:{v}": img for v, img in r.images.items()}
        data.update({f"var:{v}": var for v, var in r.variance.items()})
        cache.mkdir(parents=True, exist_ok=True)
        np.savez(path, **data)
        print(f"  reference done in {time.time() - t0:.0f} s", flush=True)
    data = np.load(path)
    images = {k[4:]: data[k] for k in data.files if k.startswith("img:")}
    variance = {k[4:]: data[k] for k in data.files if k.startswith("var:")}
    return images, variance


def reference(scene_path: Path, rig, defines: dict, spp: int, threads: int, cache: Path) -> tuple:
    """Per-view reference images and the relMSE their own noise adds (from their variance)."""
    images, variance = reference_images(scene_path, rig, defines, spp, threads, cache)
    # Expected relMSE contributed by the reference's noise: mean of var / (r^2 + eps).
    noise = {v: float(np.mean(var / (images[v].astype(np.float64) ** 2 + metrics.RELMSE_EPS)))
             for v, var in variance.items()}
    # The same for what a display shows (views blended with their neighbours along the row).
    noise["display"] = metrics.display_relmse(images, images, variance)[1]
    return images, noise


def pooled_relmse(images: dict, ref: dict) -> float:
    num = sum(metrics.relative_squared_error(images[v], ref[v]).sum() for v in ref)
    den = sum(np.asarray(ref[v]).size for v in ref)
    return float(num / den)


def run_case(spec: str, defines: dict, args) -> dict:
    """Renders one case's rounds, prints its table and returns its summary line."""
    scene_path, rig = split_spec(spec)
    # (the shared scenes' files are mostly scene.xml: their folder names them)
    name = scene_path.parent.name if scene_path.stem == "scene" else scene_path.name
    label = f"{name}{'@' + rig if rig else ''}{''.join(f' {k}={v}' for k, v in defines.items())}"
    print(f"\n## {scene_path.name}{' with rig ' + rig if rig else ''} "
          f"({', '.join(f'{k}={v}' for k, v in defines.items()) or 'defaults'}), "
          f"{args.time:g} s per method, {args.rounds} rounds", flush=True)
    ref, ref_noise = reference(scene_path, rig, defines, args.ref_spp, args.threads, args.cache)
    scene = mvpt.load_file(scene_path, rig=rig, **defines)
    auto = api.choose_method(scene, [], 1000, args.threads)  # what --method auto picks (the first round's seed)
    views = list(ref)
    err = {"pt": [], "mvpt": []}
    stats = {"pt": [], "mvpt": []}
    for rnd in range(args.rounds):
        order = ("pt", "mvpt") if rnd % 2 == 0 else ("mvpt", "pt")
        for method in order:
            splits = args.splits if method == "mvpt" else None
            r = mvpt.render(scene, time=args.time, seed=1000 + rnd, threads=args.threads, method=method,
                            splits=splits)
            per_view = {v: metrics.relmse(r.images[v], ref[v]) for v in views}
            per_view["overall"] = pooled_relmse(r.images, ref)
            per_view["display"] = metrics.display_relmse(r.images, ref)[0]
            err[method].append(per_view)
            stats[method].append(r.stats)
            print(f"  round {rnd + 1} {method:4s}: {r.stats['seconds']:.1f} s, {r.stats['passes']} passes, "
                  f"relMSE {per_view['overall']:.3e}", flush=True)

    rows = views + ["overall", "display"]
    med = {m: {v: statistics.median(e[v] for e in err[m]) for v in rows} for m in err}
    npx = {v: np.asarray(ref[v]).size for v in views}
    ref_noise["overall"] = sum(ref_noise[v] * npx[v] for v in views) / sum(npx.values())
    ref_all = ref_noise["overall"]
    corrected = {}
    print("\n| view | relMSE pt | relMSE mvpt | pt / mvpt | corrected pt / mvpt | mvpt time to pt's relMSE |")
    print("|---|---|---|---|---|---|")
    for v in rows:
        ratio = med["pt"][v] / med["mvpt"][v]
        pt_c, mv_c = med["pt"][v] - ref_noise[v], med["mvpt"][v] - ref_noise[v]
        corrected[v] = pt_c / mv_c if mv_c > 0 else float("inf")
        print(f"| {v} | {med['pt'][v]:.3e} | {med['mvpt'][v]:.3e} | {ratio:.2f} | {corrected[v]:.2f} | "
              f"{args.time / corrected[v]:.1f} s |")
    mv = stats["mvpt"][-1].get("multiview")
    pt_rate = statistics.median(s["samples_per_second"] for s in stats["pt"])
    mv_rate = statistics.median(s["samples_per_second"] for s in stats["mvpt"])
    shared = (f"mvpt splits {[s.get('splits') for s in stats['mvpt']]}, mean |S| {mv['mean_sharing']:.2f}, "
              f"{mv['rays_per_native_sample']:.1f} rays per native sample, rejected shifts "
              f"{ {k: round(100 * n / max(1, mv['shifts_tried']), 1) for k, n in mv['rejected'].items()} } %"
              if mv else "mvpt path traced (nothing to share)")
    print(f"\nreference noise adds {ref_all:.2e} to every relMSE ({100 * ref_all / med['mvpt']['overall']:.0f}% of "
          f"mvpt's); pt {pt_rate / 1e6:.3f} M samples/s, mvpt {mv_rate / 1e6:.3f} M native samples/s "
          f"(cost ratio {pt_rate / mv_rate:.2f}); {shared}")
    own = med["mvpt"]["overall"] - ref_all
    noisy = not own > 0 or ref_all > 0.1 * own
    if noisy:
        print(f"WARNING: the reference's own noise is {'more than' if not own > 0 else f'{ref_all / own:.0%} of'} "
              f"mvpt's error: too noisy to judge the gain (raise --ref-spp)")
    d_ratio = med["pt"]["display"] / med["mvpt"]["display"]
    print(f"--method auto: {auto['method']} ({auto['reason']})")
    return {"auto": auto["method"], "predicted": auto["predicted_gain"], "case": label, "views": len(views), "pt_over_mvpt": corrected["overall"],
            "raw": med["pt"]["overall"] / med["mvpt"]["overall"], "display": corrected["display"],
            "display_raw": d_ratio, "reference_noise_share": ref_all / med["mvpt"]["overall"],
            "cost_ratio": pt_rate / mv_rate, "mean_sharing": mv["mean_sharing"] if mv else 1.0,
            "splits": [s.get("splits") for s in stats["mvpt"]], "methods": [s.get("method") for s in stats["mvpt"]]}


def auto_share(line: dict, key: str) -> float:
    """The better method's relMSE over that of the one --method auto picked (1: it picked the
    better), from a summary line's pt / mvpt under `key`."""
    gain = line[key]
    return min(1.0, gain) if line["auto"] == "mvpt" else min(1.0, 1.0 / gain) if gain > 0 else 1.0


def print_summary(lines: list) -> None:
    """One line per case, worst (lowest pt / mvpt) first, with what --method auto picks."""
    print("\n## Summary, worst first (pt / mvpt: relMSE ratio, the reference's noise subtracted; raw in "
          "parentheses; auto: its pick, its pilot's predicted pt / mvpt, and the better method's relMSE over "
          "its pick's, per view and as a display shows it)\n")
    print("| case | views | pt / mvpt | as a display shows it | native sample's cost (pt samples) | mean abs(S) "
          "| auto (predicted) | better / auto |")
    print("|---|---|---|---|---|---|---|---|")
    for s in sorted(lines, key=lambda s: s["pt_over_mvpt"]):
        predicted = f"{s['predicted']:.2f}" if s["predicted"] else "-"
        print(f"| {s['case']} | {s['views']} | {s['pt_over_mvpt']:.2f} ({s['raw']:.2f}) | {s['display']:.2f} "
              f"({s['display_raw']:.2f}) | {s['cost_ratio']:.2f} | {s['mean_sharing']:.1f} | {s['auto']} "
              f"({predicted}) | {auto_share(s, 'pt_over_mvpt'):.2f}, {auto_share(s, 'display'):.2f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="*", default=None, help="FILE or FILE@RIG (default: the Cornell box and "
                    "the light field)")
    ap.add_argument("--suite", choices=sorted(SUITES), help="the cases the gain is judged on (see the module doc)")
    ap.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--time", type=float, default=20.0, help="seconds per method and round")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--splits", type=lambda t: t if t == "auto" else int(t), default=None,
                    help="mvpt's splits of the shared vertex: 1-64 or auto (default: the scene's)")
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / "bench-cache")
    ap.add_argument("--summary", type=Path, help="write the summary lines as JSON")
    ap.add_argument("--quick", action="store_true", help="res 32, 2 s, 2 rounds, 512-spp reference")
    args = ap.parse_args(argv)
    given = dict(d.split("=", 1) for d in args.define)
    if args.quick:
        args.time, args.rounds, args.ref_spp = 2.0, 2, 512
    cases = SUITES.get(args.suite) or [(s, {}) for s in (args.scenes or DEFAULT_SCENES)]
    lines = []
    for spec, case_defines in cases:
        scene_path, _ = split_spec(spec)
        if not scene_path.is_file():
            print(f"\n## {scene_path.name}: skipped ({scene_path} is not there)")
            continue
        defines = dict(case_defines, **given)
        if args.quick:
            defines.update({k: "32" for k in ("res", "width", "height", "resx", "resy") if k in defines}
                           or {"res": "32"})
        lines.append(run_case(spec, defines, args))
        if args.summary:
            args.summary.write_text(json.dumps(lines, indent=1))
    if len(lines) > 1:
        print_summary(lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
