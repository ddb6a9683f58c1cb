"""Opening .blend files with Blender's Python module (bpy) and loading them into mvpt through
the Mitsuba 3 XML that the exporter writes."""
from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import warnings
from pathlib import Path

from .blend_file import check_blend
from .report import BlendError

INSTALL = 'pip install "mvpt[blender]"'


class BlendWarning(UserWarning):
    """Something of a Blender scene that mvpt renders differently from Cycles, or leaves out."""


def require_bpy():
    """Blender's module, or a BlendError saying how to install it."""
    try:
        import bpy
    except ImportError:
        raise BlendError(f"reading .blend files needs Blender as a Python module: {INSTALL} "
                         f"(bpy 5.0.1, for Python 3.11 only)") from None
    return bpy


@contextlib.contextmanager
def _silenced():
    """Blender's own messages on stdout and stderr (its file reader prints) discarded: what
    matters comes back as the exception's text."""
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved + [null]:
            os.close(fd)


def open_blend(path) -> Path:
    """Make `path` Blender's current file (replacing the data bpy holds)."""
    path = check_blend(path)
    bpy = require_bpy()
    try:
        with _silenced():
            bpy.ops.wm.open_mainfile(filepath=str(path.resolve()), load_ui=False)
    except RuntimeError as e:
        reason = str(e).strip().splitlines()[-1] if str(e).strip() else "unknown error"
        raise BlendError(f"{path}: Blender cannot open it: {reason}") from None
    return path


def export_blend(path, folder, frames=None):
    """Convert the .blend file `path` into `folder` (Mitsuba 3 XML + PLY meshes): an Export
    with the XML's path, warnings and notes. frames: (first, last), Blender's frame numbers,
    for a shot of one view per frame (default: the current frame)."""
    from .exporter import export_current
    path = open_blend(path)
    if not bpy_scene_has_camera():
        raise BlendError(f"{path}: its scene has no camera to render from")
    try:
        return export_current(folder, name=path.stem, frames=frames)
    except ValueError as e:
        raise BlendError(f"{path}: {e}") from None


def bpy_scene_has_camera() -> bool:
    import bpy
    camera = bpy.context.scene.camera
    return camera is not None and camera.type == "CAMERA"


def load_blend(path, folder=None, rig=None, frames=None, **defines):
    """An mvpt Scene from a .blend file: its current scene converted to Mitsuba 3 XML in
    `folder` (kept, to edit or render again), or in a temporary folder removed once loaded;
    `frames` (first, last) converts that range of Blender's frames as a shot, one view per frame.
    Each conversion warning is issued as a BlendWarning. Keyword arguments override the
    scene's <default>s (spp, width, height, max_depth), as in mvpt.load_file."""
    from .. import api
    temporary = folder is None
    target = Path(tempfile.mkdtemp(prefix="mvpt-blend-")) if temporary else Path(folder)
    try:
        result = export_blend(path, target, frames)
        for text in result.warnings:
            warnings.warn(text, BlendWarning, stacklevel=2)
        return api.load_file(result.xml, rig=rig, **defines)
    finally:
        if temporary:
            shutil.rmtree(target, ignore_errors=True)
