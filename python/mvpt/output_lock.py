"""One render at a time per output folder: an advisory lock (flock(2)) on the folder itself,
held from before the render until its outputs are written and released by the kernel when the
process ends, however it ends; nothing is left in the folder."""
from __future__ import annotations

import fcntl
import os


class FolderBusy(RuntimeError):
    """Another process holds the output folder."""


class FolderLock:
    """Holds `folder` (which exists) from construction until the end of its `with` block;
    FolderBusy when another render holds it, OSError when it cannot be opened."""

    def __init__(self, folder):
        self.fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self.fd)
            raise FolderBusy(f"another render holds {folder}/ (it writes its images or state there); wait for it "
                             f"to end or choose another -o") from None

    def __enter__(self) -> "FolderLock":
        return self

    def __exit__(self, *exc) -> None:
        os.close(self.fd)
