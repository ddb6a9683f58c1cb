"""Chi-square test of a direction sampler against its solid-angle density.

Directions are binned on an equal-area (phi, cos theta) grid in a frame whose
z axis is `axis`, restricted to cos theta >= `cos_min`; expected counts come from
integrating the density over each cell (midpoint rule, refined where the density
jumps, e.g. at the silhouette of an area light). Cells with small expected counts
are pooled (Mitsuba's chi2.py). A failed sample or one outside the grid (the
caller chooses `cos_min` to cover the density's support) makes the test fail.
"""
from __future__ import annotations

import numpy as np
from scipy import stats


def frame(axis):
    n = np.asarray(axis, float)
    n = n / np.linalg.norm(n)
    sign = np.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1 + sign * n[0] ** 2 * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] ** 2 * a, -n[1]])
    return s, t, n


def _directions(frame_, phi, cos_t):
    s, t, n = frame_
    sin_t = np.sqrt(np.maximum(0.0, 1 - cos_t ** 2))
    return (np.outer(sin_t * np.cos(phi), s) + np.outer(sin_t * np.sin(phi), t) + np.outer(cos_t, n)).astype(np.float32)


def _cell_integrals(pdf_fn, frame_, res, cos_min, k):
    """Integral of the density over cells (i_cos, j_phi), k x k midpoints per cell."""
    n_phi, n_cos = res
    dphi, dcos = 2 * np.pi / n_phi, (1 - cos_min) / n_cos
    sub_phi = (np.arange(n_phi * k) + 0.5) * dphi / k
    sub_cos = cos_min + (np.arange(n_cos * k) + 0.5) * dcos / k
    P, C = np.meshgrid(sub_phi, sub_cos)
    vals = np.asarray(pdf_fn(_directions(frame_, P.ravel(), C.ravel())), float).reshape(n_cos * k, n_phi * k)
    cell_vals = vals.reshape(n_cos, k, n_phi, k)
    integral = cell_vals.mean(axis=(1, 3)) * dphi * dcos
    support = cell_vals.max(axis=(1, 3)) > 0
    jumps = (cell_vals.min(axis=(1, 3)) == 0) & support
    # The support may also clip a cell whose midpoints all miss it: refine the
    # neighbours of every cell on the boundary too (phi wraps around).
    edge = jumps.copy()
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            shifted = np.roll(support, dj, axis=1)
            if di:
                shifted = np.roll(shifted, di, axis=0)
                shifted[0 if di > 0 else -1, :] = support[0 if di > 0 else -1, :]
            edge |= shifted != support
    return integral, edge


def _refine(pdf_fn, frame_, res, cos_min, cells, k):
    n_phi, n_cos = res
    dphi, dcos = 2 * np.pi / n_phi, (1 - cos_min) / n_cos
    out = []
    g = (np.arange(k) + 0.5) / k
    gp, gc = np.meshgrid(g, g)
    for i, j in cells:
        phi = (j + gp.ravel()) * dphi
        cos_t = cos_min + (i + gc.ravel()) * dcos
        v = np.asarray(pdf_fn(_directions(frame_, phi, cos_t)), float)
        out.append(v.mean() * dphi * dcos)
    return out


def chi2_directions(sample_dirs, pdf_fn, axis=(0, 0, 1), cos_min=-1.0, res=(48, 24), k=4, k_refine=32,
                    min_expected=5.0, allow_failures=False, mass_tol=3e-3):
    """Returns (p_value, message). `sample_dirs`: (n,3) unit directions that a
    sampler produced (zero vectors mark failed samples); `pdf_fn(dirs) -> (m,)`
    is the solid-angle density of the successful ones. With `allow_failures`, the
    density may integrate to less than one and the failures form one more cell
    expecting the missing mass (e.g. back faces of a closed emitter)."""
    frame_ = frame(axis)
    d = np.asarray(sample_dirs, float)
    n = len(d)
    valid = np.linalg.norm(d, axis=1) > 0.5
    s, t, nrm = frame_
    x, y, z = d[valid] @ s, d[valid] @ t, np.clip(d[valid] @ nrm, -1, 1)
    phi = np.mod(np.arctan2(y, x), 2 * np.pi)
    n_phi, n_cos = res
    inside = z >= cos_min
    i = np.clip(((z[inside] - cos_min) / (1 - cos_min) * n_cos).astype(int), 0, n_cos - 1)
    j = np.clip((phi[inside] / (2 * np.pi) * n_phi).astype(int), 0, n_phi - 1)
    observed = np.zeros((n_cos, n_phi))
    np.add.at(observed, (i, j), 1)
    failed = int(n - valid.sum())
    outside = int(valid.sum() - inside.sum())

    integral, jumps = _cell_integrals(pdf_fn, frame_, res, cos_min, k)
    cells = list(zip(*np.nonzero(jumps)))
    if cells:
        for (ci, cj), v in zip(cells, _refine(pdf_fn, frame_, res, cos_min, cells, k_refine)):
            integral[ci, cj] = v
    # Samples in a cell whose integral came out zero: a sliver of the support the
    # midpoints missed, or a real error; integrate such cells much more finely.
    empty = list(zip(*np.nonzero((integral == 0) & (observed > 0))))
    if empty:
        for (ci, cj), v in zip(empty, _refine(pdf_fn, frame_, res, cos_min, empty, 8 * k_refine)):
            integral[ci, cj] = v
    expected = integral.ravel() * n
    total_mass = integral.sum()
    # Pearson's statistic barely sees a density that is off by a constant factor.
    if not allow_failures and abs(total_mass - 1.0) > mass_tol:
        return 0.0, f"the density integrates to {total_mass:.5f} over the grid, not 1"
    observed = observed.ravel()
    if outside > 0:
        return 0.0, f"{outside} samples fell outside the binned region (cos theta < {cos_min})"
    if failed > 0 and not allow_failures:
        return 0.0, f"{failed} samples failed"

    # Pool small cells (sorted by expectation) until each pooled cell expects >= min_expected.
    order = np.argsort(expected)
    obs_c, exp_c = [], []
    acc_o = acc_e = 0.0
    for idx in order:
        if expected[idx] == 0:
            if observed[idx] > 0:
                return 0.0, f"{int(observed[idx])} samples in a cell of zero density"
            continue
        acc_o += observed[idx]
        acc_e += expected[idx]
        if acc_e >= min_expected:
            obs_c.append(acc_o)
            exp_c.append(acc_e)
            acc_o = acc_e = 0.0
    if acc_e > 0 and exp_c:
        obs_c[-1] += acc_o
        exp_c[-1] += acc_e
    if allow_failures:
        obs_c.append(failed)
        exp_c.append(max(0.0, 1.0 - total_mass) * n)
    obs_c, exp_c = np.array(obs_c), np.array(exp_c)
    if (exp_c <= 0).any() and (obs_c[exp_c <= 0] > 0).any():
        return 0.0, f"{failed} failed samples but the density integrates to {total_mass:.5f}"
    obs_c, exp_c = obs_c[exp_c > 0], exp_c[exp_c > 0]
    chi2 = float(((obs_c - exp_c) ** 2 / exp_c).sum())
    dof = len(obs_c) - 1
    p = float(stats.chi2.sf(chi2, dof))
    return p, f"chi2={chi2:.1f} dof={dof} p={p:.3g} density mass={total_mass:.5f} failed={failed}"


def sidak_alpha(alpha: float, n_tests: int) -> float:
    """Per-test significance level for `n_tests` tests at family-wise level `alpha`."""
    return 1.0 - (1.0 - alpha) ** (1.0 / n_tests)
