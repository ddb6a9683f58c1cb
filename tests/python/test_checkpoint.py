"""Render state files (docs/checkpoints.md): an interrupted render resumes to the bit-identical
images of one that was never stopped (path tracing under a box and a splatted gaussian filter,
both multi-view estimators, adaptive maps on, another thread count), through the API and the command line (SIGINT, SIGTERM, SIGHUP);
a state of another scene, setting or mvpt version is refused naming what differs; a truncated
or corrupt file is refused with one line."""
from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import mvpt
from mvpt import cli
from mvpt import state as state_file

from small_scenes import slow_scene

pytestmark = pytest.mark.serial  # signals arrive at set times: never beside other tests

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
CLI = [sys.executable, "-m", "mvpt.cli"]
SCENES = Path(__file__).resolve().parents[1] / "scenes" / "mv"


def _interrupt_at(n_passes: int):
    """A progress callback that interrupts the render once `n_passes` passes are done."""
    def progress(p):
        if p["pass"] >= n_passes:
            raise KeyboardInterrupt
    return progress


def _assert_same(a, b):
    for v in a.images:
        assert np.array_equal(a.images[v], b.images[v]), v
        assert np.array_equal(a.variance[v], b.variance[v]), v
        assert np.array_equal(a.sample_count[v], b.sample_count[v]), v
        if v in a.contributions:
            assert np.array_equal(a.contributions[v], b.contributions[v]), v
            assert np.array_equal(a.weight_sum[v], b.weight_sum[v]), v


def _mvpath(estimator: str):
    xml = (SCENES / "cornell_phong9.xml").read_text()
    src = '<integrator type="$integrator">'
    assert src in xml
    xml = xml.replace(src, f'<integrator type="mvpath"><string name="estimator" value="{estimator}"/>', 1)
    return mvpt.load_string(xml, SCENES, res=24)


def _gaussian(xml: str) -> str:
    """The scene's films with a gaussian filter: path tracing splats its samples."""
    assert xml.count('<rfilter type="box"/>') >= 1
    return xml.replace('<rfilter type="box"/>', '<rfilter type="gaussian"/>')


CASES = {  # name: (scene, method, spp); the multi-view ones make adaptive maps after 4 passes
    "pt": (lambda: mvpt.load_string(slow_scene(3, res=24)), "pt", 40),
    "pt-splats": (lambda: mvpt.load_string(_gaussian(slow_scene(3, res=24))), "pt", 40),
    "mvpt-balance": (lambda: _mvpath("balance"), "mvpt", 24),
    "mvpt-weighted": (lambda: _mvpath("weighted"), "mvpt", 24),
}


@pytest.mark.parametrize("name", list(CASES))
def test_resume_is_bit_identical(tmp_path, name):
    make, method, spp = CASES[name]
    scene = make()
    whole = mvpt.render(scene, spp=spp, seed=7, method=method, threads=2)
    rng = random.Random(name)
    # After one pass the balance estimator's state holds its first pass for the second's fold.
    for stop in [1] + sorted(rng.sample(range(2, 15), 2)):
        state = tmp_path / f"{stop}.mvpt-state"
        part = mvpt.render(scene, spp=spp, seed=7, method=method, threads=2, state=state, poll=0.001,
                           progress=_interrupt_at(stop))
        assert part.stats["cancelled"] and 1 <= part.stats["passes"] < whole.stats["passes"], part.stats["passes"]
        assert state.exists()
        # Resumed on one thread, interrupted once more, then finished.
        again = mvpt.render(scene, spp=spp, seed=7, method=method, threads=1, state=state, resume=state,
                            poll=0.001, progress=_interrupt_at(part.stats["passes"] + 2))
        assert again.stats["resumed_from_pass"] == part.stats["passes"]
        done = mvpt.render(scene, spp=spp, seed=7, method=method, threads=2, state=state, resume=state)
        assert done.stats["resumed_from_pass"] == again.stats["passes"] and not done.stats["cancelled"]
        assert done.stats["passes"] == whole.stats["passes"] and done.stats["samples"] == whole.stats["samples"]
        _assert_same(whole, done)


def test_resume_refuses_other_settings(tmp_path, monkeypatch):
    scene = mvpt.load_string(slow_scene(2, res=16))
    state = tmp_path / "s.mvpt-state"
    mvpt.render(scene, spp=4, seed=1, method="mvpt", state=state)
    mvpt.render(scene, spp=4, seed=1, method="mvpt", resume=state)  # the same: accepted
    for change, word in ((dict(spp=8), "spp"), (dict(seed=2), "seed"), (dict(method="pt"), "method"),
                         (dict(views=[0]), "views"), (dict(time=1.0), "time"), (dict(splits="auto"), "splits")):
        kw = dict(spp=4, seed=1, method="mvpt") | change
        with pytest.raises(mvpt.StateError, match=f"cannot resume from .*{word}: "):
            mvpt.render(scene, **kw, resume=state)
    phong = mvpt.load_file(SCENES / "cornell_phong9.xml", res=8)
    mvpt.render(phong, spp=2, seed=1, views=[0, 1], state=state)
    with pytest.raises(mvpt.StateError, match="the -D overrides: .*'filter': 'gaussian'"):
        mvpt.render(mvpt.load_file(SCENES / "cornell_phong9.xml", res=8, filter="gaussian"), spp=2, seed=1,
                    views=[0, 1], resume=state)
    monkeypatch.setattr(state_file, "__version__", "0.0.0")
    with pytest.raises(mvpt.StateError, match="mvpt version .* wrote it, this is 0.0.0"):
        mvpt.render(scene, spp=4, seed=1, method="mvpt", resume=state)


def test_resume_refuses_a_changed_scene_file(tmp_path):
    xml = tmp_path / "room.xml"
    xml.write_text(slow_scene(2, res=16))
    state = tmp_path / "s.mvpt-state"
    mvpt.render(mvpt.load_file(xml), spp=2, seed=1, state=state)
    xml.write_text(slow_scene(2, res=16).replace("<scene", "<!-- edited -->\n<scene", 1))
    with pytest.raises(mvpt.StateError, match="room.xml has changed"):
        mvpt.render(mvpt.load_file(xml), spp=2, seed=1, resume=state)


def test_scene_source_files(tmp_path):
    """The files a scene is read from: its XML, its includes, and the data files they name."""
    mesh = tmp_path / "tri.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (tmp_path / "inc.xml").write_text('<scene version="3.0.0"><shape type="obj"><string name="filename" '
                                      'value="tri.obj"/></shape></scene>')
    xml = slow_scene(1, res=8).replace("</scene>", '<include filename="inc.xml"/></scene>')
    (tmp_path / "main.xml").write_text(xml)
    scene = mvpt.load_file(tmp_path / "main.xml")
    assert scene.source_files == [str(tmp_path / "main.xml"), str(tmp_path / "inc.xml"), str(mesh)]


@pytest.mark.parametrize("method", ["pt", "mvpt"])
def test_time_budget_is_the_total(tmp_path, method):
    """Under a time budget a resume spends what is left of it: a state that used it all adds nothing."""
    scene = mvpt.load_string(slow_scene(2, res=16))
    state = tmp_path / "s.mvpt-state"
    first = mvpt.render(scene, time=0.3, seed=1, method=method, state=state)
    later = mvpt.render(scene, time=0.3, seed=1, method=method, state=state, resume=state)
    assert later.stats["resumed_from_pass"] == first.stats["passes"] == later.stats["passes"]
    _assert_same(first, later)


def _corrupt(path: Path, how: str):
    data = bytearray(path.read_bytes())
    if how == "truncated":
        path.write_bytes(bytes(data[: len(data) * 2 // 3]))
    elif how == "flipped":
        data[len(data) // 2] ^= 0x10
        path.write_bytes(bytes(data))
    elif how == "header":  # a digit of the JSON header changed: still valid JSON, only the checksum tells
        start = 8 + 4 + 8
        i = next(i for i in range(start, len(data)) if chr(data[i]).isdigit())
        data[i] = ord("7") if data[i] != ord("7") else ord("3")
        path.write_bytes(bytes(data))
    elif how == "appended":
        path.write_bytes(bytes(data) + b"\0")
    else:
        path.write_bytes(b"not a state file at all")


@pytest.mark.parametrize("how,message", [("truncated", "is truncated"), ("flipped", "is corrupt"),
                                         ("header", "is corrupt"),
                                         ("appended", "is corrupt"), ("garbage", "is not an mvpt state file")])
def test_corrupt_state_is_refused(tmp_path, capsys, how, message):
    scene_path = tmp_path / "room.xml"
    scene_path.write_text(slow_scene(2, res=16))
    out = tmp_path / "out"
    assert cli.main(["render", str(scene_path), "--spp", "3", "--checkpoint", "100", "-o", str(out), "-q"]) == 0
    state = out / f"room{state_file.SUFFIX}"
    _corrupt(state, how)
    capsys.readouterr()
    assert cli.main(["render", "--resume", str(out), "-q"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mvpt: error: ") and message in err[0], err
    with pytest.raises(mvpt.StateError, match=message):
        mvpt.render(mvpt.load_file(scene_path), spp=3, resume=state)


def test_resume_takes_no_image_options(tmp_path, capsys):
    assert cli.main(["render", "--resume", str(tmp_path), "--spp", "4"]) == 2
    assert "--resume continues a render with its own scene and settings; drop --spp" in capsys.readouterr().err
    assert cli.main(["render", "--resume", str(tmp_path)]) == 1
    assert "holds no render state (.mvpt-state)" in capsys.readouterr().err


SIGNALLED = ["--spp", "400", "--seed", "3", "--method", "mvpt", "--aovs", "-q"]


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The scene of test_cli_signal_then_resume and its render never stopped."""
    path = tmp_path_factory.mktemp("signalled") / "slow.xml"
    path.write_text(slow_scene(3, res=32))
    whole = path.parent / "whole"
    assert subprocess.run(CLI + ["render", str(path), *SIGNALLED, "-o", str(whole)], env=ENV).returncode == 0
    assert not (whole / "slow.mvpt-state").exists()  # a finished render keeps no state unless asked
    return path, whole


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_cli_signal_then_resume(tmp_path, sig, uninterrupted):
    path, whole = uninterrupted
    args = SIGNALLED
    out = tmp_path / "out"
    proc = subprocess.Popen(CLI + ["render", str(path), *args, "--checkpoint", "0.2", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 60
        while not (out / "slow.mvpt-state").exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 128 + int(sig), stderr
    assert "Traceback" not in stderr and f"mvpt render --resume {out}" in stderr
    cut = json.loads((out / "slow.json").read_text())
    assert cut["cancelled"] and cut["passes"] < json.loads((whole / "slow.json").read_text())["passes"]
    resumed = subprocess.run(CLI + ["render", "--resume", str(out), "--threads", "1", "-q"], env=ENV,
                             capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    data = json.loads((out / "slow.json").read_text())
    assert data["resumed_from_pass"] == cut["passes"] and not data["cancelled"]
    for i in range(3):
        assert (out / f"slow_v{i}.exr").read_bytes() == (whole / f"slow_v{i}.exr").read_bytes()
    assert (out / "slow.mvpt-state").exists()  # --checkpoint keeps the state of the finished render


@pytest.mark.parametrize("method", ["pt", "mvpt"])
def test_range_resumes_to_the_same_state(tmp_path, method):
    """A range of a split render (passes=...) resumes like any render, and its state merges the same."""
    scene = _mvpath("balance") if method == "mvpt" else mvpt.load_string(slow_scene(3, res=24))
    n = 12 if method == "mvpt" else 200  # path tracing runs passes in groups of up to 16
    whole_state, state = tmp_path / "whole.mvpt-state", tmp_path / "part.mvpt-state"
    whole = mvpt.render(scene, seed=4, method=method, passes=(10, n), state=whole_state)
    part = mvpt.render(scene, seed=4, method=method, passes=(10, n), state=state, poll=0.001,
                       progress=_interrupt_at(5))
    assert part.stats["cancelled"] and part.stats["passes"] < n
    with pytest.raises(mvpt.StateError, match=rf"passes: \[10, {n}\] then, \[10, {n + 1}\] now"):
        mvpt.render(scene, seed=4, method=method, passes=(10, n + 1), resume=state)
    done = mvpt.render(scene, seed=4, method=method, passes=(10, n), state=state, resume=state, threads=1)
    _assert_same(whole, done)
    _assert_same(mvpt.merge(scene, [whole_state]), mvpt.merge(scene, [state]))


def test_a_path_rigs_key_file_is_part_of_the_scene(tmp_path):
    """The key file of a camera-path rig (the option or the element) is one of the scene's
    files: a resume refuses a state whose keys have changed."""
    import json
    keys = tmp_path / "keys.json"
    path_keys = [{"time": 0, "position": [0, 1, 5], "target": [0, 0.5, 0]},
                 {"time": 1, "position": [1, 1, 5], "target": [0, 0.5, 0]}]
    keys.write_text(json.dumps({"keys": path_keys}))
    xml = tmp_path / "room.xml"
    xml.write_text(slow_scene(1, res=8))
    rig = f"path:{keys},frames=2,fps=2"
    scene = mvpt.load_file(xml, rig=rig)
    assert scene.source_files[-1] == str(keys)
    text = slow_scene(1, res=8)
    sensor = text[text.index("<sensor"):text.index("</sensor>") + len("</sensor>")]
    element = text.replace(sensor, f'<mvpt:rig type="path" file="keys.json" frames="2" fps="2">{sensor}</mvpt:rig>')
    element = element.replace('<scene version="3.0.0">', '<scene version="3.0.0" xmlns:mvpt="urn:mvpt">', 1)
    (tmp_path / "element.xml").write_text(element)
    assert mvpt.load_file(tmp_path / "element.xml").source_files[1] == str(keys)
    state = tmp_path / "s.mvpt-state"
    mvpt.render(scene, spp=2, seed=1, state=state)
    path_keys[1]["position"] = [2, 1, 5]
    keys.write_text(json.dumps({"keys": path_keys}))
    with pytest.raises(mvpt.StateError, match="keys.json has changed"):
        mvpt.render(mvpt.load_file(xml, rig=rig), spp=2, seed=1, resume=state)
