"""A mesh that loses data says so once: non-finite vertex normals and texture coordinates are
replaced and warned about (stderr and stats['warnings']), zero-area triangles are a note, and
meshes without such data say nothing."""
from __future__ import annotations

import subprocess
import sys

import numpy as np

import mvpt
from small_scenes import scene, sensor

# A tilted quad of two triangles facing the camera, with vertex normals that differ (so that a
# vertex normal lost to zero would change the interpolated shading) and uvs.
QUAD = ("v -0.5 0 0\nv 0.5 0 0\nv 0.5 1 0.2\nv -0.5 1 0.2\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "vn 0.3 0 1\nvn -0.3 0 1\nvn 0 0.3 1\n{last}\n"
        "f 1/1/1 2/2/2 3/3/3\nf 1/1/1 3/3/3 4/4/4\n{extra}")


def _scene(tmp_path, obj_text: str, name: str = "m.obj"):
    (tmp_path / name).write_text(obj_text)
    body = (f'    <shape type="obj"><string name="filename" value="{name}"/>\n'
            '        <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>\n')
    path = tmp_path / f"{name}.xml"
    path.write_text(scene(sensors=sensor(res=12, spp=2), body=body))
    return path


def _computed_last_normal() -> str:
    """The normal mvpt computes for vertex 4 from its one face (angle-weighted face normals)."""
    p = np.array([[-0.5, 0, 0], [0.5, 1, 0.2], [-0.5, 1, 0.2]])
    n = np.cross(p[1] - p[0], p[2] - p[0])
    n /= np.linalg.norm(n)
    return "vn " + " ".join(f"{c:.9g}" for c in n)


def test_non_finite_normal_is_replaced_and_warned(tmp_path):
    bad = mvpt.load_file(_scene(tmp_path, QUAD.format(last="vn 1e39 0 1", extra=""), "bad.obj"))
    good = mvpt.load_file(_scene(tmp_path, QUAD.format(last=_computed_last_normal(), extra=""), "good.obj"))
    assert good.warnings == []
    assert len(bad.warnings) == 1
    assert "OBJ mesh 'bad.obj'" in bad.warnings[0]
    assert "1 of 4 vertex normals is not finite, computed from the faces instead" in bad.warnings[0]
    a = mvpt.render(bad, spp=2, seed=1, threads=1)
    b = mvpt.render(good, spp=2, seed=1, threads=1)
    assert a.stats["warnings"] == bad.warnings
    # The replaced normal is the face's: the image equals the one with that normal written out.
    np.testing.assert_allclose(a.images["cam"], b.images["cam"], rtol=1e-5, atol=1e-6)


def test_non_finite_uv_is_warned(tmp_path):
    text = QUAD.format(last="vn 0 0 1", extra="").replace("vt 1 1", "vt 1 1e39")
    sc = mvpt.load_file(_scene(tmp_path, text))
    assert len(sc.warnings) == 1 and "texture coordinates is not finite, set to (0, 0)" in sc.warnings[0]


def test_zero_area_triangles_are_a_note_not_a_warning(tmp_path):
    sc = mvpt.load_file(_scene(tmp_path, QUAD.format(last="vn 0 0 1", extra="f 1/1/1 2/2/2 2/2/2\n")))
    assert sc.warnings == []
    notes = [n for n in sc.notes if "m.obj" in n]
    assert len(notes) == 1 and "1 of 3 triangles has no area" in notes[0]


def test_warning_printed_once_by_the_cli(tmp_path):
    path = _scene(tmp_path, QUAD.format(last="vn inf 0 1", extra=""))
    run = subprocess.run([sys.executable, "-m", "mvpt.cli", "render", str(path), "-o", str(tmp_path / "out"),
                          "--spp", "1", "-q"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    lines = [line for line in run.stderr.splitlines() if line.startswith("mvpt: warning:")]
    assert len(lines) == 1 and "vertex normals is not finite" in lines[0], run.stderr
