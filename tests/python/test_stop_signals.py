"""SIGINT, SIGTERM and SIGHUP from the start of the `mvpt` program to the end of its process:
one that comes while it starts is handled; one that comes as the program exits (Python's shutdown once set the default action back,
and the process died of the signal with its outputs written) gives the signal's exit code;
Ctrl-C twice then SIGTERM while finishing exits 130; a signal during a long scene load (a rig
of many views) is answered within a fraction of the load."""
from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import mvpt
from mvpt import _core

from small_scenes import scene, sensor, views

pytestmark = pytest.mark.serial  # signals arrive at set times: never beside other tests

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))

# Runs the program like its entry point and, while Python shuts down (after its signal
# handling is torn down: a __main__ global is deleted then), sends itself the signals argv[2:].
_SIGNALS_AT_SHUTDOWN = """
import os, sys
from mvpt import cli

class SignalsAtShutdown:
    def __del__(self, kill=os.kill, pid=os.getpid(), signals=[int(s) for s in sys.argv[2:]]):
        for s in signals:
            kill(pid, s)

at_shutdown = SignalsAtShutdown()
sys.argv = ["mvpt", "render", sys.argv[1], "-q", "-o", os.path.join(os.path.dirname(sys.argv[1]), "out")]
sys.exit(cli.command())
"""


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("stop") / "many.xml"
    path.write_text(scene(views(40, res=24, spp=2)))
    return path


def _whole_set(out: Path) -> dict:
    data = json.loads((out / "many.json").read_text())
    for vid in data["views"]:
        _core.read_image(str(out / f"many_{vid}.exr"))
        _core.read_image(str(out / f"many_{vid}.png"))
    return data


@pytest.mark.parametrize("signals", [(signal.SIGTERM,), (signal.SIGHUP,), (signal.SIGINT, signal.SIGINT, signal.SIGTERM)],
                         ids=["TERM", "HUP", "INT-INT-TERM"])
def test_signals_during_shutdown_give_the_first_ones_code(small, tmp_path, signals):
    scene_path = tmp_path / small.name
    scene_path.write_text(small.read_text())
    proc = subprocess.run([sys.executable, "-c", _SIGNALS_AT_SHUTDOWN, str(scene_path)] + [str(int(s)) for s in signals],
                          env=ENV, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 128 + int(signals[0]), (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr and "Exception" not in proc.stderr, proc.stderr
    assert not _whole_set(tmp_path / "out")["cancelled"]


def _caught(pid: int) -> int:
    """The mask of the signals that process `pid` catches (0 once it is gone)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("SigCgt:"):
                return int(line.split()[1], 16)
    except OSError:
        pass
    return 0


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_as_the_program_starts_is_handled(small, tmp_path, sig):
    """While NumPy and the native core load (a tenth of a second or more), SIGTERM killed the
    program and Ctrl-C printed a traceback: its handlers came after. The signal is sent 60 to
    150 ms after Python's own start (once it catches SIGINT): the program then still imports."""
    rng = random.Random(int(sig))
    for k in range(3):
        proc = subprocess.Popen([sys.executable, "-m", "mvpt", "render", str(small), "-q", "-o", str(tmp_path / f"t{k}")],
                                env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 60
        while not _caught(proc.pid) & (1 << (signal.SIGINT - 1)) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.0005)
        time.sleep(rng.uniform(0.06, 0.15))
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode in (128 + int(sig), 0), (proc.returncode, err)  # (0: it had finished)
        assert "Traceback" not in err, err


def _render_then_signal(path: Path, out: Path, schedule, after_json: bool) -> tuple:
    """`mvpt render` of `path` into `out`, sending the signals of `schedule` ((seconds, signal)
    pairs) that long after the JSON appeared (`after_json`) or after the render began (its
    first line); the exit code and stderr."""
    proc = subprocess.Popen([sys.executable, "-m", "mvpt", "render", str(path), "-o", str(out)], env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().startswith("rendering")
    deadline = time.monotonic() + 120
    while after_json and not (out / "many.json").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.0005)
    t0 = time.monotonic()
    for delay, sig in schedule:
        time.sleep(max(0.0, t0 + delay - time.monotonic()))
        if proc.poll() is None:
            proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_a_signal_as_the_program_exits_is_not_fatal(small, tmp_path, sig):
    """SIGTERM or SIGHUP 0-25 ms after the JSON appeared killed the process in 5 of 6 trials."""
    rng = random.Random(int(sig))
    for k in range(4):
        out = tmp_path / f"t{k}"
        rc, err = _render_then_signal(small, out, [(rng.uniform(0.0, 0.025), sig)], after_json=True)
        assert rc in (0, 128 + int(sig)), (rc, err)  # 0: it had exited before the signal
        assert "Traceback" not in err, err
        _whole_set(out)


def test_ctrl_c_twice_then_sigterm_exits_130(small, tmp_path):
    """SIGINT, SIGINT, SIGTERM 50 ms apart at random points of a render, its writing and its
    exit: a whole set of outputs (or the previous none) and exit 130 (0: it ended first)."""
    rng = random.Random(3)
    for k in range(4):
        out = tmp_path / f"t{k}"
        start = rng.uniform(0.0, 0.6)
        rc, err = _render_then_signal(small, out, [(start, signal.SIGINT), (start + 0.05, signal.SIGINT),
                                                   (start + 0.1, signal.SIGTERM)], after_json=False)
        assert rc in (0, 130), (rc, err)
        assert "Traceback" not in err, err
        if (out / "many.json").exists():
            _whole_set(out)


def _interrupted_load(path: Path, rig: str, after: float) -> float:
    """Seconds from a SIGINT `after` seconds into mvpt.load_file to its KeyboardInterrupt (sent by
    another process: a thread of this one would wait for the GIL)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    sender = None
    try:
        with pytest.raises(KeyboardInterrupt):
            sent = time.monotonic() + after
            sender = subprocess.Popen(["sh", "-c", f"sleep {after:.3f}; kill -INT {os.getpid()}"])
            mvpt.load_file(path, rig=rig)
            time.sleep(1.0 + after)  # (the interrupt came after the load: raised here)
        latency = time.monotonic() - sent
    finally:
        if sender is not None:
            sender.wait()
        signal.signal(signal.SIGINT, previous)
    return latency


def test_ctrl_c_stops_a_long_load(tmp_path):
    """The load of a rig of 10^5 views held the GIL: Ctrl-C was answered once it was done (27-36 s
    on two cores at 512^2). It runs on a thread of its own and stops between views."""
    path = tmp_path / "base.xml"
    path.write_text(scene(sensor(res=4)))
    rig = "grid:200x200,spacing=0.001"
    mvpt.load_file(path, rig="grid:10x10,spacing=0.001")  # (the first load's costs)
    t = time.monotonic()
    mvpt.load_file(path, rig=rig)
    whole = time.monotonic() - t
    latency = _interrupted_load(path, rig, 0.15 * whole)
    assert latency < 0.5 * whole, (latency, whole)  # (uninterrupted: 0.85)


def _resident_mib(pid: int) -> float:
    try:
        return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * os.sysconf("SC_PAGESIZE") / 2**20
    except (OSError, IndexError, ValueError):
        return 0.0


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_the_program_stops_while_loading(tmp_path, sig):
    """The command line answers a signal during the load with the signal's exit code and one line."""
    path = tmp_path / "base.xml"
    path.write_text(scene(sensor(res=4)))
    # 90000 views of 4 x 4 pixels (their images fit): a load of seconds on two cores.
    proc = subprocess.Popen([sys.executable, "-m", "mvpt", "render", str(path), "--rig", "grid:300x300,spacing=0.001", "-o",
                             str(tmp_path / "out")], env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # The load is under way once the process holds more than Python and the libraries (about 70
    # MiB; the whole load about 800).
    deadline = time.monotonic() + 60
    while _resident_mib(proc.pid) < 200 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    sent = time.monotonic()
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    answered = time.monotonic() - sent
    assert proc.returncode == 128 + int(sig), (proc.returncode, err)
    assert out == "" and err.strip() == "mvpt: interrupted", (out, err)  # in the load: nothing rendered
    assert answered < 10, answered  # (a hang guard: the whole load takes seconds)
