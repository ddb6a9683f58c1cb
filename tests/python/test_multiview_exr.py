"""Multi-view OpenEXR: one part per view, part name and `view` attribute = view id (or left/right
with stereo names), `multiView` listing all views; read back with the OpenEXR Python bindings
(an implementation independent of ours) and with mvpt's own reader."""
from __future__ import annotations

import numpy as np
import pytest

import mvpt
from mvpt import _core, cli, movie
from mvpt.output import write_multiview_exr
from mvpt.runs import load_run

from small_scenes import scene, sensor, views

OpenEXR = pytest.importorskip("OpenEXR", reason="the multi-view EXR test reads files with the OpenEXR bindings")
Image = pytest.importorskip("PIL.Image", reason="the display outputs need Pillow")


@pytest.fixture(scope="module")
def three_views():
    """Three views of different sizes (parts keep their own data windows)."""
    xml = scene(sensor("front", res=12, spp=2) + sensor("side", res=8, spp=2, origin="3, 1, 2")
                + sensor("top", res=10, spp=2, origin="0, 4, 0.5"))
    return mvpt.render(mvpt.load_string(xml), threads=1, seed=1)


def _parts(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        out = []
        for p in f.parts:
            out.append((p.name(), dict(p.header), {k: np.array(c.pixels) for k, c in p.channels.items()}))
        return out


def test_every_view_is_a_part_named_by_its_id(three_views, tmp_path):
    path = write_multiview_exr(three_views, tmp_path / "all.exr", aovs=True)
    parts = _parts(path)
    assert [p[0] for p in parts] == ["front", "side", "top"]
    for (name, header, channels), vid in zip(parts, ["front", "side", "top"]):
        assert header["view"] == vid
        assert list(header["multiView"]) == ["front", "side", "top"]
        img = three_views.images[vid]
        assert channels["R"].shape == img.shape[:2]
        for i, c in enumerate("RGB"):
            np.testing.assert_array_equal(channels[c], img[..., i])
            np.testing.assert_array_equal(channels[f"variance.{c}"], three_views.variance[vid][..., i])
        np.testing.assert_array_equal(channels["sample_count.Y"], three_views.sample_count[vid])


def test_stereo_views_are_left_and_right(tmp_path):
    xml = scene(sensor("camL", res=8, spp=1, origin="-0.1, 1, 4") + sensor("camR", res=8, spp=1, origin="0.1, 1, 4"))
    r = mvpt.render(mvpt.load_string(xml), threads=1)
    path = write_multiview_exr(r, tmp_path / "stereo.exr", stereo=True)
    parts = _parts(path)
    assert [(p[0], p[1]["view"]) for p in parts] == [("left", "left"), ("right", "right")]
    assert list(parts[0][1]["multiView"]) == ["left", "right"]  # left is the default view
    np.testing.assert_array_equal(parts[1][2]["G"], r.images["camR"][..., 1])
    with pytest.raises(ValueError, match="exactly two views"):
        write_multiview_exr(mvpt.render(mvpt.load_string(scene(views(3, res=4, spp=1))), threads=1),
                            tmp_path / "bad.exr", stereo=True)


def test_own_reader_round_trips(three_views, tmp_path):
    path = write_multiview_exr(three_views, tmp_path / "all.exr")
    run = load_run(path)
    assert list(run.images) == ["front", "side", "top"]
    for vid, img in three_views.images.items():
        np.testing.assert_array_equal(run.images[vid], img)


def test_part_names_must_be_unique(tmp_path):
    a = np.zeros((2, 2), np.float32)
    with pytest.raises(RuntimeError, match="two views are named 'x'"):
        _core.write_multiview_exr(str(tmp_path / "dup.exr"), [("x", {"R": a}), ("x", {"R": a})])
    assert not list(tmp_path.iterdir())  # nothing left behind


def test_cli_writes_multiview_exr_and_displays(tmp_path):
    path = tmp_path / "rig.xml"
    path.write_text(scene(views(4, res=8, spp=1)))
    out = tmp_path / "out"
    code = cli.main(["render", str(path), "-o", str(out), "-q", "--threads", "1", "--multiview-exr", "--quilt",
                     "--contact-sheet", "--gif"])
    assert code == 0
    assert [p[0] for p in _parts(out / "rig.exr")] == ["v0", "v1", "v2", "v3"]
    assert (out / "rig_qs2x2a1.png").is_file()
    assert (out / "rig_contact.png").is_file() and (out / "rig.gif").is_file()
    with Image.open(out / "rig.gif") as gif:
        assert gif.n_frames == 4
    # the directory is still one run for `mvpt compare` (the multi-view EXR does not confuse it)
    assert list(load_run(out).images) == ["v0", "v1", "v2", "v3"]


def test_cli_writes_mp4(tmp_path):
    try:
        movie.ffmpeg_executable()
    except RuntimeError as e:
        pytest.skip(str(e))
    path = tmp_path / "rig.xml"
    path.write_text(scene(views(3, res=8, spp=1)))
    out = tmp_path / "out"
    assert cli.main(["render", str(path), "-o", str(out), "-q", "--threads", "1", "--mp4", "--fps", "3"]) == 0
    assert (out / "rig.mp4").stat().st_size > 0


def test_cli_stereo_needs_multiview_exr(tmp_path, capsys):
    path = tmp_path / "rig.xml"
    path.write_text(scene(views(2, res=4, spp=1)))
    assert cli.main(["render", str(path), "-o", str(tmp_path / "o"), "-q", "--stereo"]) == 2
    assert "--multiview-exr" in capsys.readouterr().err
