"""A state file made up to pass its checksum is still refused when what it holds cannot come
from a render: sums that are not finite, a sample map beyond the adaptive maximum, more
passes in a pixel than the state has. (A damaged file is test_checkpoint.py's.)"""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

import mvpt
from small_scenes import slow_scene

MASK = (1 << 64) - 1


def _mix(h: int, w: int) -> int:
    h ^= (w * 0x9E3779B97F4A7C15) & MASK
    return ((((h << 29) | (h >> 35)) & MASK) * 0xBF58476D1CE4E5B9) & MASK


def _hash(h: int, data: bytes) -> int:
    """render_state.cpp's checksum of one byte string, chained from h."""
    whole = len(data) - len(data) % 8
    for (w,) in struct.iter_unpack("<Q", data[:whole]):
        h = _mix(h, w)
    tail = int.from_bytes(data[whole:] + bytes(8 - len(data) % 8), "little")
    return _mix(_mix(h, tail), len(data))


def _blocks(raw: bytes):
    """The header and the (count, size, data) blocks of a state file."""
    (length,) = struct.unpack_from("<Q", raw, 12)
    header, pos, blocks = raw[20:20 + length], 20 + length, []
    while pos < len(raw) - 8:
        n, size = struct.unpack_from("<QI", raw, pos)
        pos += 12
        blocks.append([n, size, bytearray(raw[pos:pos + n * size])])
        pos += n * size
    return header, blocks


def _forge(path: Path, change) -> None:
    """Rewrites the state at `path` with `change(blocks)` applied and its checksum recomputed."""
    raw = path.read_bytes()
    header, blocks = _blocks(raw)
    change(blocks)
    out, h = bytearray(raw[:20 + len(header)]), _hash(0, header)
    for n, size, data in blocks:
        out += struct.pack("<QI", n, size) + data
        h = _hash(_hash(h, struct.pack("<Q", n)), bytes(data))
    path.write_bytes(bytes(out + struct.pack("<Q", h)))


def _sums(blocks, pixels: int):
    """The first block of 3 doubles per pixel: the first view's sums."""
    return next(b for b in blocks if b[1] == 8 and b[0] == 3 * pixels)


def _nan_sums(blocks):
    b = _sums(blocks, 16 * 16)
    values = np.frombuffer(b[2], np.float64).copy()
    values[5] = np.nan
    b[2][:] = values.tobytes()


def _full_map(blocks):
    for b in blocks:
        if b[1] == 2:  # uint16: the multi-view sample maps
            b[2][:] = np.full(b[0], 65535, np.uint16).tobytes()


def _many_passes(blocks):
    b = next(b for b in blocks if b[1] == 4 and b[0] == 16 * 16)  # the first view's estimate counts
    b[2][:] = np.full(b[0], 1000, np.uint32).tobytes()


@pytest.mark.parametrize("method,change,message", [
    ("pt", _nan_sums, "a pixel's sums are not finite"),
    ("mvpt", _nan_sums, "a pixel's sums are not finite"),
    ("mvpt", _full_map, "its sample map asks for more than 16 samples in a pixel"),
    ("mvpt", _many_passes, "a pixel holds more passes than the state has"),
])
def test_forged_state_is_refused(tmp_path, method, change, message):
    scene = mvpt.load_string(slow_scene(2, res=16))
    state = tmp_path / "s.mvpt-state"
    mvpt.render(scene, spp=4, seed=1, method=method, state=state)
    # Unchanged, rewritten with the test's checksum: resumes (the forging itself is sound).
    _forge(state, lambda blocks: None)
    mvpt.render(scene, spp=4, seed=1, method=method, state=state, resume=state)
    _forge(state, change)
    with pytest.raises(mvpt.StateError, match="the state is not one a render wrote: " + message):
        mvpt.render(scene, spp=4, seed=1, method=method, state=state, resume=state)
