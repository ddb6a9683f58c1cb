"""`mvpt render scene.blend` and mvpt.load_blend on files that are not whole .blend files, and
without Blender's module: one error line naming the file and what was expected, exit code 1.
The file checks come before Blender is needed, so these run without bpy too; the last test,
a whole render from a .blend, needs it."""
import subprocess
import sys

import pytest

import mvpt
from mvpt import cli

try:
    import bpy  # noqa: F401
    HAS_BPY = True
except ImportError:
    HAS_BPY = False
# A .blend header (Blender 5's) and no end block: what a cut-off uncompressed file looks like.
CUT = b"BLENDER17-01v0500" + bytes(200)


def _render(capsys, path, *extra):
    code = cli.main(["render", str(path), "-q", "-o", str(path.parent / "out"), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    return code, err


@pytest.mark.parametrize("name,content,expected", [
    ("missing.blend", None, "no such file"),
    ("notes.blend", b"these are my notes, not a scene\n", "not a Blender file"),
    ("cut.blend", CUT, "truncated"),
])
def test_bad_files_are_one_line(tmp_path, capsys, name, content, expected):
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    code, err = _render(capsys, path)
    assert code == 1 and len(err) == 1, err
    assert err[0].startswith("mvpt: error: ") and str(path) in err[0] and expected in err[0], err
    with pytest.raises(ValueError, match=expected):
        mvpt.load_blend(path)


@pytest.mark.skipif(not HAS_BPY, reason="Blender's Python module is not installed (pip install \"mvpt[blender]\")")
def test_compressed_file_cut_short(tmp_path, capsys):
    from blender_scenes import add_mesh, bpy, empty_scene
    empty_scene()
    add_mesh("cube", None)
    whole = tmp_path / "whole.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(whole), compress=True)
    data = whole.read_bytes()
    assert data[:4] == b"\x28\xb5\x2f\xfd"  # Zstandard
    for cut in (len(data) // 2, len(data) * 9 // 10):
        path = tmp_path / f"cut{cut}.blend"
        path.write_bytes(data[:cut])
        code, err = _render(capsys, path)
        assert code == 1 and len(err) == 1 and "truncated" in err[0], err


def test_without_bpy_says_what_to_install(tmp_path):
    path = tmp_path / "whole.blend"
    path.write_bytes(b"BLENDER17-01v0500" + bytes(64) + b"ENDB" + bytes(28))
    script = ("import sys; sys.modules['bpy'] = None\n"  # as if Blender's module were not installed
              "from mvpt import cli\n"
              f"sys.exit(cli.main(['render', {str(path)!r}, '-q', '-o', {str(tmp_path / 'out')!r}]))\n")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    err = run.stderr.strip().splitlines()
    assert run.returncode == 1 and len(err) == 1, run.stderr
    assert 'pip install "mvpt[blender]"' in err[0], err


@pytest.mark.skipif(not HAS_BPY, reason="Blender's Python module is not installed (pip install \"mvpt[blender]\")")
def test_render_a_blend_file(tmp_path, capsys):
    from blender_scenes import add_camera, add_light, add_mesh, bpy, empty_scene
    empty_scene(res=16, samples=4)
    add_mesh("plane", None, size=4.0)
    add_camera((0, -3, 2), (60, 0, 0))
    add_light("SUN", (0, 0, 3), energy=2.0, angle=0.0)
    path = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    code = cli.main(["render", str(path), "-q", "-o", str(tmp_path / "out"), "--xml-dir", str(tmp_path / "xml")])
    capsys.readouterr()
    assert code == 0
    assert (tmp_path / "out" / "shot_camera.exr").exists() and (tmp_path / "xml" / "shot.xml").exists()
    scene = mvpt.load_blend(path, spp=2)
    image = mvpt.render(scene, seed=1).images["camera"]
    assert image.shape == (16, 16, 3) and image.mean() > 0
