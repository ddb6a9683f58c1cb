"""Who owns an output folder: one render at a time holds it (an flock on the folder, released
when the process ends); a render never overwrites or removes a state it did not write; and
`--resume` refuses options it cannot honour and honours the outputs it is given."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mvpt import cli
from mvpt import state as state_file

from small_scenes import slow_scene

pytestmark = pytest.mark.serial  # one test holds a folder from another process: never beside other tests

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
HOLD = ("import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDONLY | os.O_DIRECTORY); "
        "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); time.sleep(60)")


def _scene(tmp_path: Path) -> Path:
    path = tmp_path / "room.xml"
    path.write_text(slow_scene(2, res=16))
    return path


def _err_lines(capsys) -> list:
    return capsys.readouterr().err.strip().splitlines()


def test_a_held_folder_is_refused(tmp_path, capsys):
    scene, out = _scene(tmp_path), tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        for extra in ([], ["--checkpoint", "0.01"]):
            assert cli.main(["render", str(scene), "--spp", "2", "-q", "-o", str(out), *extra]) == 1
            err = _err_lines(capsys)
            assert len(err) == 1 and f"another render holds {out}/" in err[0], err
        assert list(out.iterdir()) == []  # nothing written, no lock file left
    finally:
        holder.kill()
        holder.wait()
    # The holder is gone (the kernel released its lock): the folder is free again.
    assert cli.main(["render", str(scene), "--spp", "2", "-q", "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(["room.json", "room_v0.exr", "room_v1.exr",
                                                             "room_v0.png", "room_v1.png"])


def test_resume_of_a_held_folder_is_refused(tmp_path, capsys):
    scene, out = _scene(tmp_path), tmp_path / "out"
    assert cli.main(["render", str(scene), "--spp", "2", "--checkpoint", "100", "-q", "-o", str(out)]) == 0
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        capsys.readouterr()
        assert cli.main(["render", "--resume", str(out), "-q"]) == 1
        assert f"another render holds {out}/" in _err_lines(capsys)[0]
    finally:
        holder.kill()
        holder.wait()


def test_a_plain_render_keeps_another_renders_state(tmp_path, capsys):
    scene, out = _scene(tmp_path), tmp_path / "out"
    assert cli.main(["render", str(scene), "--spp", "4", "--checkpoint", "100", "-q", "-o", str(out)]) == 0
    state = out / f"room{state_file.SUFFIX}"
    kept = state.read_bytes()
    assert cli.main(["render", str(scene), "--spp", "2", "-q", "-o", str(out)]) == 0
    assert state.read_bytes() == kept
    assert json.loads((out / "room.json").read_text())["settings"]["spp"] == 2
    # A render that would write a state of its own there is refused before it renders.
    capsys.readouterr()
    for extra in (["--checkpoint", "5"], ["--passes", "0:2"]):
        assert cli.main(["render", str(scene), "-q", "-o", str(out), *extra]) == 1
        err = _err_lines(capsys)
        assert len(err) == 1 and "holds the state of another render" in err[0] and "--resume" in err[0], err
    assert state.read_bytes() == kept
    # The state still resumes (to the render it was: 4 spp).
    assert cli.main(["render", "--resume", str(out), "-q"]) == 0


def test_resume_refuses_given_image_options_and_other_folders(tmp_path, capsys):
    scene, out = _scene(tmp_path), tmp_path / "out"
    assert cli.main(["render", str(scene), "--spp", "2", "--checkpoint", "100", "-q", "-o", str(out)]) == 0
    capsys.readouterr()
    # Given values equal to a default are given all the same (--seed 0 is a seed).
    for extra, named in ((["--seed", "0"], "--seed"), (["--method", "pt"], "--method"), (["--spp", "3"], "--spp")):
        assert cli.main(["render", "--resume", str(out), "-q", *extra]) == 2
        assert f"drop {named}" in _err_lines(capsys)[0]
    assert cli.main(["render", "--resume", str(out), "-q", "-o", str(tmp_path / "elsewhere")]) == 2
    assert "writes into the folder of its state" in _err_lines(capsys)[0]
    assert not (tmp_path / "elsewhere").exists()
    assert cli.main(["render", "--resume", str(out), "-q", "-o", str(out)]) == 0  # its own folder is fine


def test_resume_honours_the_outputs_it_is_given(tmp_path):
    scene, out = _scene(tmp_path), tmp_path / "out"
    assert cli.main(["render", str(scene), "--spp", "2", "--checkpoint", "100", "-q", "-o", str(out)]) == 0
    assert not list(out.glob("room_qs*.png"))
    assert cli.main(["render", "--resume", str(out), "-q", "--quilt", "2x1"]) == 0
    assert len(list(out.glob("room_qs2x1*.png"))) == 1


@pytest.mark.parametrize("option", [["--workers", "2"], ["--shared-scene"], ["--wheel", "x.whl"]])
def test_ray_options_need_ray(tmp_path, capsys, option):
    scene = _scene(tmp_path)
    assert cli.main(["render", str(scene), "--spp", "1", "-q", "-o", str(tmp_path / "o"), *option]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1 and f"{option[0]} only apply with --ray" in err[0], err
    assert not (tmp_path / "o").exists()


def test_a_moved_project_resumes(tmp_path):
    """The state names its scene also relative to its own folder: a project folder moved as a
    whole (scene and output inside it) still resumes, and merges."""
    project = tmp_path / "project"
    project.mkdir()
    scene, out = _scene(project), project / "out"
    assert cli.main(["render", str(scene), "--spp", "2", "--checkpoint", "100", "-q", "-o", str(out)]) == 0
    moved = tmp_path / "moved"
    project.rename(moved)
    assert cli.main(["render", "--resume", str(moved / "out"), "-q"]) == 0
    assert cli.main(["merge", str(moved / "out"), "-q", "-o", str(moved / "merged")]) == 0


def test_a_folder_of_several_states_names_them(tmp_path, capsys):
    """Renders of two scenes with states in one folder (a state copied in from elsewhere, or two
    stems): `--resume` of the folder names each state with its scene; each resumes by name."""
    scene, out = _scene(tmp_path), tmp_path / "out"
    other = tmp_path / "hall.xml"
    other.write_text(scene.read_text())
    for s in (scene, other):
        assert cli.main(["render", str(s), "--spp", "2", "--checkpoint", "100", "-q", "-o", str(out)]) == 0
    capsys.readouterr()
    assert cli.main(["render", "--resume", str(out), "-q"]) == 1
    err = _err_lines(capsys)
    assert len(err) == 1, err
    assert "holds 2 render states, hall.mvpt-state (of hall.xml), room.mvpt-state (of room.xml)" in err[0], err
    assert f"e.g. {out / 'hall.mvpt-state'}" in err[0], err
    for stem in ("hall", "room"):
        assert cli.main(["render", "--resume", str(out / f"{stem}{state_file.SUFFIX}"), "-q"]) == 0
