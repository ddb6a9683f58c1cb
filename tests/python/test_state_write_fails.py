"""A state file that cannot be written (here a file-size limit, as a full disk would) does not
cost a render its images: the render goes on without checkpoints, the images are written
whole, and the failure is one line (the command line: exit 1) or stats["state_error"] and a
warning (the API)."""
from __future__ import annotations

import os
import resource
import subprocess
import sys

import pytest

from small_scenes import slow_scene

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
LIMIT = 24 * 1024  # bytes: the images fit, a state of this scene does not


def _limited():
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, LIMIT))


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "room.xml"
    path.write_text(slow_scene(2, res=24))
    return path


def test_the_command_line_keeps_the_images(scene_file, tmp_path):
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "mvpt.cli", "render", str(scene_file), "--spp", "16",
                          "--checkpoint", "0.001", "-q", "-o", str(out)],
                         capture_output=True, text=True, timeout=120, env=ENV, preexec_fn=_limited)
    err = run.stderr.strip().splitlines()
    assert run.returncode == 1 and len(err) == 1, run.stderr
    assert "cannot write the state file" in err[0] and "the images were written to" in err[0], err
    names = sorted(p.name for p in out.iterdir())
    assert {"room.json", "room_v0.exr", "room_v1.exr"} <= set(names), names
    assert not any(n.endswith(".tmp") for n in names), names


def test_the_api_reports_it(scene_file, tmp_path):
    code = ("import mvpt, sys; sc = mvpt.load_file(sys.argv[1]); "
            "r = mvpt.render(sc, spp=16, seed=1, state=sys.argv[2], checkpoint=0.001); "
            "print(r.stats['state_error']); print(r.stats['warnings'][-1]); print(r.stats['passes'])")
    run = subprocess.run([sys.executable, "-c", code, str(scene_file), str(tmp_path / "s.mvpt-state")],
                         capture_output=True, text=True, timeout=120, env=ENV, preexec_fn=_limited)
    assert run.returncode == 0, run.stderr
    error, warning, passes = run.stdout.strip().splitlines()
    assert error.startswith("cannot write the state file") and "File too large" in error, error
    assert warning == f"{error}: the render went on without its state"
    assert passes == "16"
