"""Contact sheet: every view as a labelled thumbnail on one PNG, in reading order (view 0 top-left)."""
from __future__ import annotations

import math
from pathlib import Path


from .images import as_rgb, srgb8

LABEL_HEIGHT = 14  # pixels of the caption strip under each tile
PAD = 4            # pixels between tiles and around the sheet
BACKGROUND = (32, 32, 32)


def make_contact_sheet(images: dict, columns: int | None = None, labels: bool = True,
                       exposure: float = 0.0):
    """A Pillow image of `images` ({label: linear (H, W, 3)}) on a grid of cells as large as the largest view."""
    from PIL import Image, ImageDraw

    if not images:
        raise ValueError("a contact sheet needs at least one view")
    tiles = {str(k): srgb8(as_rgb(v), exposure) for k, v in images.items()}
    n = len(tiles)
    columns = columns or math.ceil(math.sqrt(n))
    rows = math.ceil(n / columns)
    cell_w = max(t.shape[1] for t in tiles.values())
    cell_h = max(t.shape[0] for t in tiles.values()) + (LABEL_HEIGHT if labels else 0)
    sheet = Image.new("RGB", (PAD + columns * (cell_w + PAD), PAD + rows * (cell_h + PAD)), BACKGROUND)
    draw = ImageDraw.Draw(sheet)
    for i, (label, tile) in enumerate(tiles.items()):
        x, y = contact_sheet_cell(i, columns, cell_w, cell_h)
        sheet.paste(Image.fromarray(tile), (x, y))
        if labels:
            draw.text((x + 2, y + tile.shape[0] + 1), label, fill=(230, 230, 230))
    return sheet


def write_contact_sheet(images: dict, path, columns: int | None = None, labels: bool = True,
                        exposure: float = 0.0) -> str:
    """Write the contact sheet of `images` as a PNG at `path`; returns the path."""
    make_contact_sheet(images, columns, labels, exposure).save(Path(path), format="PNG")
    return str(path)


def contact_sheet_cell(i: int, columns: int, cell_w: int, cell_h: int) -> tuple:
    """(x, y) of tile i's top-left corner on a sheet made with these cell sizes (cell_h includes the label)."""
    return PAD + (i % columns) * (cell_w + PAD), PAD + (i // columns) * (cell_h + PAD)


