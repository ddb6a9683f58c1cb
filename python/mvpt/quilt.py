"""Looking Glass quilts: all views tiled in one image, as the Looking Glass tools read them.

Convention (Looking Glass Factory, "What is a quilt"): tiles run left to right, then
bottom to top: view 0 is the bottom-left tile and the last view the top-right one, and
view 0 is the leftmost view of the scene. The file name ends in
`_qs{columns}x{rows}a{aspect}` where aspect is one view's width / height (e.g.
`_qs8x6a0.75` for the Looking Glass Portrait), so Looking Glass Studio and the display
tools pick the layout up by themselves. The caller orders the views (scene order here);
unused tiles at the top right are black."""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from .images import as_rgb, srgb8

_NAME = re.compile(r"_qs(\d+)x(\d+)a(\d+(?:\.\d+)?)$")


def layout(n: int, columns: int | None = None, rows: int | None = None) -> tuple:
    """(columns, rows) for `n` views: as given, or near-square with enough tiles."""
    if n < 1:
        raise ValueError("a quilt needs at least one view")
    if columns is None and rows is None:
        columns = math.ceil(math.sqrt(n))
    if columns is None:
        columns = math.ceil(n / rows)
    if rows is None:
        rows = math.ceil(n / columns)
    if columns < 1 or rows < 1 or columns * rows < n:
        raise ValueError(f"a {columns}x{rows} quilt has {columns * rows} tiles, too few for {n} views")
    return int(columns), int(rows)


def tile_origin(i: int, columns: int, rows: int, tile_w: int, tile_h: int) -> tuple:
    """(x, y) of view i's tile in image coordinates (y down): column i % columns, row i // columns from the bottom."""
    col, row_from_bottom = i % columns, i // columns
    return col * tile_w, (rows - 1 - row_from_bottom) * tile_h


def make_quilt(images: list, columns: int | None = None, rows: int | None = None) -> tuple:
    """Tile same-sized (H, W, 3) views into a quilt: (quilt array, columns, rows)."""
    tiles = [as_rgb(im) for im in images]
    columns, rows = layout(len(tiles), columns, rows)
    h, w = tiles[0].shape[:2]
    for i, t in enumerate(tiles):
        if t.shape[:2] != (h, w):
            raise ValueError(f"view {i} is {t.shape[1]}x{t.shape[0]} but view 0 is {w}x{h}: quilt tiles must match")
    quilt = np.zeros((rows * h, columns * w, 3), dtype=tiles[0].dtype)
    for i, t in enumerate(tiles):
        x, y = tile_origin(i, columns, rows, w, h)
        quilt[y:y + h, x:x + w] = t
    return quilt, columns, rows


def split_quilt(quilt: np.ndarray, columns: int, rows: int, n: int | None = None) -> list:
    """The views of a quilt in order (the inverse of make_quilt); `n` drops unused tiles."""
    qh, qw = quilt.shape[:2]
    if qh % rows or qw % columns:
        raise ValueError(f"a {qw}x{qh} image does not split into {columns}x{rows} equal tiles")
    h, w = qh // rows, qw // columns
    n = columns * rows if n is None else n
    out = []
    for i in range(n):
        x, y = tile_origin(i, columns, rows, w, h)
        out.append(quilt[y:y + h, x:x + w])
    return out


def format_aspect(aspect: float) -> str:
    """The aspect as the file names write it: up to 3 decimals, no trailing zeros (0.75, 1.778, 1)."""
    return f"{aspect:.3f}".rstrip("0").rstrip(".")


def quilt_name(stem: str, columns: int, rows: int, aspect: float, ext: str = ".png") -> str:
    """`<stem>_qs{columns}x{rows}a{aspect}<ext>`."""
    return f"{stem}_qs{columns}x{rows}a{format_aspect(aspect)}{ext}"


def parse_quilt_name(path) -> tuple:
    """(columns, rows, aspect) from a quilt file name; ValueError if it has no _qs suffix."""
    m = _NAME.search(Path(path).stem)
    if not m:
        raise ValueError(f"'{Path(path).name}' has no _qs<columns>x<rows>a<aspect> suffix")
    return int(m.group(1)), int(m.group(2)), float(m.group(3))


def write_quilt(images: list, out_dir, stem: str, columns: int | None = None, rows: int | None = None,
                exposure: float = 0.0) -> str:
    """Write the sRGB 8-bit PNG quilt of linear views to <out_dir>/<stem>_qs..png; returns its path."""
    from PIL import Image

    quilt, columns, rows = make_quilt(images, columns, rows)
    h, w = np.asarray(images[0]).shape[:2]
    path = Path(out_dir) / quilt_name(stem, columns, rows, w / h)
    Image.fromarray(srgb8(quilt, exposure)).save(path)
    return str(path)
