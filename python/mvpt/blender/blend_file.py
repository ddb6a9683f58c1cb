"""Checks that a file is a whole .blend before Blender opens it, so that a wrong or cut-off file
is one clear error line.

A .blend file (uncompressed) starts with "BLENDER" and ends with an ENDB block header (its
last 20 to 32 bytes, by pointer size and header version); Blender 3.0+ may compress it with
Zstandard (magic 28 B5 2F FD), older versions with gzip (1F 8B). A compressed file is read
through to its end, which a truncated one does not reach."""
from __future__ import annotations

import gzip
import os
from pathlib import Path

from .report import BlendError

ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
GZIP_MAGIC = b"\x1f\x8b"
CHUNK = 1 << 20


def _ends(stream) -> tuple[bytes, bytes]:
    """The first 16 and the last 64 bytes of a stream, read through to its end."""
    head = stream.read(16)
    tail = head
    while True:
        chunk = stream.read(CHUNK)
        if not chunk:
            return head, tail[-64:]
        tail = (tail + chunk)[-64:]


def _decompressed_ends(path: Path, magic: bytes) -> tuple[bytes, bytes]:
    if magic.startswith(GZIP_MAGIC):
        try:
            with gzip.open(path, "rb") as f:
                return _ends(f)
        except (EOFError, OSError, gzip.BadGzipFile) as e:
            raise BlendError(f"{path}: the gzip-compressed .blend file is truncated or damaged ({e})") from None
    try:
        import zstandard
    except ImportError:
        raise BlendError(f"{path}: reading a compressed .blend needs the zstandard module "
                         f"(installed with Blender's: pip install \"mvpt[blender]\")") from None
    try:
        with open(path, "rb") as raw, zstandard.ZstdDecompressor().stream_reader(raw, read_across_frames=True) as f:
            head, tail = _ends(f)
    except zstandard.ZstdError as e:
        raise BlendError(f"{path}: the compressed .blend file is truncated or damaged ({e})") from None
    return head, tail


def check_blend(path) -> Path:
    """`path` as a Path if it is a whole .blend file; a BlendError naming it otherwise."""
    path = Path(path)
    if not path.exists():
        raise BlendError(f"{path}: no such file")
    if not path.is_file():
        raise BlendError(f"{path}: not a file")
    if not os.access(path, os.R_OK):
        raise BlendError(f"{path}: cannot be read (permission denied)")
    with open(path, "rb") as f:
        magic = f.read(4)
        if magic == ZSTD_MAGIC or magic.startswith(GZIP_MAGIC):
            head, tail = _decompressed_ends(path, magic)
        else:
            f.seek(0)
            head, tail = _ends(f)
    if not head and (magic == ZSTD_MAGIC or magic.startswith(GZIP_MAGIC)):
        raise BlendError(f"{path}: the compressed .blend file is truncated or damaged (it holds no data)")
    if not head.startswith(b"BLENDER"):
        shown = head[:16].decode("ascii", "backslashreplace")
        raise BlendError(f"{path}: not a Blender file (expected a file starting with 'BLENDER', "
                         f"found {shown!r})")
    if b"ENDB" not in tail[-40:]:
        raise BlendError(f"{path}: the .blend file is truncated (it lacks its end block)")
    return path
