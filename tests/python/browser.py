"""Headless Chromium for the report tests: load a page, let it run, return its final DOM and console output."""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

NAMES = ("chromium", "chromium-browser", "google-chrome")


def chromium() -> str:
    """The browser binary; skips the test on a developer machine without one, fails under CI (which installs it)."""
    for name in NAMES:
        exe = shutil.which(name)
        if exe:
            return exe
    if os.environ.get("CI"):
        pytest.fail("Chromium is missing under CI: scripts/test.sh installs Debian's 'chromium' for the report tests")
    pytest.skip("Chromium is not installed (apt-get install chromium); the report's browser test needs it")


def _run(args: list, timeout: float) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory(prefix="mvpt-chromium-") as profile:
        cmd = [chromium(), "--headless", "--disable-gpu", "--no-sandbox", "--disable-dev-shm-usage",
               "--no-first-run", "--no-default-browser-check", "--disable-extensions", "--mute-audio",
               "--enable-logging=stderr", "--v=0", f"--user-data-dir={profile}",
               "--virtual-time-budget=10000"] + args
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def dump_dom(page: Path, timeout: float = 120) -> tuple:
    """(DOM after the page's load event, console lines Chromium logged) of a local page."""
    proc = _run(["--dump-dom", Path(page).resolve().as_uri()], timeout)
    if proc.returncode != 0 or not proc.stdout.strip():
        raise RuntimeError(f"chromium failed ({proc.returncode}): {proc.stderr[-2000:]}")
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    return proc.stdout, console


def screenshot(page: Path, png: Path, size: str = "1200,3000", timeout: float = 120) -> Path:
    """A PNG screenshot of a local page (for looking at a report by eye)."""
    _run([f"--screenshot={Path(png).resolve()}", f"--window-size={size}", Path(page).resolve().as_uri()], timeout)
    return png
