"""Animated shots: frames (linear RGB views, in order) to an animated GIF (Pillow) or an H.264 MP4 (ffmpeg).

ffmpeg is the one on PATH, else the binary of the `imageio-ffmpeg` package. The MP4 is
yuv420p (the pixel format every player reads), so odd frame sizes are padded by one
black row/column."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np

from .images import as_rgb, srgb8


def _frames8(frames: list, exposure: float) -> list:
    if not frames:
        raise ValueError("a movie needs at least one frame")
    out = [srgb8(as_rgb(f), exposure) for f in frames]
    h, w = out[0].shape[:2]
    for i, f in enumerate(out):
        if f.shape[:2] != (h, w):
            raise ValueError(f"frame {i} is {f.shape[1]}x{f.shape[0]} but frame 0 is {w}x{h}: frames must match")
    return out


def write_gif(frames: list, path, fps: float = 12.0, exposure: float = 0.0, loop: bool = True) -> str:
    """Animated GIF of the frames at `fps` (looping unless `loop` is False); returns the path."""
    from PIL import Image

    if not fps > 0:
        raise ValueError(f"fps must be > 0, got {fps}")
    images = [Image.fromarray(f) for f in _frames8(frames, exposure)]
    extra = {"loop": 0} if loop else {}
    images[0].save(Path(path), format="GIF", save_all=True, append_images=images[1:],
                   duration=max(1, round(1000.0 / fps)), **extra)
    return str(path)


def ffmpeg_executable() -> str:
    """Path of an ffmpeg binary: PATH first, then imageio-ffmpeg's; RuntimeError if there is none."""
    exe = shutil.which("ffmpeg")
    if exe:
        return exe
    try:
        import imageio_ffmpeg
        return imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        raise RuntimeError("writing MP4 needs ffmpeg: install Debian's 'ffmpeg' or pip install imageio-ffmpeg") from None


def check_ffmpeg() -> str:
    """The ffmpeg binary (ffmpeg_executable) once it has answered `-version`; RuntimeError naming
    it when it does not run."""
    exe = ffmpeg_executable()
    try:
        ok = subprocess.run([exe, "-version"], capture_output=True, timeout=20).returncode == 0
    except (OSError, subprocess.SubprocessError):
        ok = False
    if not ok:
        raise RuntimeError(f"writing MP4 needs a working ffmpeg, and '{exe} -version' failed")
    return exe


def write_mp4(frames: list, path, fps: float = 24.0, exposure: float = 0.0, crf: int = 18) -> str:
    """H.264 MP4 of the frames at `fps` (quality `crf`, lower is better); returns the path."""
    if not fps > 0:
        raise ValueError(f"fps must be > 0, got {fps}")
    data = _frames8(frames, exposure)
    h, w = data[0].shape[:2]
    cmd = [ffmpeg_executable(), "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
           "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
           "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", str(int(crf)), "-movflags", "+faststart",
           str(path)]
    proc = subprocess.run(cmd, input=np.ascontiguousarray(np.stack(data)).tobytes(), capture_output=True)
    if proc.returncode != 0:
        raise RuntimeError(f"ffmpeg failed ({proc.returncode}): {proc.stderr.decode(errors='replace').strip()}")
    return str(path)
