"""A render's outputs appear as a set: SIGINT, SIGTERM and SIGHUP at random points of a render
and of its writing leave a consistent set (the JSON describes every image present: the
previous render's or the new one's); SIGKILL leaves every file whole and, once the JSON is the
new one, every image new, and once recovered (by the next render there) the previous set or the
new one whole; a write that fails (the file-size limit standing in for a full disk)
leaves the previous outputs and no file under a final name."""
from __future__ import annotations

import json
import os
import random
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mvpt import _core

from small_scenes import scene, views

pytestmark = pytest.mark.serial  # kills land at set times: never beside other tests

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
# Path tracing, whatever the command line's default: a render that a signal cuts keeps its
# finished passes, images of neither whole render, which _which cannot name; path tracing's
# two passes are a small part of the run here (the rest is start-up and writing).
CLI = [sys.executable, "-m", "mvpt.cli"]
PT = ["--method", "pt"]
N_VIEWS = 40


@pytest.fixture(scope="module")
def many(tmp_path_factory):
    """A scene of 40 small views, its outputs from seed 1 and from seed 2, and a run's seconds."""
    root = tmp_path_factory.mktemp("set")
    path = root / "many.xml"
    path.write_text(scene(views(N_VIEWS, res=24, spp=2)))
    outs = {}
    for seed in (1, 2):
        out = root / f"seed{seed}"
        t = time.monotonic()
        assert subprocess.run(CLI + ["render", str(path), *PT, "--seed", str(seed), "-q", "-o", str(out)], env=ENV).returncode == 0
        seconds = time.monotonic() - t
        outs[seed] = _read_set(out)
    return path, outs, seconds


def _read_set(out: Path) -> dict:
    """{'json': the summary, view id: image} of an output directory (every file must be whole)."""
    data = json.loads((out / "many.json").read_text())
    got = {"json": data}
    for vid in data["views"]:
        got[vid] = _core.read_image(str(out / f"many_{vid}.exr"))
        _core.read_image(str(out / f"many_{vid}.png"))
    return got


def _which(images: dict, vid: str, outs: dict) -> int:
    for seed in (1, 2):
        if np.array_equal(images[vid], outs[seed][vid]):
            return seed
    return 0


def _trial(path: Path, out: Path, sig: int, delay: float) -> int:
    """Render seed 2 into `out` and send `sig` `delay` seconds after the render started (its
    first line: mvpt has loaded the scene)."""
    proc = subprocess.Popen(CLI + ["render", str(path), *PT, "--seed", "2", "-o", str(out)], env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    first = proc.stdout.readline()
    assert first.startswith("rendering"), first
    time.sleep(delay)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert "Traceback" not in err, err
    return proc.returncode


def _previous(out: Path, path: Path):
    assert subprocess.run(CLI + ["render", str(path), *PT, "--seed", "1", "-q", "-o", str(out)], env=ENV).returncode == 0


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_signals_leave_a_consistent_set(many, tmp_path, sig):
    path, outs, seconds = many
    rng = random.Random(int(sig))
    for k in range(4):
        out = tmp_path / f"t{k}"
        _previous(out, path)
        rc = _trial(path, out, sig, rng.uniform(0.0, 0.9) * seconds)
        got = _read_set(out)
        seeds = {_which(got, v, outs) for v in got["json"]["views"]}
        assert len(seeds) == 1 and 0 not in seeds, seeds  # one render's images, all of them
        (seed,) = seeds
        assert got["json"]["settings"]["seed"] == seed  # and the JSON that describes them
        assert rc in (0, 128 + int(sig)), rc  # never a death by the signal (test_stop_signals.py)
        assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no staging left


def test_sigkill_leaves_whole_files(many, tmp_path):
    path, outs, seconds = many
    rng = random.Random(9)
    for k in range(6):
        out = tmp_path / f"k{k}"
        _previous(out, path)
        _trial(path, out, signal.SIGKILL, rng.uniform(0.0, 0.9) * seconds)
        got = _read_set(out)  # every file present reads whole
        seeds = {_which(got, v, outs) for v in got["json"]["views"]}
        assert 0 not in seeds
        if got["json"]["settings"]["seed"] == 2:
            assert seeds == {2}  # the JSON moves last: a new JSON means a complete new set
        # A later render removes the killed one's staging directory.
        _previous(out, path)
        assert not [p for p in out.iterdir() if p.name.startswith(".")]


# Writes a set of four files with staged_outputs and SIGKILLs itself at a chosen move: before the
# commit record (-1) or before the k-th file's move.
_KILLED_WHILE_MOVING = """
import os, signal, sys
from pathlib import Path
from mvpt import output
out, kill_at = Path(sys.argv[1]), int(sys.argv[2])
real, moved = os.replace, []
def replace(src, dst):
    if Path(dst).name == output.COMMIT_RECORD and kill_at == -1:
        os.kill(os.getpid(), signal.SIGKILL)
    if Path(dst).parent == out:
        if len(moved) == kill_at:
            os.kill(os.getpid(), signal.SIGKILL)
        moved.append(src)
    real(src, dst)
os.replace = replace
with output.staged_outputs(out) as (staging, written):
    for name in ("set_a.exr", "set_b.exr", "set_a.png", "set.json"):
        (staging / name).write_text("new " + name)
        written.append(str(staging / name))
"""


@pytest.mark.parametrize("kill_at", [-1, 0, 1, 2, 3])
def test_sigkill_while_moving_leaves_one_set_once_recovered(tmp_path, kill_at):
    """SIGKILL between the moves into place: the next mvpt that writes there (recover_outputs)
    finishes a set whose commit record was written and removes one whose record was not, so
    the directory holds the previous set or the new one, whole."""
    from mvpt import output
    out = tmp_path / "out"
    out.mkdir()
    names = ("set_a.exr", "set_b.exr", "set_a.png", "set.json")
    for name in names:
        (out / name).write_text("old " + name)
    proc = subprocess.run([sys.executable, "-c", _KILLED_WHILE_MOVING, str(out), str(kill_at)], env=ENV)
    assert proc.returncode == -signal.SIGKILL
    output.recover_outputs(out)
    contents = {(out / name).read_text().split()[0] for name in names}
    assert contents == ({"old"} if kill_at == -1 else {"new"}), contents
    assert sorted(p.name for p in out.iterdir()) == sorted(names)  # no staging left


def _limit_file_size(limit: int):
    def setup():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG) instead
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return setup


def test_png_write_errors_are_checked(tmp_path):
    """stb's file writer ignored write errors: a full disk left an empty PNG."""
    target = tmp_path / "big.png"
    code = ("import numpy as np, sys; from mvpt import _core\n"
            "img = np.random.default_rng(1).random((256, 256, 3), dtype=np.float32)\n"
            "try:\n    _core.write_png(sys.argv[1], img)\nexcept RuntimeError as e:\n    print(e); sys.exit(3)\n")
    proc = subprocess.run([sys.executable, "-c", code, str(target)], env=ENV, capture_output=True, text=True,
                          preexec_fn=_limit_file_size(20000))
    assert proc.returncode == 3 and "cannot write PNG" in proc.stdout, (proc.stdout, proc.stderr)
    assert list(tmp_path.iterdir()) == []


def test_full_disk_keeps_the_previous_outputs(many, tmp_path):
    path, outs, _ = many
    out = tmp_path / "full"
    _previous(out, path)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    proc = subprocess.run(CLI + ["render", str(path), "--seed", "2", "-q", "-o", str(out)], env=ENV,
                          capture_output=True, text=True, preexec_fn=_limit_file_size(3000))
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 1 and len(err) == 1 and err[0].startswith("mvpt: error: cannot write"), proc.stderr
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_second_ctrl_c_keeps_the_finished_passes(tmp_path):
    """Ctrl-C twice (a tenth of a second apart, as people press it) still writes the passes
    finished before the first."""
    path = tmp_path / "slow.xml"
    from small_scenes import slow_scene
    path.write_text(slow_scene(4, res=64))
    out = tmp_path / "out"
    proc = subprocess.Popen(CLI + ["render", str(path), "--spp", "100000", "--method", "mvpt", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().startswith("rendering")
    time.sleep(1.5)
    for _ in range(2):
        proc.send_signal(signal.SIGINT)
        time.sleep(0.1)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err, err
    data = json.loads((out / "slow.json").read_text())
    assert data["cancelled"] and data["passes"] >= 1
    assert all((out / f"slow_v{i}.exr").exists() for i in range(4))


def test_the_program_catches_signals_once_done(tmp_path, monkeypatch):
    """The `mvpt` program keeps catching the signals after the render: a second Ctrl-C that comes
    once the outputs are written (a render stopped within a tenth of a second) must not meet
    the default handler, which Python's shutdown restores and which would kill the process
    (exit -2, not 130), nor raise a KeyboardInterrupt. Python's table says "ignored" (its
    shutdown leaves those alone); the operating system's handler records them."""
    from mvpt import cli, stop_signals
    path = tmp_path / "s.xml"
    path.write_text(scene(views(1, res=8, spp=1)))
    monkeypatch.setattr(sys, "argv", ["mvpt", "render", str(path), "-q", "-o", str(tmp_path / "out")])
    previous = {s: signal.getsignal(s) for s in stop_signals.STOPS}
    try:
        assert cli.command() == 0
        assert all(signal.getsignal(s) is signal.SIG_IGN for s in stop_signals.STOPS)
        os.kill(os.getpid(), signal.SIGINT)  # recorded natively: no KeyboardInterrupt
        time.sleep(0.05)
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)  # (and the exit code of this process is left alone)
        stop_signals.reset()


def test_a_signal_after_the_work_is_done_raises_nothing():
    """A signal that comes while the command restores its handlers (the render and its outputs
    are complete) must not raise into that code: it printed a traceback once (a SIGTERM 30 ms
    into a render short enough to have finished). It is recorded: the exit code says so."""
    from mvpt import stop_signals
    try:
        stop_signals.reset()
        stop_signals.interruptible = False
        stop_signals.on_signal(signal.SIGTERM, None)
        assert stop_signals.stopped_by == signal.SIGTERM and stop_signals.final_code(0) == 143
        stop_signals.reset()
        with pytest.raises(KeyboardInterrupt):
            stop_signals.on_signal(signal.SIGTERM, None)
    finally:
        stop_signals.reset()
