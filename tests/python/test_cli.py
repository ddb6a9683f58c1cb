"""The `mvpt` command line: outputs per view, JSON summary, AOVs, Ctrl-C, atomic writes,
progress bar on a terminal only, --views, -D, and one-line errors for bad input."""
from __future__ import annotations

import json
import os
import pty
import signal
import subprocess
import sys
import time
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import mvpt
from mvpt import _core, cli

from small_scenes import overflow_scene, scene, sensor, slow_scene

ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
CLI = [sys.executable, "-m", "mvpt.cli"]


def _two_view_scene(tmp_path: Path) -> Path:
    """Views 'left' and 'right'; the resolution is a <default> (16) for -D to override."""
    xml = scene(sensor("left", res="$res", spp=2, origin="-1, 1, 4") + sensor("right", res="$res", spp=2, origin="1, 1, 4"))
    xml = xml.replace('<scene version="3.0.0">', '<scene version="3.0.0">\n    <default name="res" value="16"/>')
    path = tmp_path / "scene.xml"
    path.write_text(xml)
    return path


def _leftovers(out: Path) -> list:
    """Temporary or hidden files in `out` (there must never be any)."""
    return [p.name for p in out.rglob("*") if p.name.startswith(".") or p.suffix == ".tmp" or ".tmp" in p.name]


def _exr_channels(path: Path) -> dict:
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    bmp = mi.Bitmap(str(path))
    return {f.name: np.array(bmp, copy=False)[..., i] for i, f in enumerate(bmp.struct_())}


def test_demo(tmp_path, capsys):
    out = tmp_path / "out"
    assert cli.main(["demo", "-o", str(out), "--spp", "4"]) == 0  # the default 16 spp takes ~4x longer
    with resources.as_file(resources.files("mvpt") / "data" / "demo.xml") as demo:
        scene = mvpt.load_file(demo)
        ids = [v["id"] for v in scene.views]
        assert len(ids) == 9
        # The demo shares paths between its views (mvpath): the same render, bit for bit.
        assert scene.integrator == "mvpath"
        expected = mvpt.render(scene, spp=4)
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(["demo.json"] + [f"demo_{v}.{ext}" for v in ids for ext in ("exr", "png")])
    exr = _core.read_image(str(out / f"demo_{ids[4]}.exr"))
    assert exr.tobytes() == expected.images[ids[4]].tobytes()  # float32 EXR: bit-exact
    png = _core.read_image(str(out / f"demo_{ids[4]}.png"))
    assert png.shape == exr.shape
    # The PNG is the sRGB-encoded 8-bit preview of the same image (clamped to [0, 1]).
    assert np.abs(png - np.clip(exr, 0, 1)).max() < 0.02
    data = json.loads((out / "demo.json").read_text())
    assert list(data["views"]) == ids and data["settings"]["views"] == ids
    printed = capsys.readouterr().out
    assert all(f"\n{v} " in printed for v in ids) and f"{exr.shape[1]}x{exr.shape[0]}" in printed


def test_nonfinite_samples_reported(tmp_path, capsys):
    path = tmp_path / "overflow.xml"
    path.write_text(overflow_scene())
    out = tmp_path / "out"
    assert cli.main(["render", str(path), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    data = json.loads((out / "overflow.json").read_text())
    n, first = data["nonfinite_samples"], data["first_nonfinite"]
    assert n > 0 and data["views"]["cam"]["nonfinite_samples"] == n
    assert (f"warning: {n:,} non-finite samples were dropped (first: view cam, pixel ({first['x']}, {first['y']}), "
            f"sample {first['sample']})") in printed
    assert np.isfinite(_core.read_image(str(out / "overflow_cam.exr"))).all()


def test_render_end_to_end(tmp_path):
    """The real entry point in a subprocess: files per view, JSON, summary, -D over a <default>."""
    path = _two_view_scene(tmp_path)
    out = tmp_path / "out"
    proc = subprocess.run(CLI + ["render", str(path), "-D", "res=32", "--spp", "4", "--method", "pt", "-o", str(out)],
                          capture_output=True, text=True, timeout=120, env=ENV)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""  # piped: no progress bar
    assert sorted(p.name for p in out.iterdir()) == ["scene.json", "scene_left.exr", "scene_left.png",
                                                     "scene_right.exr", "scene_right.png"]
    expected = mvpt.render(mvpt.load_file(path, res=32), spp=4)
    for vid in ("left", "right"):
        exr = _core.read_image(str(out / f"scene_{vid}.exr"))
        assert exr.shape == (32, 32, 3)
        assert exr.tobytes() == expected.images[vid].tobytes(), vid
        assert _core.read_image(str(out / f"scene_{vid}.png")).shape == (32, 32, 3)

    data = json.loads((out / "scene.json").read_text())
    assert {"settings", "wall_time", "passes", "samples", "samples_per_second", "rays", "rays_per_second",
            "nonfinite_samples", "views", "cancelled", "threads"} <= set(data)
    st = data["settings"]
    assert st["scene"] == str(path) and st["defines"] == {"res": "32"} and st["spp"] == 4
    assert st["views"] == ["left", "right"] and st["integrator"] == "path"
    assert data["passes"] == 4 and data["cancelled"] is False
    assert data["samples"] == 2 * 32 * 32 * 4
    assert data["wall_time"] > 0 and data["samples_per_second"] == pytest.approx(data["samples"] / data["wall_time"])
    assert data["rays"]["camera"] == data["samples"]
    assert data["rays"]["total"] == data["rays"]["intersect"] + data["rays"]["shadow"] > data["samples"]
    assert data["rays_per_second"] > 0 and data["nonfinite_samples"] == 0
    for vid in ("left", "right"):
        v = data["views"][vid]
        assert (v["id"], v["width"], v["height"], v["spp"]) == (vid, 32, 32, 4.0)
        assert v["mean"] == pytest.approx(expected.images[vid].reshape(-1, 3).mean(axis=0), rel=1e-5)

    # The summary table: one row per view, then the totals.
    lines = proc.stdout.splitlines()
    header = next(i for i, l in enumerate(lines) if l.split()[:3] == ["view", "size", "spp"])
    assert lines[header + 2].split()[:4] == ["left", "32x32", "4.0", "4,096"]
    assert lines[header + 3].split()[:4] == ["right", "32x32", "4.0", "4,096"]
    assert any("4 passes" in l for l in lines) and any("rays:" in l and "shadow" in l for l in lines)


def test_aovs(tmp_path):
    path = _two_view_scene(tmp_path)
    pt = ["--method", "pt"]  # (path tracing's AOVs; multi-view path tracing's below)
    assert cli.main(["render", str(path), "--spp", "3", *pt, "-o", str(tmp_path / "plain"), "-q"]) == 0
    assert cli.main(["render", str(path), "--spp", "3", *pt, "-o", str(tmp_path / "aov"), "--aovs", "-q"]) == 0
    plain = _exr_channels(tmp_path / "plain" / "scene_left.exr")
    assert sorted(plain) == ["B", "G", "R"]
    ch = _exr_channels(tmp_path / "aov" / "scene_left.exr")
    assert sorted(ch) == ["B", "G", "R", "sample_count.Y", "variance.B", "variance.G", "variance.R"]
    expected = mvpt.render(mvpt.load_file(path), spp=3)
    assert (ch["sample_count.Y"] == 3).all()
    for i, c in enumerate("RGB"):
        assert np.array_equal(ch[f"variance.{c}"], expected.variance["left"][..., i])
        assert np.array_equal(ch[c], expected.images["left"][..., i])
    assert ch["variance.R"].max() > 0
    # Multi-view path tracing adds the contributions each pixel received.
    assert cli.main(["render", str(path), "--spp", "3", "--method", "mvpt", "-o", str(tmp_path / "mv"), "--aovs",
                     "-q"]) == 0
    mv = _exr_channels(tmp_path / "mv" / "scene_left.exr")
    assert sorted(mv) == ["B", "G", "R", "contributions.Y", "sample_count.Y", "variance.B", "variance.G", "variance.R"]
    expected = mvpt.render(mvpt.load_file(path), spp=3, method="mvpt")
    assert np.array_equal(mv["contributions.Y"], expected.contributions["left"])
    assert (mv["contributions.Y"] >= mv["sample_count.Y"]).all() and (mv["sample_count.Y"] == 3).all()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_writes_finished_passes(tmp_path, sig):
    path = tmp_path / "slow.xml"
    path.write_text(slow_scene(4, res=64))
    out = tmp_path / "out"
    # The child must see SIGINT at its default even when this process was started in the
    # background (which ignores SIGINT, and the ignore is inherited).
    proc = subprocess.Popen(CLI + ["render", str(path), "--spp", "100000", "--aovs", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        first = proc.stdout.readline()
        assert first.startswith("rendering 4 views"), first + proc.stderr.read()
        time.sleep(1.0)  # a few passes (~0.1 s each)
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 128 + int(sig), stderr
    assert "Traceback" not in stderr and "interrupted" in stderr
    data = json.loads((out / "slow.json").read_text())
    assert data["cancelled"] is True and 1 <= data["passes"] < 100000
    for i in range(4):
        exr = out / f"slow_v{i}.exr"
        img = _core.read_image(str(exr))
        assert img.shape == (64, 64, 3) and np.isfinite(img).all() and img.mean() > 0
        assert (out / f"slow_v{i}.png").exists()
        # Whole passes, or whole tiles of one pass more where a long pass was cut (a loaded
        # machine can make a pass long).
        assert data["passes"] <= data["views"][f"v{i}"]["spp"] <= data["passes"] + 1
    assert "cancelled after" in stdout
    assert _leftovers(out) == []
    count = _exr_channels(out / "slow_v0.exr")["sample_count.Y"]
    assert count.shape == (64, 64) and count.min() >= data["passes"] and count.max() <= data["passes"] + 1
    for y in range(0, 64, 16):
        for x in range(0, 64, 16):
            assert (count[y:y + 16, x:x + 16] == count[y, x]).all()


def test_outputs_atomic(tmp_path, capsys):
    path = _two_view_scene(tmp_path)
    out = tmp_path / "out"
    assert cli.main(["render", str(path), "-o", str(out), "-q"]) == 0
    assert _leftovers(out) == []
    # The PNG of view 'right' cannot be written (a directory is in the way): one error line,
    # exit code 1, and no temporary file left behind.
    bad = tmp_path / "bad"
    (bad / "scene_right.png").mkdir(parents=True)
    capsys.readouterr()
    assert cli.main(["render", str(path), "-o", str(bad), "-q"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mvpt: error: ") and "scene_right.png" in err[0]
    assert _leftovers(bad) == []
    # The output "directory" is a file.
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert cli.main(["render", str(path), "-o", str(blocker), "-q"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mvpt: error: ")
    assert _leftovers(tmp_path) == []


def _run_on_pty(args: list) -> tuple:
    """Run the CLI with stderr on a pseudo-terminal; returns (exit code, stderr bytes)."""
    master, slave = pty.openpty()
    proc = subprocess.Popen(CLI + args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave, env=ENV)
    os.close(slave)
    chunks = []
    try:
        while True:
            try:
                data = os.read(master, 4096)
            except OSError:  # EIO: the child closed the terminal
                break
            if not data:
                break
            chunks.append(data)
        proc.wait(timeout=60)
    finally:
        os.close(master)
        if proc.poll() is None:
            proc.kill()
    return proc.returncode, b"".join(chunks).decode(errors="replace")


def test_progress_bar_on_tty_only(tmp_path):
    path = tmp_path / "slow.xml"
    path.write_text(slow_scene(4, res=64))
    rc, err = _run_on_pty(["render", str(path), "--time", "0.8", "-o", str(tmp_path / "tty")])
    assert rc == 0, err
    draws = [d for d in err.split("\r") if "ETA" in d]
    assert len(draws) >= 3, err  # redrawn in place while rendering, then the final state
    assert "elapsed" in draws[0] and "%" in draws[0]
    assert "100.0%" in draws[-1]
    piped = subprocess.run(CLI + ["render", str(path), "--time", "0.3", "-o", str(tmp_path / "pipe")],
                           capture_output=True, text=True, timeout=60, env=ENV)
    assert piped.returncode == 0 and "ETA" not in piped.stderr and "\r" not in piped.stderr


def test_views_by_id_and_index(tmp_path):
    """An id wins; a digit string that is no id is an index (the ids here are 1, 7, 3)."""
    path = tmp_path / "scene.xml"
    path.write_text(scene(sensor("1") + sensor("7", origin="1, 1, 4") + sensor("3", origin="-1, 1, 4")))

    def rendered(views: str) -> list:
        out = tmp_path / f"out_{views.replace(',', '_')}"
        assert cli.main(["render", str(path), "--spp", "1", "--views", views, "-o", str(out), "-q"]) == 0
        return sorted(p.stem.split("_", 1)[1] for p in out.glob("*.exr"))

    assert rendered("1") == ["1"]
    assert rendered("2") == ["3"]
    assert rendered("7,0") == ["1", "7"]
    assert rendered("3,2") == ["3"]  # id 3 and index 2 are the same view


@pytest.mark.parametrize("args, needle", [
    (["--views", "nope"], "unknown view 'nope'"),
    (["--views", "5"], "out of range"),
    (["--views", ""], "--views: the list is empty"),  # once every view, without a word
    (["--gif", "--fps", "1e9"], "at most 1000"),
    (["--gif", "--fps", "inf"], "at most 1000"),
    (["--spp", "-1"], "--spp"),
    (["--spp", "many"], "--spp"),
    (["--time", "-1"], "--time"),
    (["--threads", "-3"], "--threads"),
    (["--spp", str(2**31)], "below 2^31"),  # once a traceback from the native module
    (["--threads", str(2**40)], "below 2^31"),
    (["--threads", "100000"], "at most 1024 threads"),  # once refused for the films' memory
    (["--workers", "2"], "only apply with --ray"),
    (["--passes", "0:0"], "FIRST:COUNT"),
    (["--passes", f"{2**31 - 1}:2"], "FIRST:COUNT"),
    (["--seed", "-1"], "--seed"),
    (["--splits", "0"], "--splits"),
    (["--splits", "many"], "--splits"),
    (["-D", "novalue"], "NAME=VALUE"),
    (["--frobnicate"], "unrecognized arguments"),
    (["--exposure", "nan"], "--exposure"),  # once an all-black quilt
    (["--gif", "--exposure", "inf"], "--exposure"),
    (["--gif", "--exposure", "1e308"], "--exposure"),  # once an OverflowError after the render
    (["--quilt", "100000x100000"], "--quilt"),  # once a MemoryError after the render
    (["--quilt", "1x1"], "too few"),
    (["--multiview-exr", "--stereo", "--views", "left"], "--stereo"),  # checked before the render
])
def test_bad_command_line(tmp_path, capsys, args, needle):
    path = _two_view_scene(tmp_path)
    out = tmp_path / "out"
    assert cli.main(["render", str(path), "-o", str(out)] + args) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("mvpt: error: ") and needle in lines[0], captured.err
    assert captured.out == "" and not out.exists()


@pytest.mark.parametrize("rig, needle", [
    ("", "the rig is empty"),  # once the scene's own sensors, without a word
    ("   ", "the rig is empty"),
    ("grid:11529216935854480x11529216935854480,spacing=0.001", "at most 100000 views"),  # once wrapped to 160,000
    ("grid:cols=1000,rows=1000,spacing=0.001", "at most 100000"),
])
def test_bad_rigs(tmp_path, capsys, rig, needle):
    path = _two_view_scene(tmp_path)
    assert cli.main(["render", str(path), "-o", str(tmp_path / "out"), "--rig", rig]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("mvpt: error: ") and needle in lines[0], lines


def test_mp4_without_a_working_ffmpeg_is_refused_before_rendering(tmp_path):
    path = _two_view_scene(tmp_path)
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    fake = bin_dir / "ffmpeg"
    fake.write_text("#!/bin/sh\nexit 1\n")
    fake.chmod(0o755)
    env = dict(ENV, PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
    out = tmp_path / "out"
    proc = subprocess.run(CLI + ["render", str(path), "--mp4", "-o", str(out)], capture_output=True, text=True,
                          timeout=60, env=env)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and "--mp4" in lines[0] and "ffmpeg" in lines[0], proc.stderr
    assert not out.exists()  # nothing rendered, nothing written


def test_missing_arguments_and_files(tmp_path, capsys):
    assert cli.main(["render"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert cli.main([]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert cli.main(["render", str(tmp_path / "nothere.xml"), "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("mvpt: error: ") and "not found" in err


def test_subprocess_bad_view_exit_code(tmp_path):
    path = _two_view_scene(tmp_path)
    proc = subprocess.run(CLI + ["render", str(path), "--views", "centre", "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=60, env=ENV)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "mvpt: error: --views: unknown view 'centre'; the scene's views are left, right"]


def test_unsafe_view_ids_get_distinct_files(tmp_path):
    path = tmp_path / "scene.xml"
    path.write_text(scene(sensor("a/b") + sensor("a_b", origin="1, 1, 4")))
    out = tmp_path / "out"
    assert cli.main(["render", str(path), "--spp", "1", "-o", str(out), "-q"]) == 0
    assert sorted(p.name for p in out.glob("*.exr")) == ["scene_a_b.exr", "scene_a_b_1.exr"]


def test_python_dash_m_mvpt_and_version():
    proc = subprocess.run([sys.executable, "-m", "mvpt", "--version"], capture_output=True, text=True,
                          timeout=60, env=ENV)
    assert proc.returncode == 0 and proc.stdout.strip() == f"mvpt {mvpt.__version__}"


@pytest.mark.parametrize("mib", [200, 300, 350, 700, 1200])
def test_memory_limits_give_one_line(tmp_path, mib):
    """Under an address-space limit (`ulimit -v`) a render works or ends with one error line and
    exit code 1: never a crash (Embree's allocations were unchecked), a bare std::bad_alloc or a
    traceback. The preflight counts the limit too."""
    import resource
    path = tmp_path / "box.xml"
    path.write_text(scene(sensor(res=16)))
    limit = mib << 20
    proc = subprocess.run(CLI + ["render", str(path), "-o", str(tmp_path / "out"), "-q", "--threads", "1"],
                          capture_output=True, text=True, timeout=120, env=ENV,
                          preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    assert proc.returncode in (0, 1), (proc.returncode, proc.stderr[-2000:])
    if proc.returncode == 1:
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("mvpt: error: "), proc.stderr[-2000:]
        assert "bad_alloc" not in lines[0] and ("memory" in lines[0] or "limit" in lines[0]), lines


def test_preflight_counts_the_address_space_limit(tmp_path):
    """A film that fits the machine but not `ulimit -v` is refused before it is allocated, naming the limit."""
    import resource
    path = tmp_path / "big.xml"
    path.write_text(scene(sensor(res=8192)))  # about 2 GiB of films
    limit = 1536 << 20
    proc = subprocess.run(CLI + ["render", str(path), "-o", str(tmp_path / "out"), "-q", "--spp", "1"],
                          capture_output=True, text=True, timeout=120, env=ENV,
                          preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    assert proc.returncode == 1, proc.stderr[-2000:]
    assert "the address-space limit (ulimit -v) leaves" in proc.stderr, proc.stderr[-2000:]


def test_output_that_is_a_file(tmp_path, capsys):
    path = _two_view_scene(tmp_path)
    target = tmp_path / "taken"
    target.write_text("a file")
    assert cli.main(["render", str(path), "-o", str(target), "--spp", "1", "-q"]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines == [f"mvpt: error: cannot use the output directory {target}: it is not a directory"], lines


# The command line, reporting its peak resident memory (MiB) on its last line of stderr.
_CLI_WITH_PEAK = ("import resource, sys\nfrom mvpt import cli\ncode = cli.main(sys.argv[1:])\n"
                  "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss >> 10, file=sys.stderr)\nsys.exit(code)\n")


def _render_under_limit(args: list, gib: int) -> tuple:
    import resource
    limit = gib << 30
    proc = subprocess.run([sys.executable, "-c", _CLI_WITH_PEAK, "render"] + args + ["-q"], capture_output=True,
                          text=True, timeout=120, env=ENV,
                          preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (limit, limit)))
    *lines, peak = proc.stderr.strip().splitlines()
    return proc.returncode, lines, float(peak)


def test_an_impossible_rig_is_refused_before_its_views_are_made(tmp_path):
    """A rig whose views' images cannot all be in memory was refused by the render's preflight
    only after its load (90000 views of 512^2: 34-75 s and 1.5 GB); it is refused before its
    views are made, unless --views renders only some of them."""
    path = tmp_path / "base.xml"
    path.write_text(scene(sensor(res=512)))
    rc, lines, peak = _render_under_limit([str(path), "--rig", "grid:300x300,spacing=0.001", "-o", str(tmp_path / "a")], 4)
    assert rc == 1 and len(lines) == 1, lines
    assert lines[0].startswith("mvpt: error: --rig grid:300x300,spacing=0.001: the rig's 90000 views need at least "), lines
    assert "MiB of memory for their images, but the address-space limit (ulimit -v) leaves" in lines[0], lines
    assert peak < 400, peak  # (the views made: about 800 MiB)
    path.write_text(scene(sensor(res=256)))
    small = [str(path), "--rig", "grid:40x40,spacing=0.001", "--spp", "1"]  # 3.2 GiB of images
    rc, lines, _ = _render_under_limit(small + ["-o", str(tmp_path / "b")], 2)
    assert rc == 1 and "the rig's 1600 views need at least" in lines[0], lines
    rc, lines, _ = _render_under_limit(small + ["--views", "r0c0", "-o", str(tmp_path / "c")], 2)
    assert rc == 0 and lines == [], lines
    assert (tmp_path / "c" / "base_r0c0.exr").exists()
