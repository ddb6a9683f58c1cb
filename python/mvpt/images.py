"""Display encodings shared by the quilt, contact sheet, movies and reports: linear RGB -> 8-bit sRGB."""
from __future__ import annotations

import numpy as np


def srgb8(rgb: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Linear RGB (H, W, 3) scaled by 2^exposure -> sRGB-encoded uint8, clipped to [0, 1].

    The same encoding as the PNGs of `mvpt render` (IEC 61966-2-1 piecewise curve);
    NaN becomes 0."""
    x = np.asarray(rgb, dtype=np.float64) * (2.0 ** float(exposure))
    x = np.clip(np.nan_to_num(x, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(y * 255.0).astype(np.uint8)


def as_rgb(image: np.ndarray) -> np.ndarray:
    """A float32 (H, W, 3) view of an (H, W), (H, W, 1), (H, W, 3) or (H, W, 4) image."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[2] not in (1, 3, 4):
        raise ValueError(f"expected an (H, W[, 1|3|4]) image, got shape {a.shape}")
    if a.shape[2] == 1:
        a = np.repeat(a, 3, axis=2)
    return np.ascontiguousarray(a[..., :3])
