"""Reusable chi-square goodness-of-fit test for direction samplers.

Checks that a sampling routine draws directions with the density that a
separate ``pdf`` routine claims (as Mitsuba's ``chi2.py`` and pbrt's
``bsdfs_test.cpp`` do):

1. draw ``n`` samples and histogram the valid ones on an equal-area grid over
   the full sphere, ``n_cos`` bins in cos(theta) in [-1, 1] times ``n_phi``
   bins in phi in [-pi, pi) (every cell has solid angle 4 pi / (n_cos n_phi));
2. integrate ``pdf`` over every cell with a tensor Gauss-Legendre rule of
   ``quad`` x ``quad`` points (exact for polynomials, fine for smooth lobes);
   the expected count is ``n`` times that integral. Samples that the sampler
   marks invalid (failed samples, zero weight, and *discrete* samples such as
   delta reflection or null transmission) are counted in ``n`` but not
   histogrammed, so ``pdf`` must integrate to the probability of a valid,
   continuous sample: a missing or extra lobe weight makes the test fail;
3. any sample in a cell whose expected count is (numerically) zero fails the
   test outright; cells with expected count < ``min_expected`` (5) are pooled
   into one bin; Pearson's statistic over the remaining bins is compared with
   the chi-square distribution with (bins - 1) degrees of freedom;
4. the p-value is compared with a Sidak-corrected significance level
   ``1 - (1 - alpha) ** (1 / n_tests)``, so that ``n_tests`` independent tests
   together have false-failure probability ``alpha``.

Usage::

    ok, p, msg = chi2_test(sample_fn, pdf_fn, n_samples=200_000, n_tests=20)
    assert ok, msg

``sample_fn(n) -> (wo, valid)``: ``wo`` an (n, 3) array of unit vectors,
``valid`` an (n,) bool array. ``pdf_fn(wo) -> (m,)`` solid-angle density of the
continuous part at the (m, 3) unit vectors ``wo``.
"""
from __future__ import annotations

import numpy as np
from scipy import stats

__all__ = ["chi2_test", "sidak_level", "sphere_grid", "integrate_pdf"]


def sidak_level(alpha: float, n_tests: int) -> float:
    """Per-test significance level giving family-wise level ``alpha`` over ``n_tests``."""
    return 1.0 - (1.0 - alpha) ** (1.0 / max(int(n_tests), 1))


def sphere_grid(n_cos: int, n_phi: int):
    """Bin edges (cos theta, phi) of the equal-area grid."""
    return np.linspace(-1.0, 1.0, n_cos + 1), np.linspace(-np.pi, np.pi, n_phi + 1)


def _to_cells(wo: np.ndarray, n_cos: int, n_phi: int) -> np.ndarray:
    cos_t = np.clip(wo[:, 2], -1.0, 1.0)
    phi = np.arctan2(wo[:, 1], wo[:, 0])
    i = np.clip(((cos_t + 1.0) * 0.5 * n_cos).astype(np.int64), 0, n_cos - 1)
    j = np.clip(((phi + np.pi) / (2 * np.pi) * n_phi).astype(np.int64), 0, n_phi - 1)
    return i * n_phi + j


def integrate_pdf(pdf_fn, n_cos: int, n_phi: int, quad: int = 6) -> np.ndarray:
    """Integral of ``pdf_fn`` over every cell of the grid (flattened, cos-major)."""
    x, w = np.polynomial.legendre.leggauss(quad)
    ce, pe = sphere_grid(n_cos, n_phi)
    dc, dp = ce[1] - ce[0], pe[1] - pe[0]
    # Quadrature points inside every cell: (cell_i, cell_j, qa, qb).
    c = ce[:-1, None] + (x[None, :] + 1.0) * 0.5 * dc  # (n_cos, quad)
    p = pe[:-1, None] + (x[None, :] + 1.0) * 0.5 * dp  # (n_phi, quad)
    C = np.broadcast_to(c[:, None, :, None], (n_cos, n_phi, quad, quad))
    P = np.broadcast_to(p[None, :, None, :], (n_cos, n_phi, quad, quad))
    s = np.sqrt(np.maximum(0.0, 1.0 - C * C))
    dirs = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
    vals = np.asarray(pdf_fn(np.ascontiguousarray(dirs, dtype=np.float32)), dtype=np.float64)
    vals = vals.reshape(n_cos, n_phi, quad, quad)
    if not np.all(np.isfinite(vals)):
        raise ValueError("pdf returned non-finite values")
    ww = (w[:, None] * w[None, :]) * 0.25 * dc * dp  # d(cos) d(phi) = solid angle
    return np.einsum("ijab,ab->ij", vals, ww).ravel()


def chi2_test(sample_fn, pdf_fn, n_samples: int = 200_000, n_cos: int = 40, n_phi: int = 80,
              quad: int = 6, alpha: float = 0.01, n_tests: int = 1, min_expected: float = 5.0):
    """Chi-square test of ``sample_fn`` against ``pdf_fn``; returns (ok, p_value, message)."""
    wo, valid = sample_fn(n_samples)
    wo = np.asarray(wo, dtype=np.float64).reshape(-1, 3)
    valid = np.asarray(valid, dtype=bool).ravel()
    if wo.shape[0] != n_samples or valid.shape[0] != n_samples:
        raise ValueError("sample_fn must return n samples")
    wv = wo[valid]
    if wv.size and (not np.all(np.isfinite(wv)) or np.max(np.abs(np.linalg.norm(wv, axis=1) - 1.0)) > 1e-3):
        return False, 0.0, "sampler returned non-finite or non-unit directions"
    observed = np.bincount(_to_cells(wv, n_cos, n_phi), minlength=n_cos * n_phi).astype(np.float64)
    expected = integrate_pdf(pdf_fn, n_cos, n_phi, quad) * n_samples

    info = (f"{int(valid.sum())}/{n_samples} valid samples, pdf integral "
            f"{expected.sum() / n_samples:.5f} vs valid fraction {valid.mean():.5f}")
    zero = expected <= 0.0
    if np.any(observed[zero] > 0):
        k = int(observed[zero].sum())
        return False, 0.0, f"{k} samples fell into cells where the pdf integrates to zero; {info}"

    order = np.argsort(expected)
    e_sorted, o_sorted = expected[order], observed[order]
    small = e_sorted < min_expected
    e_bins, o_bins = list(e_sorted[~small]), list(o_sorted[~small])
    pool_e, pool_o = float(e_sorted[small].sum()), float(o_sorted[small].sum())
    if pool_e > 0:
        if pool_e >= min_expected or not e_bins:
            e_bins.append(pool_e)
            o_bins.append(pool_o)
        else:  # merge an undersized pool into the smallest regular bin
            e_bins[0] += pool_e
            o_bins[0] += pool_o
    e_bins, o_bins = np.array(e_bins), np.array(o_bins)
    if len(e_bins) < 2:
        return False, 0.0, f"too few bins for a chi-square test; {info}"
    stat = float(np.sum((o_bins - e_bins) ** 2 / e_bins))
    dof = len(e_bins) - 1
    p = float(stats.chi2.sf(stat, dof))
    level = sidak_level(alpha, n_tests)
    ok = p > level
    msg = (f"chi2 = {stat:.1f} with {dof} dof, p = {p:.3g} "
           f"({'>' if ok else '<='} Sidak level {level:.3g}); {info}")
    return ok, p, msg
