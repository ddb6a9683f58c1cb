"""Display outputs: Looking Glass quilt (tile i is view i, view 0 bottom-left, _qs name), contact
sheet, GIF and MP4 of a sequence of views."""
from __future__ import annotations

import numpy as np
import pytest

from mvpt import contact_sheet, movie, quilt
from mvpt.images import srgb8

PIL = pytest.importorskip("PIL", reason="the display outputs need Pillow")
from PIL import Image  # noqa: E402


def _views(n: int, w: int = 6, h: int = 4) -> list:
    """n views, each with its own constant color and a marker pixel at (0, 0) so flips are caught."""
    out = []
    for i in range(n):
        v = np.full((h, w, 3), [(i + 1) / (n + 1), 0.5 * (i % 2), 1 - (i + 1) / (n + 1)], dtype=np.float32)
        v[0, 0] = [1, 1, 1]
        out.append(v)
    return out


def test_layout_defaults_and_errors():
    assert quilt.layout(9) == (3, 3)
    assert quilt.layout(10) == (4, 3)
    assert quilt.layout(45, 5, 9) == (5, 9)
    assert quilt.layout(7, rows=2) == (4, 2)
    with pytest.raises(ValueError, match="too few"):
        quilt.layout(10, 3, 3)


def test_view_zero_is_bottom_left_and_last_is_top_right():
    views = _views(6)
    q, cols, rows = quilt.make_quilt(views, 3, 2)
    h, w = 4, 6
    assert q.shape == (rows * h, cols * w, 3)
    np.testing.assert_array_equal(q[h:, :w], views[0])          # bottom-left
    np.testing.assert_array_equal(q[h:, w:2 * w], views[1])     # left to right ...
    np.testing.assert_array_equal(q[:h, :w], views[3])          # ... then the row above
    np.testing.assert_array_equal(q[:h, 2 * w:], views[5])      # top-right


def test_quilt_png_round_trips(tmp_path):
    views = _views(7)
    path = quilt.write_quilt(views, tmp_path, "shot", columns=4, rows=2)
    assert path.endswith("shot_qs4x2a1.5.png")
    cols, rows, aspect = quilt.parse_quilt_name(path)
    assert (cols, rows, aspect) == (4, 2, 1.5)
    png = np.asarray(Image.open(path).convert("RGB"))
    assert png.shape == (2 * 4, 4 * 6, 3)
    tiles = quilt.split_quilt(png, cols, rows, n=7)
    for i, tile in enumerate(tiles):
        np.testing.assert_array_equal(tile, srgb8(views[i]), err_msg=f"tile {i} is not view {i}")
    # the unused top-right tile is black
    np.testing.assert_array_equal(quilt.split_quilt(png, cols, rows)[7], 0)


def test_quilt_name_aspect_format():
    assert quilt.quilt_name("a", 8, 6, 0.75) == "a_qs8x6a0.75.png"
    assert quilt.quilt_name("a", 5, 9, 16 / 9) == "a_qs5x9a1.778.png"
    with pytest.raises(ValueError, match="_qs"):
        quilt.parse_quilt_name("plain.png")


def test_quilt_rejects_views_of_different_sizes():
    with pytest.raises(ValueError, match="must match"):
        quilt.make_quilt([np.zeros((4, 6, 3)), np.zeros((4, 5, 3))])


def test_contact_sheet_places_views_in_reading_order(tmp_path):
    views = {f"v{i}": v for i, v in enumerate(_views(5))}
    path = contact_sheet.write_contact_sheet(views, tmp_path / "sheet.png", columns=3)
    sheet = np.asarray(Image.open(path).convert("RGB"))
    cell_h = 4 + contact_sheet.LABEL_HEIGHT
    for i, v in enumerate(views.values()):
        x, y = contact_sheet.contact_sheet_cell(i, 3, 6, cell_h)
        np.testing.assert_array_equal(sheet[y:y + 4, x:x + 6], srgb8(v))


def test_gif_has_one_frame_per_view(tmp_path):
    views = _views(5, 8, 8)
    path = movie.write_gif(views, tmp_path / "shot.gif", fps=10)
    with Image.open(path) as gif:
        assert gif.n_frames == 5
        assert gif.info["duration"] == 100
        for i in range(5):
            gif.seek(i)
            frame = np.asarray(gif.convert("RGB")).astype(int)
            # GIF palettes quantize; constant frames come out within a few levels
            assert np.abs(frame[4, 4] - srgb8(views[i])[4, 4].astype(int)).max() <= 8


def test_mp4_decodes_to_the_frames(tmp_path):
    try:
        exe = movie.ffmpeg_executable()
    except RuntimeError as e:
        pytest.skip(str(e))
    import subprocess

    views = _views(6, 17, 9)  # odd sizes are padded to even ones
    path = movie.write_mp4(views, tmp_path / "shot.mp4", fps=6)
    raw = subprocess.run([exe, "-loglevel", "error", "-i", path, "-f", "rawvideo", "-pix_fmt", "rgb24", "-"],
                         capture_output=True, check=True).stdout
    frames = np.frombuffer(raw, np.uint8).reshape(-1, 10, 18, 3)
    assert len(frames) == 6
    for i, f in enumerate(frames):
        # H.264 with 4:2:0 chroma is lossy; the centre of a constant frame stays close
        assert np.abs(f[5, 9].astype(int) - srgb8(views[i])[5, 9].astype(int)).max() <= 12, f"frame {i}"


def test_looking_glass_devices_give_their_quilts_layout_and_view_size(tmp_path):
    from mvpt import cli, looking_glass
    portrait = looking_glass.device("portrait")
    assert (portrait.columns, portrait.rows, portrait.views) == (8, 6, 48)
    assert portrait.view_size() == (420, 560) and portrait.view_size(0.25) == (105, 140)
    for d in looking_glass.DEVICES.values():  # every view at the aspect its quilt's name carries
        w, h = d.view_size()
        assert abs(w / h - d.aspect) < 0.5 / h + 1e-9 and d.views >= 48, d
    with pytest.raises(ValueError, match="unknown Looking Glass device 'portait': expected one of portrait, go"):
        looking_glass.device("portait")
    # --quilt DEVICE: the device's layout, the views' own aspect in the name; a device with fewer
    # tiles than views is the usage error of a layout with too few tiles.
    from small_scenes import scene, views as row
    path = tmp_path / "row.xml"
    path.write_text(scene(row(6, res=8, spp=1)))
    assert cli.main(["render", str(path), "--method", "pt", "--quilt", "portrait", "-o", str(tmp_path / "o"), "-q"]) == 0
    assert [p.name for p in (tmp_path / "o").glob("*_qs*")] == ["row_qs8x6a1.png"]
    assert cli.main(["render", str(path), "--quilt", "portait", "-o", str(tmp_path / "bad"), "-q"]) == 2
