"""Throughput of mvpt against Mitsuba 3 (scalar_rgb and llvm_ad_rgb) on the same scenes.

    python bench/bench_vs_mitsuba.py            # full: 256 px, 64 spp, 5 rounds
    python bench/bench_vs_mitsuba.py --quick    # 64 px, 8 spp, 3 rounds (a smoke run)

Every renderer renders the same XML (includes inlined, every rfilter a box, films scaled
so the larger side is --res; cbox-rgb at max_depth 8, the others at their own max_depth,
the same define passed to all) at the same spp. Runs are interleaved, round by round
(mvpt, scalar, llvm, mvpt, scalar, llvm, ...), each with a new seed, so that load changes
on a shared machine hit all renderers alike; the median of the rounds is reported.

Excluded from the timings: scene loading (all renderers load once, before the rounds) and
Mitsuba's LLVM JIT compilation: one untimed warm-up render of llvm_ad_rgb at the same spp
per scene, after which Dr.Jit reuses its cached kernels (a new seed does not recompile;
checked: first render 0.31 s, later ones 0.07-0.09 s on cbox 64 px 16 spp). The llvm
timing includes reading the image back to NumPy (forcing the evaluation). Threads: every
renderer uses all cores.

Throughput = camera paths (pixels × spp) per second. Agreement (mvpt vs Mitsuba
scalar_rgb): the relative image-mean difference per channel and the verdict of the
block t-test of tests/python/mitsuba_compare.py, with Mitsuba's variance estimated from
its independent rounds (scalar and llvm rounds pooled: same estimator, different seeds)
and mvpt's from its own per-pixel variance averaged over rounds.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

# NumPy's BLAS threads spin after each call and would take CPU from the renders being timed.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "python"))
import mitsuba_compare as mc  # noqa: E402
from shared_data import shared_scenes  # noqa: E402

SCENES = [  # (name, path under the shared scenes, defines)
    ("cbox-rgb", "m3data-cbox/cbox-rgb.xml", {"max_depth": 8}),
    ("matpreview", "m3data-matpreview/matpreview.xml", {}),
    ("veach-mis", "bitterli-veach-mis/scene.xml", {"integrator": "path"}),
    # Participating media (volpath), on request: --scenes staircase2 sss
    ("staircase2", "bitterli-staircase2/scene.xml", {}),
    ("sss", "m3data-testsuite/docs/scenes/medium_homogeneous_sss.xml", {}),
]
DEFAULT_SCENES = ["cbox-rgb", "matpreview", "veach-mis"]


def shared_dir(arg: str | None) -> Path:
    """--shared (the scenes folder), else the tests' resolver (MVPT_SHARED or ../shared)."""
    path = Path(arg) if arg else shared_scenes()
    if not path.is_dir():
        sys.exit(f"shared scenes not found at {path}: pass --shared or set MVPT_SHARED")
    return path.resolve()


class Runner:
    """One renderer on one prepared scene: load once, then timed renders with new seeds."""

    def __init__(self, kind: str, xml: str, base: Path, defines: dict, spp: int):
        self.kind, self.spp, self.times, self.images, self.vars, self.error = kind, spp, [], [], [], None
        try:
            if kind == "mvpt":
                self.scene = mc.load_mvpt(xml, defines, base)
            else:
                self.scene = mc.load_mitsuba(xml, defines, base, variant=kind)
                if kind.startswith("llvm"):
                    self.render(seed=10**6, record=False)  # JIT warm-up, untimed
        except Exception as e:  # unknown plugin etc.: report, keep benchmarking the others
            self.error = f"{type(e).__name__}: {(str(e).splitlines() or [repr(e)])[0][:90]}"

    def render(self, seed: int, record: bool = True):
        if self.error:
            return
        if self.kind == "mvpt":
            import mvpt
            t0 = time.perf_counter()
            r = mvpt.render(self.scene, spp=self.spp, seed=seed)
            dt = time.perf_counter() - t0
            vid = r.view_ids[0]
            img, var = np.asarray(r.images[vid], np.float64), np.asarray(r.variance[vid], np.float64)
        else:
            import mitsuba as mi
            mi.set_variant(self.kind)
            t0 = time.perf_counter()
            img = np.array(mi.render(self.scene, spp=self.spp, seed=seed), dtype=np.float64)[..., :3]
            dt = time.perf_counter() - t0
            var = None
        if record:
            self.times.append(dt)
            self.images.append(img)
            if var is not None:
                self.vars.append(var)

    def paths_per_second(self) -> float:
        if not self.times:
            return float("nan")
        h, w, _ = self.images[0].shape
        return h * w * self.spp / statistics.median(self.times)


def agreement(m: Runner, refs: list) -> str:
    """'rel. mean diff R/G/B; verdict' of mvpt against the pooled Mitsuba rounds."""
    imgs = [i for r in refs for i in r.images]
    if m.error or len(imgs) < 2 or not m.images:
        return "n/a"
    k = len(m.images)
    a = mc.ImageEstimate(np.mean(m.images, 0), np.mean(m.vars, 0) / k,
                         np.full(m.images[0].shape, float(k * (m.spp - 1))))
    b = mc.estimate_from_seeds(imgs)
    res = mc.compare_estimates("bench", [(0, "0", a, b)])
    v = res.views[0]
    rel = "/".join(f"{d*100:+.2f}" if t else "n/a" for d, t in zip(v.mean_rel_diff, v.mean_tested))
    return f"{rel} % ; {'pass' if res.passed else 'FAIL'} (min p {float(v.p.min()):.1e})"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="64 px, 8 spp, 3 rounds")
    ap.add_argument("--res", type=int, default=256, help="larger film side (default 256)")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--scenes", nargs="*", default=DEFAULT_SCENES, help=f"of {[s[0] for s in SCENES]}")
    ap.add_argument("--renderers", nargs="*", default=["mvpt", "scalar_rgb", "llvm_ad_rgb"])
    ap.add_argument("--shared", default=None, help="the shared scenes folder")
    args = ap.parse_args(argv)
    if args.quick:
        args.res, args.spp, args.rounds = 64, 8, 3
    root = shared_dir(args.shared)
    rows = []
    for name, rel, defines in SCENES:
        if name not in args.scenes:
            continue
        xml, base = mc.prepare_scene(root / rel, defines, max_res=args.res, box_filter=True)
        runners = [Runner(k, xml, base, defines, args.spp) for k in args.renderers]
        for rnd in range(args.rounds):
            for r in runners:
                r.render(seed=rnd + 1)
        by = {r.kind: r for r in runners}
        shape = next((r.images[0].shape for r in runners if r.images), (0, 0, 3))
        pps = {k: r.paths_per_second() for k, r in by.items()}
        m = by.get("mvpt")
        mi_runs = [r for k, r in by.items() if k != "mvpt" and not r.error]
        rows.append((name, f"{shape[1]}x{shape[0]}", pps, by, agreement(m, mi_runs) if m else "n/a"))
        print(f"done {name}", file=sys.stderr)

    kinds = args.renderers
    print(f"\n{args.spp} spp, {args.rounds} interleaved rounds, median camera paths per second (M/s)\n")
    head = ["scene", "size"] + [f"{k} M/s" for k in kinds]
    head += [f"mvpt/{k}" for k in kinds if k != "mvpt" and "mvpt" in kinds]
    head += ["mvpt − Mitsuba mean (R/G/B) ; block t-test"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for name, size, pps, by, agree in rows:
        cells = [name, size]
        for k in kinds:
            cells.append(by[k].error and f"— ({by[k].error})" or f"{pps[k]/1e6:.3f}")
        for k in kinds:
            if k != "mvpt" and "mvpt" in kinds:
                ok = not by["mvpt"].error and not by[k].error
                cells.append(f"{pps['mvpt']/pps[k]:.2f}" if ok else "—")
        cells.append(agree)
        print("| " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
