"""Statistical image comparison of mvpt against Mitsuba 3 (scalar_rgb) for the shape tests.

The same XML goes through both renderers. mvpt reports the variance of each pixel mean;
Mitsuba is rendered with K independent seeds and its variance of the mean comes from their
spread. Pixels are pooled into blocks; every block and channel gets a z-test, Šidák-corrected
over all blocks, channels and views; the image means must also agree within `mean_tol`.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import mvpt

mi = pytest.importorskip("mitsuba")
mi.set_variant("scalar_rgb")

from shared_data import require_shared, shared_scenes  # noqa: E402,F401  (re-exported to the shape tests)


def mitsuba_reference(xml: str, base_dir: Path, sensor: int, spp: int, runs: int):
    """Mean image and variance of the mean over `runs` independent Mitsuba renders."""
    old = Path.cwd()
    os.chdir(base_dir)
    try:
        scene = mi.load_string(xml)
        imgs = np.stack([np.array(mi.render(scene, sensor=sensor, spp=spp, seed=1000 + k)) for k in range(runs)])
    finally:
        os.chdir(old)
    return imgs.mean(axis=0), imgs.var(axis=0, ddof=1) / runs


def block_sums(img: np.ndarray, b: int) -> np.ndarray:
    h, w = img.shape[:2]
    return img[: h - h % b, : w - w % b].reshape(h // b, b, w // b, b, -1).sum(axis=(1, 3))


def compare_with_mitsuba(xml: str, base_dir: Path = Path("."), spp: int = 64, mi_spp: int = 16, runs: int = 8,
                         block: int = 4, alpha: float = 1e-3, mean_tol: float = 0.01, seed: int = 7):
    """Render `xml` (>= 2 sensors) with both renderers and assert statistical agreement per view."""
    scene = mvpt.load_string(xml, base_dir)
    result = mvpt.render(scene, spp=spp, seed=seed)
    ids = list(result.images.keys())
    assert len(ids) >= 2, "shape comparisons use at least two sensors"
    zs, report = [], []
    for i, vid in enumerate(ids):
        a, var_a = result.images[vid].astype(np.float64), result.variance[vid].astype(np.float64)
        b, var_b = mitsuba_reference(xml, base_dir, i, mi_spp, runs)
        assert a.shape == b.shape
        ma, mb = a.mean(), b.mean()
        report.append(f"view {vid}: mvpt mean {ma:.5f}, mitsuba mean {mb:.5f}")
        assert mb > 0, f"view {vid}: the Mitsuba image is black; the test scene is broken"
        assert abs(ma - mb) <= mean_tol * mb, "; ".join(report)
        zs.append(block_z_scores(a, var_a, b, var_b, block, f"view {vid}"))
    assert_z_scores(np.concatenate(zs), alpha, "; ".join(report))
    return report


def block_z_scores(a, var_a, b, var_b, block: int, what: str) -> np.ndarray:
    """z-scores of block sums of two mean images with per-pixel variances of the mean."""
    # Noise-free blocks (e.g. directly seen emitters) may still differ by float
    # rounding: a relative 1e-5 floor on the deviation keeps those from dividing by ~0.
    sa, sb = block_sums(a, block), block_sums(b, block)
    sd = np.sqrt(block_sums(var_a, block) + block_sums(var_b, block) + (1e-5 * np.abs(sb)) ** 2)
    ok = sd > 0
    assert np.all(sa[~ok] == sb[~ok]), f"{what}: black blocks differ"
    return (sa - sb)[ok] / sd[ok]


def assert_z_scores(z: np.ndarray, alpha: float, report: str = ""):
    """Šidák correction over all tests: per-test level 1 - (1 - alpha)^(1/n)."""
    p_each = 1.0 - (1.0 - alpha) ** (1.0 / len(z))
    limit = stats.norm.ppf(1.0 - p_each / 2.0)
    worst = np.max(np.abs(z))
    assert worst < limit, f"largest |z| = {worst:.2f} over {len(z)} blocks exceeds {limit:.2f}; {report}"
