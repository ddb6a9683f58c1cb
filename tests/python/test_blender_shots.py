"""A frame range of a Blender scene as a shot (docs/blender.md, "Animation"): one view per frame,
its shutter from Blender's motion blur, the camera's and the moving objects' poses sampled
across the shutters; a frame of the shot agrees with Cycles' render of that frame; what the
conversion cannot carry (a deforming mesh, a moving light) is warned; `--frames` on the
command line."""
import math
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from blender_scenes import add_light, agreement, bpy, cycles_images, table_scene

import mvpt
from mvpt.blender import export_current

FPS = 24


def _moving_table():
    """The diffuse table-top of blender_scenes, its camera sliding along x over frames 1..5 and
    the cube rising; a point light."""
    scene = table_scene()
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.frame_start, scene.frame_end = 1, 5
    cam, cube = scene.camera, bpy.data.objects["Cube"]
    for frame, x, z in ((1, -0.4, 0.4), (5, 0.4, 0.9)):
        cam.location.x = x
        cam.keyframe_insert("location", frame=frame)
        cube.location.z = z
        cube.keyframe_insert("location", frame=frame)
    add_light("POINT", (1.0, -0.5, 2.5), energy=150.0, shadow_soft_size=0.0)
    scene.frame_set(1)
    return scene, cam, cube


def _pose_at(obj, frame: float):
    scene = bpy.context.scene
    scene.frame_set(int(math.floor(frame)), subframe=frame - math.floor(frame))
    m = [list(row) for row in obj.matrix_world]
    scene.frame_set(1)
    return np.array(m)


def _matrix(element) -> np.ndarray:
    return np.array([float(v) for v in element.find("matrix").get("value").split()]).reshape(4, 4)


def _sensors(xml_path) -> dict:
    root = ET.parse(xml_path).getroot()
    return {s.get("id"): s for s in root.iter("sensor")}


def _floats(element) -> dict:
    return {f.get("name"): float(f.get("value")) for f in element.findall("float")}


def test_frames_are_views_at_their_instants(tmp_path):
    scene, cam, cube = _moving_table()
    exported = export_current(tmp_path, frames=(2, 4))
    assert not exported.warnings, exported.warnings
    sensors = _sensors(exported.xml)
    assert list(sensors) == ["frame0002", "frame0003", "frame0004"]
    for f, s in zip((2, 3, 4), sensors.values()):
        t = (f - 2) / FPS
        assert _floats(s)["shutter_open"] == pytest.approx(t) and _floats(s)["shutter_close"] == pytest.approx(t)
        to_world = _matrix(s.find("transform"))
        assert to_world[:3, 3] == pytest.approx(_pose_at(cam, f)[:3, 3], abs=1e-5)
    # The cube moves: keyframes at every frame of the range, the camera still has no effect on it.
    shapes = [s for s in ET.parse(exported.xml).getroot().iter("shape") if s.find("animation") is not None]
    assert len(shapes) == 1
    keys = shapes[0].find("animation").findall("transform")
    assert [float(k.get("time")) for k in keys] == pytest.approx([0.0, 1 / FPS, 2 / FPS])
    for f, k in zip((2, 3, 4), keys):
        assert _matrix(k)[:3, 3] == pytest.approx(_pose_at(cube, f)[:3, 3], abs=1e-5)
    loaded = mvpt.load_file(exported.xml)
    assert [v["id"] for v in loaded.views] == list(sensors)
    assert loaded.views[1]["shutter"] == pytest.approx((1 / FPS, 1 / FPS))


def test_motion_blur_opens_each_shutter_with_keys_across_it(tmp_path):
    scene, cam, cube = _moving_table()
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
    scene.render.motion_blur_position = "CENTER"
    exported = export_current(tmp_path, frames=(2, 3))
    assert not exported.warnings, exported.warnings
    sensors = _sensors(exported.xml)
    for f, s in zip((2, 3), sensors.values()):
        t = (f - 2) / FPS
        fl = _floats(s)
        assert (fl["shutter_open"], fl["shutter_close"]) == pytest.approx((t - 0.25 / FPS, t + 0.25 / FPS))
        keys = s.find("animation").findall("transform")
        times = [float(k.get("time")) for k in keys]
        # A grid of 1/8 frame: the shutter's ends and the three instants between.
        assert times == pytest.approx([t + (i / 8 - 0.25) / FPS for i in range(5)])
        for x, k in zip(times, keys):
            assert _matrix(k)[:3, 3] == pytest.approx(_pose_at(cam, 2 + x * FPS)[:3, 3], abs=1e-5)
    cube_keys = [s for s in ET.parse(exported.xml).getroot().iter("shape")
                 if s.find("animation") is not None][0].find("animation").findall("transform")
    times = np.array([float(k.get("time")) for k in cube_keys])
    assert np.allclose(np.diff(times), 1 / (8 * FPS))  # evenly spaced over every shutter
    assert times[0] == pytest.approx(-0.25 / FPS) and times[-1] == pytest.approx(1.25 / FPS)
    loaded = mvpt.load_file(exported.xml)
    r = mvpt.render(loaded, spp=1, seed=1, method="mvpt")
    # Shutters of half a frame do not overlap while the cube moves: nothing to share, path traced.
    assert r.stats["method"] == "pt" and any("nothing to share" in n for n in r.stats["notes"])


def test_a_frame_of_the_shot_agrees_with_cycles(tmp_path):
    """Frame 3 of the shot (the camera and the cube half-way) against Cycles' render of frame 3."""
    seeds = 12
    scene, _, _ = _moving_table()
    exported = export_current(tmp_path, frames=(1, 5))
    scene.frame_set(3)
    cy = cycles_images(seeds)
    loaded = mvpt.load_file(exported.xml)
    mv = np.stack([mvpt.render(loaded, seed=1000 + s, threads=2, views=["frame0003"]).images["frame0003"]
                   for s in range(seeds)]).astype(np.float64)
    a = agreement(mv, cy)
    shifted = np.stack([mvpt.render(loaded, seed=1000 + s, threads=2, views=["frame0002"]).images["frame0002"]
                        for s in range(seeds)]).astype(np.float64)
    b = agreement(shifted, cy)
    print(f"\nframe 3: mvpt {a['mvpt']:.5f} vs Cycles {a['cycles']:.5f}, z {a['z']:+.2f}, largest block |z| "
          f"{a['max_block_z']:.2f}; frame 2 against Cycles' frame 3: largest block |z| {b['max_block_z']:.1f}")
    assert abs(a["z"]) < 4.0 and a["max_block_z"] < 4.5, a
    assert b["max_block_z"] > 4.5, b  # the test sees a frame's difference


def test_a_deforming_mesh_and_a_moving_light_are_warned(tmp_path):
    scene, _, cube = _moving_table()
    cube.shape_key_add(name="Basis")
    key = cube.shape_key_add(name="squash")
    for v in key.data:
        v.co.z *= 0.5
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=5)
    light = bpy.data.objects["point"]
    light.keyframe_insert("location", frame=1)
    light.location.x += 1.0
    light.keyframe_insert("location", frame=5)
    scene.frame_set(1)
    exported = export_current(tmp_path, frames=(1, 3))
    text = "\n".join(exported.warnings)
    assert "'Cube' changes shape over the frames" in text and "frame 1 is used" in text
    assert "light 'point' moves over the frames" in text


def test_frames_on_the_command_line(tmp_path):
    _moving_table()
    blend = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "mvpt", "render", str(blend), "--frames", "2:3", "--spp", "1",
                          "-q", "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert sorted(p.name for p in out.glob("*.exr")) == ["shot_frame0002.exr", "shot_frame0003.exr"]
    for bad, why in (("3:2", "A <= B"), ("2", "A:B"), ("a:b", "two frame numbers")):
        run = subprocess.run([sys.executable, "-m", "mvpt", "render", str(blend), "--frames", bad, "-o", str(out)],
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 2 and why in run.stderr, (bad, run.stderr)
    xml = tmp_path / "x.xml"
    xml.write_text('<scene version="3.0.0"/>')
    run = subprocess.run([sys.executable, "-m", "mvpt", "render", str(xml), "--frames", "1:2", "-o", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "--frames converts a range of a .blend scene's frames" in run.stderr
    assert re.search(r"^mvpt: ", run.stderr, re.M)
