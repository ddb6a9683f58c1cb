"""Statistical image comparison of mvpt against Mitsuba 3 (``scalar_rgb``).

One scene (an XML file or string, with ``-D``-style defines) is rendered by both
renderers, every sensor separately, and two tests are run per view:

(a) **Image mean**, per channel: the relative difference of the two image means must be
    within ``mean_tol`` (1 %) *up to statistical noise*: a channel fails when
    ``|Δ| > mean_tol·|mean_ref| + z_crit·se(Δ)``, with ``se`` from the variance
    estimates below and ``z_crit`` Šidák-corrected over all (view, channel) mean tests.
    A plain ``|Δ| ≤ 1 %`` would be flaky whenever the standard error of the image mean is
    not far below 1 %, which at test resolutions and sample counts it often is not; the
    noise allowance is reported (``mean_se_rel``), so a test can also assert that the
    resolution of the check is good enough. Channels without meaningful energy (mean
    below ``1e-3`` of the largest channel mean of the view, or below ``1e-6``) are not
    mean-tested; the block test still covers them.

(b) **Per-block z-test** on 8×8 pixel blocks (edge blocks are smaller), per channel:
    ``t = (m_a − m_b) / sqrt(V_a + V_b)`` where ``m`` is the block mean and ``V`` the
    variance of that block mean. The p-value comes from Student's t with the
    Welch–Satterthwaite degrees of freedom (below), and the per-test level is Šidák
    corrected, ``1 − (1 − α)^(1/N)``, over all N = blocks × 3 channels × views, for an
    overall false-alarm rate α = 0.01 (channels are positively correlated, which makes
    Šidák conservative, not flaky). Blocks whose variance is zero on both sides, or whose
    standard error is below a tenth of float32 accumulation noise (background, directly seen
    constant emitters), must agree exactly (relative 1e-5, that noise).

Variance estimates
------------------
*mvpt* returns, per pixel, the variance of the pixel mean from the sample second moment
(``RenderResult.variance``) with ``spp − 1`` degrees of freedom. With Owen-scrambled Sobol
samplers this over-estimates the true variance (conservative).

*Mitsuba* in ``scalar_rgb`` cannot give a per-pixel RGB variance in one render: its
``moment`` integrator works (checked with 3.9.1) but records the moments of the **XYZ**
sample values, and the RGB variance needs the XYZ cross-moments, which it does not
store. The harness therefore renders ``K`` independent seeds (small consecutive integers:
see SEED_BASE for why strides would repeat streams) of ``S`` samples each and uses, per pixel, the sample
variance of the K seed images divided by K (``K − 1`` degrees of freedom). A per-pixel
variance from K = 8 values is poor, but the block variance ``V = Σ v_p / n²`` pools
n = 64 independent pixels (both renderers sample pixels independently), so its
Welch–Satterthwaite degrees of freedom ``ν = V² / Σ (v_p/n²)²/d_p`` are up to
64·(K − 1) for a uniform block and smaller where a few pixels dominate; the t
distribution accounts for that honestly instead of trusting a normal approximation.

Heavy tails (fireflies): a rare large sample inflates both the mean difference and the
variance estimate of the side that drew it, so ``t`` stays O(1); the dangerous case is
the *other* side under-estimating its variance because it drew no rare sample. Each
Mitsuba seed image averages S ≥ 16 samples per pixel and the block pools 64 pixels, so the
quantities entering the test are averages of ≥ 64·S samples; test scenes keep spp such
that blocks see hundreds of samples per pixel at most 64×64 resolution, and scenes with
caustics through smooth interfaces get twice that. Calibration is itself tested
(test_vs_mitsuba_features.py): the false-alarm rate on synthetic exponential and
log-normal data with these estimators stays at ≈ α, and a 4 % brighter light in a
real render is detected. All pixel statistics assume each sample lands in one pixel:
use box filters (`prepare_scene` rewrites filters and film sizes in memory). Reference
images (Mitsuba's test suite ``refs/*_ref_rgb.exr`` with per-sample variance
``*_rgb_var.exr``) are not used for the block test: they deviate from Mitsuba 3.9.1 itself
(a constant emitter of radiance 1 is stored as R = 1.0011; dark blocks of instancing/
differ by 15–30 %, measured with this module). Against them `compare_to_reference` applies
the rule they were made for (Mitsuba's ``test_renders.py``: per-pixel z with the reference
variance floored at 1e-4, Šidák over pixels, ≥ 99.75 % of pixels passing) plus test (a).

CLI: ``python tests/python/mitsuba_compare.py scene.xml -D integrator=path --spp 256
--diff out/`` compares one scene by hand and writes ``out/<view>_diff.exr`` (mvpt |
Mitsuba | signed difference | |t| per pixel block, side by side).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

import numpy as np
from scipy import stats

#: Mitsuba seed of render k of sensor i: 1 + SEED_BASE·seed + i·K + k (small consecutive
#: integers). scalar_rgb seeds pixel p of a render with seed·W·H + p (uint32, see its
#: SamplingIntegrator::render), so large or power-of-two strides wrap around and repeat
#: streams (seeds 2^21 and 10·2^20 give identical images); consecutive seeds never give a
#: pixel the same stream twice.
SEED_BASE = 1000
#: Samples per pixel behind Mitsuba's test-suite reference images.
REF_SPP = 32000
#: Linear sRGB → CIE XYZ (D65), the map of Mitsuba's Bitmap conversion.
RGB_TO_XYZ = np.array([[0.412453, 0.357580, 0.180423],
                       [0.212671, 0.715160, 0.072169],
                       [0.019334, 0.119193, 0.950227]])
#: Fraction of pixels that must pass in Mitsuba's test-suite criterion (test_renders.py).
REF_PASS_FRACTION = 0.9975


# --------------------------------------------------------------------------------------
# Image statistics: a mean image with the variance of each pixel mean and its dof
# --------------------------------------------------------------------------------------

@dataclass
class ImageEstimate:
    """Per-pixel mean, variance of that mean, and degrees of freedom of the variance."""

    mean: np.ndarray            # (H, W, 3) float64
    var: np.ndarray             # (H, W, 3) variance of the pixel mean
    dof: np.ndarray             # (H, W, 3) degrees of freedom of `var` (inf: exact)
    label: str = ""
    seconds: float = 0.0
    samples: int = 0


def estimate_from_seeds(images: Sequence[np.ndarray], label: str = "") -> ImageEstimate:
    """Mean of K independent seed images; per-pixel variance of the mean with K−1 dof."""
    stack = np.stack([np.asarray(i, dtype=np.float64)[..., :3] for i in images])
    k = stack.shape[0]
    if k < 2:
        raise ValueError("at least two independent seeds are needed to estimate a variance")
    mean = stack.mean(axis=0)
    var = stack.var(axis=0, ddof=1) / k
    return ImageEstimate(mean, var, np.full(mean.shape, float(k - 1)), label)


def block_estimate_from_seeds(images: Sequence[np.ndarray], block: int, label: str = "") -> ImageEstimate:
    """Means over block×block tiles (edge tiles smaller) of K independent seed images, each
    image averaged over its tiles before the spread is taken: exact where neighbouring pixels
    are correlated (a sample splatted into every pixel its filter reaches). Compare such
    estimates with block=1."""
    n = _block_sums(np.ones(np.asarray(images[0]).shape[:2] + (1,)), block)
    return estimate_from_seeds([_block_sums(np.asarray(i, dtype=np.float64)[..., :3], block) / n for i in images],
                               label)


def _block_sums(a: np.ndarray, block: int) -> np.ndarray:
    """Sum over block×block tiles (edge tiles smaller) of an (H, W, C) array."""
    h, w, c = a.shape
    hb, wb = -(-h // block), -(-w // block)
    pad = np.zeros((hb * block, wb * block, c), dtype=np.float64)
    pad[:h, :w] = a
    return pad.reshape(hb, block, wb, block, c).sum(axis=(1, 3))


@dataclass
class BlockStats:
    """Per-block (mean, variance of mean, Satterthwaite dof) of one image estimate."""

    mean: np.ndarray
    var: np.ndarray
    dof: np.ndarray
    count: np.ndarray


def block_stats(e: ImageEstimate, block: int) -> BlockStats:
    """Pool pixels into blocks: mean, V = Σv/n², ν = V² / Σ((v/n²)²/d) (Welch–Satterthwaite)."""
    h, w, _ = e.mean.shape
    n = _block_sums(np.ones((h, w, 1)), block)
    mean = _block_sums(e.mean, block) / n
    var = _block_sums(e.var, block) / n**2
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(np.isinf(e.dof), 0.0, e.var**2 / np.maximum(e.dof, 1e-300))
        denom = _block_sums(d, block) / n**4
        dof = np.where(denom > 0, var**2 / denom, np.inf)
    return BlockStats(mean, var, dof, np.broadcast_to(n, mean.shape))


def welch_p_values(a: BlockStats, b: BlockStats, exact_rtol: float = 1e-5):
    """Two-sided p-values of the block t statistics; zero-variance blocks must match exactly."""
    v = a.var + b.var
    diff = a.mean - b.mean
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(v > 0, diff / np.sqrt(v), 0.0)
        inv_a = np.where(np.isfinite(a.dof) & (a.var > 0), a.var**2 / a.dof, 0.0)
        inv_b = np.where(np.isfinite(b.dof) & (b.var > 0), b.var**2 / b.dof, 0.0)
        nu = np.where(inv_a + inv_b > 0, v**2 / (inv_a + inv_b), np.inf)
    nu = np.maximum(nu, 1.0)
    p = np.where(np.isinf(nu), 2.0 * stats.norm.sf(np.abs(t)), 2.0 * stats.t.sf(np.abs(t), np.minimum(nu, 1e12)))
    # Blocks whose standard error is below float resolution (a constant background whose
    # variance is only accumulation rounding) are held to the exact rule instead.
    tol = exact_rtol * np.maximum(np.abs(a.mean), np.abs(b.mean)) + 1e-7
    exact = v <= (0.1 * tol) ** 2
    mismatch = exact & (np.abs(diff) > tol)
    p = np.where(exact, np.where(mismatch, 0.0, 1.0), p)
    return t, nu, p, mismatch


def sidak(alpha: float, n: int) -> float:
    """Per-test level for an overall false-alarm rate `alpha` over `n` independent tests."""
    return -math.expm1(math.log1p(-alpha) / max(1, n))


# --------------------------------------------------------------------------------------
# Comparison result
# --------------------------------------------------------------------------------------

@dataclass
class ViewComparison:
    """Both tests for one view."""

    index: int
    view_id: str
    shape: tuple
    mean_mvpt: np.ndarray
    mean_ref: np.ndarray
    mean_rel_diff: np.ndarray      # per channel, nan where not tested
    mean_se_rel: np.ndarray        # standard error of the relative difference
    mean_tested: np.ndarray        # bool per channel
    mean_ok: np.ndarray            # bool per channel
    t: np.ndarray                  # (hb, wb, 3)
    nu: np.ndarray
    p: np.ndarray
    exact_mismatch: np.ndarray
    block_mean_a: np.ndarray
    block_mean_b: np.ndarray
    a: ImageEstimate = None
    b: ImageEstimate = None


@dataclass
class CompareResult:
    """Outcome over all views; `passed` is both tests on every view; `message` explains."""

    name: str
    views: list = field(default_factory=list)
    alpha: float = 0.01
    block: int = 8
    level_block: float = 0.0       # Šidák-corrected per-block level
    level_mean: float = 0.0        # Šidák-corrected per-channel level of the mean test
    mean_tol: float = 0.01
    seconds: dict = field(default_factory=dict)

    @property
    def n_block_tests(self) -> int:
        return int(sum(v.p.size for v in self.views))

    @property
    def block_failures(self) -> list:
        out = []
        for v in self.views:
            for (by, bx, c) in zip(*np.nonzero(v.p < self.level_block)):
                out.append((float(v.p[by, bx, c]), v, int(by), int(bx), int(c)))
        out.sort(key=lambda r: r[0])
        return out

    @property
    def mean_failures(self) -> list:
        return [(v, c) for v in self.views for c in range(3) if v.mean_tested[c] and not v.mean_ok[c]]

    @property
    def passed(self) -> bool:
        return not self.block_failures and not self.mean_failures

    @property
    def max_mean_se_rel(self) -> float:
        """Largest standard error of a tested relative mean difference (resolution of test a)."""
        s = [float(v.mean_se_rel[c]) for v in self.views for c in range(3) if v.mean_tested[c]]
        return max(s) if s else 0.0

    def summary(self) -> str:
        ch = "RGB"
        lines = [f"{self.name}: {'PASS' if self.passed else 'FAIL'} — {len(self.views)} view(s), "
                 f"{self.n_block_tests} block tests at Šidák level {self.level_block:.2e} (α={self.alpha})"]
        for v in self.views:
            rel = ", ".join(f"{ch[c]} {v.mean_rel_diff[c]*100:+.2f}%±{v.mean_se_rel[c]*100:.2f}"
                            if v.mean_tested[c] else f"{ch[c]} n/a" for c in range(3))
            nfail = int((v.p < self.level_block).sum())
            lines.append(f"  view {v.index} '{v.view_id}' {v.shape[1]}x{v.shape[0]}: mean rel diff [{rel}]"
                         f"{' MEAN FAIL' if not all(v.mean_ok[c] or not v.mean_tested[c] for c in range(3)) else ''}; "
                         f"min p {float(v.p.min()):.2e}; {nfail} failing block(s)")
        for v, c in self.mean_failures:
            lines.append(f"  mean test failed: view {v.index} '{v.view_id}' channel {ch[c]}: "
                         f"mvpt {v.mean_mvpt[c]:.6g} vs ref {v.mean_ref[c]:.6g} "
                         f"({v.mean_rel_diff[c]*100:+.3f}%, tolerance {self.mean_tol*100:.1f}% + noise "
                         f"{v.mean_se_rel[c]*100:.3f}%·z)")
        fails = self.block_failures
        for p, v, by, bx, c in fails[:8]:
            y0, x0 = by * self.block, bx * self.block
            what = "(near) zero variance on both sides but means differ" if v.exact_mismatch[by, bx, c] else \
                f"t={v.t[by, bx, c]:+.2f} (ν={v.nu[by, bx, c]:.0f}) p={p:.2e}"
            lines.append(f"  block fail: view {v.index} '{v.view_id}' px x[{x0},{x0 + self.block}) "
                         f"y[{y0},{y0 + self.block}) {ch[c]}: mvpt {v.block_mean_a[by, bx, c]:.5g} vs ref "
                         f"{v.block_mean_b[by, bx, c]:.5g}; {what}")
        if len(fails) > 8:
            lines.append(f"  ... and {len(fails) - 8} more failing block tests")
        return "\n".join(lines)

    __str__ = summary


def compare_estimates(name: str, pairs: Sequence[tuple], alpha: float = 0.01, block: int = 8,
                      mean_tol: float = 0.01, sys_rel: float = 0.0) -> CompareResult:
    """Run tests (a) and (b) on [(index, view_id, mvpt ImageEstimate, reference ImageEstimate)].

    sys_rel: a known systematic relative uncertainty of the reference (0 for live Mitsuba
    renders), added to each block's variance as (sys_rel · reference block mean)², exact dof."""
    res = CompareResult(name=name, alpha=alpha, block=block, mean_tol=mean_tol)
    n_tests = 0
    n_mean = 0
    prepared = []
    for idx, vid, a, b in pairs:
        if a.mean.shape != b.mean.shape:
            raise ValueError(f"view {idx} '{vid}': mvpt image {a.mean.shape} vs reference {b.mean.shape}")
        ba, bb = block_stats(a, block), block_stats(b, block)
        if sys_rel > 0:
            extra = (sys_rel * bb.mean) ** 2
            with np.errstate(divide="ignore", invalid="ignore"):
                dof = np.where(np.isinf(bb.dof), np.inf, (bb.var + extra) ** 2 / (bb.var**2 / bb.dof))
            bb = BlockStats(bb.mean, bb.var + extra, dof, bb.count)
        n_tests += ba.mean.size
        ma, mb = a.mean.reshape(-1, 3).mean(0), b.mean.reshape(-1, 3).mean(0)
        npx = a.mean.shape[0] * a.mean.shape[1]
        se = np.sqrt(a.var.reshape(-1, 3).sum(0) + b.var.reshape(-1, 3).sum(0)) / npx
        ref_scale = np.maximum(np.abs(mb), np.abs(ma))
        tested = (ref_scale >= 1e-3 * ref_scale.max()) & (ref_scale > 1e-6)
        n_mean += int(tested.sum())
        prepared.append((idx, vid, a, b, ba, bb, ma, mb, se, tested))
    res.level_block = sidak(alpha, n_tests)
    res.level_mean = sidak(alpha, n_mean)
    z_mean = stats.norm.isf(res.level_mean / 2)
    for idx, vid, a, b, ba, bb, ma, mb, se, tested in prepared:
        t, nu, p, mismatch = welch_p_values(ba, bb)
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(tested, (ma - mb) / np.abs(mb), np.nan)
            se_rel = np.where(tested, se / np.abs(mb), np.nan)
        ok = ~tested | (np.abs(ma - mb) <= mean_tol * np.abs(mb) + z_mean * se)
        res.views.append(ViewComparison(idx, vid, a.mean.shape, ma, mb, rel, se_rel, tested, ok,
                                        t, nu, p, mismatch, ba.mean, bb.mean, a, b))
    return res


# --------------------------------------------------------------------------------------
# Scene preparation: includes inlined, films resized, box filters (in memory only)
# --------------------------------------------------------------------------------------

def _resolve_var(text: str, variables: dict) -> str:
    import re
    return re.sub(r"\$(\w+)", lambda m: str(variables.get(m.group(1), m.group(0))), text)


def prepare_scene(path, defines: Optional[dict] = None, max_res: Optional[int] = None,
                  box_filter: bool = True) -> tuple:
    """(xml string, base dir) of `path` with every <include> inlined, each film scaled so its
    larger side is `max_res` (aspect kept, crop windows scaled along) and every rfilter a box.

    Files on disk are not touched. A box filter makes each sample land in exactly one pixel,
    which the per-pixel variance estimates assume; downscaling keeps the full field of view.
    Inlining follows Mitsuba's semantics (the included <scene>'s children replace the
    <include>); relative names in included files then resolve against the scene's
    directory and its <path> entries, as Mitsuba's file resolver does."""
    import xml.etree.ElementTree as ET
    path = Path(path).resolve()
    base = path.parent
    defines = {k: str(v) for k, v in (defines or {}).items()}

    def inline(elem, cur_dir, depth=0):
        if depth > 32:
            raise ValueError(f"{path}: includes nested too deeply")
        out = []
        for c in list(elem):
            if c.tag == "include":
                name = Path(c.get("filename"))
                cand = [cur_dir / name, base / name]
                f = next((x for x in cand if x.is_file()), None)
                if f is None:
                    raise FileNotFoundError(f"{path}: included file {name} not found")
                sub = ET.parse(f).getroot()
                inline(sub, f.parent, depth + 1)
                out.extend(list(sub))
            else:
                inline(c, cur_dir, depth + 1)
                out.append(c)
        for c in list(elem):
            elem.remove(c)
        elem.extend(out)

    root = ET.parse(path).getroot()
    inline(root, base)
    variables = {d.get("name"): d.get("value") for d in root.iter("default")}
    variables.update(defines)
    for film in root.iter("film"):
        ints = {c.get("name"): c for c in film if c.tag == "integer"}
        for key, default in (("width", 768), ("height", 576)):  # hdrfilm's defaults
            if max_res and key not in ints:
                ints[key] = ET.SubElement(film, "integer", {"name": key, "value": str(default)})
        if max_res:
            w = int(_resolve_var(ints["width"].get("value"), variables))
            h = int(_resolve_var(ints["height"].get("value"), variables))
            scale = max_res / max(w, h)
            if scale < 1:
                for key in ("width", "height", "crop_offset_x", "crop_offset_y", "crop_width", "crop_height"):
                    if key in ints:
                        v = int(_resolve_var(ints[key].get("value"), variables))
                        ints[key].set("value", str(max(1, int(round(v * scale))) if "offset" not in key
                                                   else int(round(v * scale))))
        if box_filter:
            for rf in [c for c in film if c.tag == "rfilter"]:
                film.remove(rf)
            ET.SubElement(film, "rfilter", {"type": "box"})
    return ET.tostring(root, encoding="unicode"), base


# --------------------------------------------------------------------------------------
# Renderers
# --------------------------------------------------------------------------------------

def _mvpt():
    import mvpt
    return mvpt


def _mitsuba(variant: str = "scalar_rgb"):
    import mitsuba as mi
    if mi.variant() != variant:
        mi.set_variant(variant)
    return mi


def _is_xml_string(scene) -> bool:
    return isinstance(scene, str) and scene.lstrip().startswith("<")


def load_mvpt(scene, defines: dict, base_dir=None):
    """Load with mvpt (path or XML string); raises mvpt.SceneError on bad or unsupported input."""
    mvpt = _mvpt()
    if _is_xml_string(scene):
        return mvpt.load_string(scene, base_dir or ".", **defines)
    return mvpt.load_file(scene, **defines)


def load_mitsuba(scene, defines: dict, base_dir=None, variant: str = "scalar_rgb"):
    """Load with Mitsuba 3 (scalar_rgb unless told; path or XML string)."""
    mi = _mitsuba(variant)
    d = {k: str(v) for k, v in defines.items()}
    if not _is_xml_string(scene):
        return mi.load_file(str(scene), **d)
    if base_dir is None:
        return mi.load_string(scene, **d)
    fr = mi.file_resolver() if hasattr(mi, "file_resolver") else mi.Thread.thread().file_resolver()
    saved = [fr[i] for i in range(len(fr))]
    fr.prepend(str(Path(base_dir).resolve()))
    try:
        return mi.load_string(scene, **d)
    finally:
        fr.clear()
        for p in saved:
            fr.append(p)


def render_mvpt(scene_obj, spp: int, seed: int = 0, threads: int = 0) -> list:
    """[(view index, view id, ImageEstimate)] for every view of an mvpt scene."""
    mvpt = _mvpt()
    t0 = time.perf_counter()
    r = mvpt.render(scene_obj, spp=spp, seed=seed, threads=threads)
    dt = time.perf_counter() - t0
    out = []
    for i, vid in enumerate(r.view_ids):
        img = np.asarray(r.images[vid], dtype=np.float64)
        var = np.asarray(r.variance[vid], dtype=np.float64)
        cnt = np.asarray(r.sample_count[vid], dtype=np.float64).reshape(img.shape[:2])
        dof = np.repeat(np.maximum(cnt - 1, 1)[..., None], 3, axis=2)
        e = ImageEstimate(img, var, dof, "mvpt", dt, int(cnt.sum()))
        out.append((i, vid, e))
    return out


def render_mitsuba(scene_obj, spp: int, seeds: int = 8, seed: int = 0) -> list:
    """[(sensor index, sensor id, ImageEstimate)]: `seeds` independent renders of spp/seeds each."""
    mi = _mitsuba()
    per_seed = max(1, spp // seeds)
    out = []
    for i, sensor in enumerate(scene_obj.sensors()):
        t0 = time.perf_counter()
        if seeds * (i + 1) >= SEED_BASE:
            raise ValueError(f"too many sensors x seeds for SEED_BASE={SEED_BASE}")
        imgs = [np.array(mi.render(scene_obj, sensor=i, seed=1 + SEED_BASE * seed + i * seeds + k, spp=per_seed))
                for k in range(seeds)]
        for k in range(1, seeds):  # repeated random streams would fake a small variance
            if np.array_equal(imgs[k], imgs[k - 1]) and np.any(imgs[k]):
                raise AssertionError(f"Mitsuba seeds {k - 1} and {k} of sensor {i} rendered identical images")
        e = estimate_from_seeds(imgs, "mitsuba")
        e.seconds = time.perf_counter() - t0
        e.samples = per_seed * seeds * e.mean.shape[0] * e.mean.shape[1]
        sid = sensor.id() or f"sensor{i}"
        out.append((i, sid, e))
    return out


def compare_scene(scene, defines: Optional[dict] = None, spp: int = 256, mitsuba_spp: Optional[int] = None,
                  seeds: int = 8, seed: int = 0, alpha: float = 0.01, block: int = 8, mean_tol: float = 0.01,
                  base_dir=None, name: Optional[str] = None, threads: int = 0, max_res: Optional[int] = None,
                  box_filter: bool = False, mitsuba_defines: Optional[dict] = None) -> CompareResult:
    """Render every sensor of `scene` with mvpt and Mitsuba 3 and run the mean and block tests.

    spp: mvpt samples per pixel; mitsuba_spp: Mitsuba's total (split over `seeds` renders),
    default `spp`. max_res / box_filter: see `prepare_scene` (applied when either is set).
    mitsuba_defines: extra defines for Mitsuba only (parameters mvpt lacks). mvpt errors
    (mvpt.SceneError, e.g. for unknown plugins) propagate unchanged."""
    defines = dict(defines or {})
    name = name or (Path(scene).name if not _is_xml_string(scene) else "<xml string>")
    if (max_res or box_filter) and not _is_xml_string(scene):
        scene, base_dir = prepare_scene(scene, defines, max_res, box_filter)
    t0 = time.perf_counter()
    s_mvpt = load_mvpt(scene, defines, base_dir)
    s_mi = load_mitsuba(scene, {**defines, **(mitsuba_defines or {})}, base_dir)
    t_load = time.perf_counter() - t0
    a = render_mvpt(s_mvpt, spp, seed, threads)
    b = render_mitsuba(s_mi, mitsuba_spp or spp, seeds, seed)
    if len(a) != len(b):
        raise AssertionError(f"{name}: mvpt has {len(a)} view(s), Mitsuba {len(b)} sensor(s)")
    pairs = [(ia, vid, ea, eb) for (ia, vid, ea), (_, _, eb) in zip(a, b)]
    res = compare_estimates(name, pairs, alpha, block, mean_tol)
    res.seconds = {"load": t_load, "mvpt": a[0][2].seconds if a else 0.0,
                   "mitsuba": sum(e.seconds for _, _, e in b)}
    return res


def compare_mitsuba_to_itself(scene, defines: Optional[dict] = None, spp: int = 256, seeds: int = 8,
                              alpha: float = 0.01, block: int = 8, mean_tol: float = 0.01, max_res=None,
                              box_filter: bool = False, name: Optional[str] = None) -> CompareResult:
    """A/A calibration: Mitsuba against Mitsuba with independent seeds, both sides estimated
    from seeds (fewer dof than mvpt's side). A scene failing here needs more samples."""
    defines = dict(defines or {})
    name = (name or (Path(scene).name if not _is_xml_string(scene) else "<xml string>")) + " (Mitsuba A/A)"
    base_dir = None
    if (max_res or box_filter) and not _is_xml_string(scene):
        scene, base_dir = prepare_scene(scene, defines, max_res, box_filter)
    s_mi = load_mitsuba(scene, defines, base_dir)
    a = render_mitsuba(s_mi, spp, seeds, seed=0)
    b = render_mitsuba(s_mi, spp, seeds, seed=1)
    pairs = [(ia, vid, ea, eb) for (ia, vid, ea), (_, _, eb) in zip(a, b)]
    return compare_estimates(name, pairs, alpha, block, mean_tol)


def read_exr(path) -> np.ndarray:
    """(H, W, 3) float64 of an RGB(A) EXR (read with Mitsuba's Bitmap)."""
    mi = _mitsuba()
    return np.array(mi.Bitmap(str(path)), dtype=np.float64)[..., :3]


@dataclass
class ReferenceResult:
    """Outcome of Mitsuba's own test-suite criterion against a stored reference."""

    name: str
    passed: bool
    fraction_ok: float
    min_p: float
    level: float
    mean_rel_diff: np.ndarray
    mean_ok: bool
    seconds: float = 0.0

    def summary(self) -> str:
        rel = ", ".join(f"{c} {d*100:+.2f}%" for c, d in zip("RGB", self.mean_rel_diff))
        return (f"{self.name}: {'PASS' if self.passed else 'FAIL'} — {self.fraction_ok*100:.2f}% of pixels pass "
                f"(need {REF_PASS_FRACTION*100:.2f}%) at Šidák level {self.level:.2e}, min p {self.min_p:.2e}; "
                f"image mean rel diff [{rel}]{'' if self.mean_ok else ' MEAN FAIL (> 1 % + noise)'}")

    __str__ = summary


def compare_to_reference(scene, ref_rgb, ref_var, defines: Optional[dict] = None, spp: int = 256,
                         seed: int = 0, alpha: float = 0.01, mean_tol: float = 0.01,
                         name: Optional[str] = None) -> ReferenceResult:
    """mvpt's first view against a stored Mitsuba test-suite reference, by that suite's rule.

    Mitsuba's test_renders.py: per pixel and channel z = |m − ref| · sqrt(spp / max(var, 1e-4))
    with `var` the reference's per-sample variance, Šidák level over pixels, and at least
    99.75 % of the pixels passing. This looser rule is used (instead of the block t-test)
    because the stored references deviate from Mitsuba 3.9.1 itself: a constant emitter of
    radiance 1 is stored as R = 1.0011, and some dark blocks of instancing/ differ by 15–30 %
    between Mitsuba 3.9.1 and its reference (measured with this module, 256 spp); the strict
    test runs against live Mitsuba renders. Plus test (a) on the image mean."""
    name = name or Path(scene).name
    s = load_mvpt(scene, dict(defines or {}))
    (_, _, ea), *_ = render_mvpt(s, spp, seed)
    return reference_criterion(name, ea, read_exr(ref_rgb), read_exr(ref_var), spp, alpha, mean_tol)


def reference_criterion(name: str, ea: ImageEstimate, ref: np.ndarray, var: np.ndarray, spp: int,
                        alpha: float = 0.01, mean_tol: float = 0.01) -> ReferenceResult:
    """The rule of `compare_to_reference` applied to an estimate `ea` rendered with `spp`."""
    if ref.shape != ea.mean.shape:
        raise ValueError(f"{name}: mvpt image {ea.mean.shape} vs reference {ref.shape}")
    # As test_renders.py, in XYZ: the files were written from XYZ with this linear map.
    z = np.abs((ea.mean - ref) @ RGB_TO_XYZ.T) * np.sqrt(spp / np.maximum(var @ RGB_TO_XYZ.T, 1e-4))
    p = 2.0 * stats.norm.sf(z)
    npx = ref.shape[0] * ref.shape[1]
    level = sidak(alpha, npx)
    frac = float((p > level).sum()) / 3.0 / npx
    ma, mb = ea.mean.reshape(-1, 3).mean(0), ref.reshape(-1, 3).mean(0)
    se = np.sqrt(ea.var.reshape(-1, 3).sum(0) + np.maximum(var, 0).reshape(-1, 3).sum(0) / REF_SPP) / npx
    tested = (np.abs(mb) >= 1e-3 * np.abs(mb).max()) & (np.abs(mb) > 1e-6)
    z_mean = stats.norm.isf(sidak(alpha, max(1, int(tested.sum()))) / 2)
    mean_ok = bool(np.all(~tested | (np.abs(ma - mb) <= mean_tol * np.abs(mb) + z_mean * se)))
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(tested, (ma - mb) / np.abs(mb), np.nan)
    return ReferenceResult(name + " vs refs", frac >= REF_PASS_FRACTION and mean_ok, frac, float(p.min()), level,
                           rel, mean_ok, ea.seconds)


# --------------------------------------------------------------------------------------
# Skip rule shared by the tests
# --------------------------------------------------------------------------------------

def unknown_plugin(err: Exception) -> Optional[str]:
    """'<kind> <type>' if `err` is mvpt's "unknown <kind> type '<type>'" SceneError, else None."""
    import re
    m = re.search(r"unknown (\w+) type '([^']+)'", str(err))
    return f"{m.group(1)} {m.group(2)}" if m else None


def run_or_skip(fn, requires: set, *args, **kwargs):
    """Call fn; turn mvpt's unknown-plugin error into pytest.skip naming the plugin.

    Any other exception propagates (and fails the test). An unknown plugin that the test's
    `requires` set does not list is an error in the test list, so it fails too."""
    import pytest
    mvpt = _mvpt()
    try:
        return fn(*args, **kwargs)
    except mvpt.SceneError as e:
        missing = unknown_plugin(e)
        if missing is None:
            raise
        kind, typ = missing.split(" ", 1)
        if typ not in requires:
            raise AssertionError(f"scene needs plugin {kind} '{typ}', which its `requires` set does not list") from e
        pytest.skip(f"plugin {typ} ({kind}) not available yet")


def write_diff(res: CompareResult, out_dir) -> list:
    """Per view: EXR of [mvpt | reference | mvpt − reference | |t| per block] side by side."""
    mi = _mitsuba()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for v in res.views:
        h, w, _ = v.shape
        tmap = np.repeat(np.repeat(np.abs(v.t), res.block, 0), res.block, 1)[:h, :w]
        panel = np.concatenate([v.a.mean, v.b.mean, v.a.mean - v.b.mean, tmap], axis=1).astype(np.float32)
        p = out_dir / f"{v.index:02d}_{v.view_id}_diff.exr"
        mi.Bitmap(panel).write(str(p))
        paths.append(p)
    return paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Compare one scene between mvpt and Mitsuba 3 (scalar_rgb).")
    ap.add_argument("scene")
    ap.add_argument("-D", dest="defines", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--spp", type=int, default=256, help="mvpt spp (and Mitsuba's total spp)")
    ap.add_argument("--mitsuba-spp", type=int, default=None)
    ap.add_argument("--seeds", type=int, default=8, help="independent Mitsuba renders")
    ap.add_argument("--alpha", type=float, default=0.01)
    ap.add_argument("--ref", nargs=2, metavar=("REF_RGB", "REF_VAR"), help="compare against stored references")
    ap.add_argument("--diff", metavar="DIR", help="write per-view diff EXRs here")
    ap.add_argument("--max-res", type=int, default=None, help="scale films so the larger side is this")
    ap.add_argument("--box", action="store_true", help="replace every rfilter by a box (in memory)")
    ap.add_argument("--self", action="store_true", help="A/A calibration: Mitsuba against itself")
    args = ap.parse_args(argv)
    defines = dict(d.split("=", 1) for d in args.defines)
    if args.self:
        res = compare_mitsuba_to_itself(args.scene, defines, args.spp, args.seeds, args.alpha,
                                        max_res=args.max_res, box_filter=args.box)
        print(res.summary())
        return 0 if res.passed else 1
    if args.ref:
        res = compare_to_reference(args.scene, args.ref[0], args.ref[1], defines, args.spp, alpha=args.alpha)
        print(res.summary())
        return 0 if res.passed else 1
    else:
        res = compare_scene(args.scene, defines, args.spp, args.mitsuba_spp, args.seeds, alpha=args.alpha,
                            max_res=args.max_res, box_filter=args.box)
    print(res.summary())
    print(f"seconds: {res.seconds}; max se of relative mean difference {res.max_mean_se_rel*100:.3f}%")
    if args.diff:
        for p in write_diff(res, args.diff):
            print("wrote", p)
    return 0 if res.passed else 1


if __name__ == "__main__":
    sys.exit(main())
