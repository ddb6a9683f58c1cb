"""Shared helpers for the BSDF tests: probes from XML snippets, sample/pdf
adapters for the chi-square harness, and incident directions."""
from __future__ import annotations

import numpy as np

from mvpt import _probes

FLAGS = _probes.BsdfProbe.flag_values
DELTA = FLAGS["delta"]


def probe(xml: str):
    """A BsdfProbe for one <bsdf> element."""
    return _probes.BsdfProbe(xml)


def direction(theta_deg: float, phi_deg: float = 0.0, below: bool = False) -> tuple:
    """Unit vector at polar angle theta (from +z, or from -z when `below`) and azimuth phi."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    z = np.cos(t) * (-1.0 if below else 1.0)
    return (float(np.sin(t) * np.cos(p)), float(np.sin(t) * np.sin(p)), float(z))


def chi2_adapters(pr, wi, seed: int = 7):
    """(sample_fn, pdf_fn) for chi2_test: continuous, non-zero-weight samples are valid."""
    def sample_fn(n):
        wo, w, pdf, typ = pr.sample(*wi, n, seed)
        typ = typ.astype(np.uint32).ravel()
        valid = (w.max(axis=1) > 0) & (pdf.ravel() > 0) & ((typ & DELTA) == 0)
        return wo, valid

    def pdf_fn(wo):
        return pr.pdf(*wi, np.ascontiguousarray(wo, dtype=np.float32)).ravel()
    return sample_fn, pdf_fn


def random_directions(n: int, rng, upper_only: bool = False) -> np.ndarray:
    """Uniform directions on the sphere (or the upper hemisphere), float32 (n, 3)."""
    z = rng.uniform(0.0 if upper_only else -1.0, 1.0, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1).astype(np.float32)
