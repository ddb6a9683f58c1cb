"""The display outputs of `mvpt render` beyond the per-view files, chosen by command-line options:
--multiview-exr (and --stereo), --quilt, --contact-sheet, --gif and --mp4 (views as frames)."""
from __future__ import annotations

import argparse
import re
from pathlib import Path

from . import contact_sheet, looking_glass, movie, quilt
from .output import _safe, multiview_exr_path, write_multiview_exr


def _grid(text: str) -> tuple:
    """--quilt's layout: COLUMNSxROWS, or a Looking Glass device's (looking_glass.DEVICES)."""
    if (text or "").strip() in looking_glass.DEVICES:
        d = looking_glass.DEVICES[text.strip()]
        return d.columns, d.rows
    m = re.fullmatch(r"\s*(\d+)\s*x\s*(\d+)\s*", text or "")
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise argparse.ArgumentTypeError(f"expected COLUMNSxROWS such as 8x6 or a Looking Glass device "
                                         f"({', '.join(looking_glass.DEVICES)}), got '{text}'")
    return int(m.group(1)), int(m.group(2))


def _fps(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not 0 < v <= MAX_FPS:
        raise argparse.ArgumentTypeError(f"expected frames per second > 0 and at most {MAX_FPS:g}, got '{text}'")
    return v


#: The highest frame rate of --gif/--mp4 (a GIF's frames last at least a millisecond).
MAX_FPS = 1000.0


#: The most stops --exposure scales the 8-bit displays by (2^64 is far beyond any radiance).
MAX_EXPOSURE = 64.0
#: The most pixels a quilt may have (a 10x10 quilt of 4K views is 0.83 G; this is 2 G, 6 GB in RGB).
MAX_QUILT_PIXELS = 1 << 31


def _exposure(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not abs(v) <= MAX_EXPOSURE:  # (also nan)
        raise argparse.ArgumentTypeError(f"expected an exposure in stops from {-MAX_EXPOSURE:g} to "
                                         f"{MAX_EXPOSURE:g}, got '{text}'")
    return v


def add_display_options(p: argparse.ArgumentParser) -> None:
    """Add the display-output options to a render-like subcommand."""
    g = p.add_argument_group("display outputs")
    g.add_argument("--multiview-exr", action="store_true",
                   help="also write <stem>.exr: one part per view, part name and 'view' attribute = view id")
    g.add_argument("--stereo", action="store_true",
                   help="name the two views of the multi-view EXR 'left' (first) and 'right'")
    g.add_argument("--quilt", nargs="?", const="auto", default=None, metavar="COLSxROWS|DEVICE",
                   help="write a Looking Glass quilt <stem>_qs{cols}x{rows}a{aspect}.png (view 0 bottom-left; "
                        "default layout near-square; a device's layout: " + ", ".join(looking_glass.DEVICES) + ")")
    g.add_argument("--contact-sheet", action="store_true", help="write <stem>_contact.png: labelled thumbnails")
    g.add_argument("--gif", action="store_true", help="write <stem>.gif with the views as frames, in scene order")
    g.add_argument("--mp4", action="store_true", help="write <stem>.mp4 (H.264) with the views as frames")
    g.add_argument("--fps", type=_fps, default=12.0, help="frame rate of --gif/--mp4 (default: 12)")
    g.add_argument("--exposure", type=_exposure, default=0.0,
                   help=f"exposure in stops for the 8-bit displays, within ±{MAX_EXPOSURE:g} (default: 0)")


def check_display_options(args) -> str | None:
    """A usage error message for inconsistent display options, or None."""
    if args.stereo and not args.multiview_exr:
        return "--stereo names the views of --multiview-exr; add --multiview-exr"
    if args.quilt not in (None, "auto"):
        try:
            args.quilt = _grid(args.quilt)
        except argparse.ArgumentTypeError as e:
            return f"--quilt: {e}"
    return None


def check_displays_for(args, sizes: list) -> str | None:
    """A usage error for display options that the views to render cannot meet, or None: checked
    before rendering, so that no render is lost to them. `sizes`: each view's (width, height)."""
    n = len(sizes)
    if getattr(args, "multiview_exr", False) and args.stereo and n != 2:
        return f"--stereo names two views, left and right; the render has {n}"
    framed = [name for name, on in (("--quilt", args.quilt), ("--gif", args.gif), ("--mp4", args.mp4)) if on]
    if framed and len(set(sizes)) > 1:
        (w0, h0), (w, h) = sizes[0], next(s for s in sizes if s != sizes[0])
        return f"{framed[0]} needs views of one size; the render has {w0}x{h0} and {w}x{h}"
    if args.quilt:
        cols, rows = (None, None) if args.quilt == "auto" else args.quilt
        try:
            cols, rows = quilt.layout(n, cols, rows)
        except ValueError as e:
            return f"--quilt: {e}"
        w, h = sizes[0]
        if cols * rows * w * h > MAX_QUILT_PIXELS:
            return (f"--quilt: a {cols}x{rows} quilt of {w}x{h} views has {cols * rows * w * h:,} pixels, "
                    f"more than {MAX_QUILT_PIXELS:,}")
    if args.mp4:
        try:
            movie.check_ffmpeg()
        except RuntimeError as e:
            return f"--mp4: {e}"
    return None


def wants_displays(args) -> bool:
    return bool(getattr(args, "multiview_exr", False) or getattr(args, "quilt", None) or
                getattr(args, "contact_sheet", False) or getattr(args, "gif", False) or getattr(args, "mp4", False))


def write_displays(result, args, out_dir, stem: str) -> list:
    """Write the display outputs `args` asks for; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    views = list(result.images.values())
    written = []
    if args.multiview_exr:
        written.append(write_multiview_exr(result, multiview_exr_path(out, stem), stereo=args.stereo,
                                           aovs=getattr(args, "aovs", False)))
    if args.quilt:
        cols, rows = (None, None) if args.quilt == "auto" else args.quilt
        written.append(quilt.write_quilt(views, out, _safe(stem), cols, rows, exposure=args.exposure))
    if args.contact_sheet:
        written.append(contact_sheet.write_contact_sheet(result.images, out / f"{_safe(stem)}_contact.png",
                                                         exposure=args.exposure))
    if args.gif:
        written.append(movie.write_gif(views, out / f"{_safe(stem)}.gif", fps=args.fps, exposure=args.exposure))
    if args.mp4:
        written.append(movie.write_mp4(views, out / f"{_safe(stem)}.mp4", fps=args.fps, exposure=args.exposure))
    return written
