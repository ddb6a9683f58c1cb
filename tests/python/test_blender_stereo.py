"""Blender's stereoscopy (Output > Views > Stereo 3D) as two views, `left` and `right`
(docs/blender.md, "Stereo"): each eye agrees with Cycles' render of that eye (the per-block
test of test_blender_cycles.py), for the default Off-Axis convergence and for Parallel eyes; the
left eye's image is not the right one's; a shot of a stereo camera has both eyes per frame."""
import tempfile
from pathlib import Path

import numpy as np
import pytest

from blender_scenes import add_light, agreement, bpy, mvpt_images, table_scene

import mvpt
from mvpt.blender import export_current

SEEDS = 12


def _stereo_scene(mode: str, pivot: str = "CENTER"):
    scene = table_scene()
    add_light("POINT", (1.0, -0.5, 2.5), energy=150.0, shadow_soft_size=0.0)
    scene.render.use_multiview = True
    scene.render.views_format = "STEREO_3D"
    stereo = scene.camera.data.stereo
    stereo.convergence_mode = mode
    stereo.pivot = pivot
    stereo.interocular_distance = 0.4  # wide, so that the eyes differ by pixels at 32^2
    stereo.convergence_distance = 3.0
    return scene


def _cycles_eyes(seeds: int) -> dict:
    """Cycles' renders of both eyes, seeds 0..seeds-1: {"left": (seeds, H, W, 3), "right": ...}."""
    scene = bpy.context.scene
    scene.render.image_settings.views_format = "INDIVIDUAL"
    out = {"left": [], "right": []}
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(seeds):
            scene.cycles.seed = seed
            scene.render.filepath = str(Path(folder) / f"c{seed}_")
            bpy.ops.render.render(write_still=True)
            for eye, suffix in (("left", "_L"), ("right", "_R")):
                image = bpy.data.images.load(str(Path(folder) / f"c{seed}_{suffix}.exr"))
                w, h = image.size
                out[eye].append(np.array(image.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1, :, :3])
                bpy.data.images.remove(image)
    return {k: np.stack(v) for k, v in out.items()}


def _mvpt_eyes(seeds: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        exported = export_current(tmp)
        assert not exported.warnings, exported.warnings
        scene = mvpt.load_file(exported.xml)
        assert [v["id"] for v in scene.views] == ["left", "right"]
        runs = [mvpt.render(scene, seed=1000 + s, threads=2, method="pt") for s in range(seeds)]
    return {eye: np.stack([r.images[eye] for r in runs]).astype(np.float64) for eye in ("left", "right")}


@pytest.mark.parametrize("mode,pivot", [("OFFAXIS", "CENTER"), ("OFFAXIS", "LEFT"), ("PARALLEL", "RIGHT"),
                                        ("TOE", "CENTER")])
def test_each_eye_agrees_with_cycles(mode, pivot):
    _stereo_scene(mode, pivot)
    cy, mv = _cycles_eyes(SEEDS), _mvpt_eyes(SEEDS)
    for eye in ("left", "right"):
        a = agreement(mv[eye], cy[eye])
        print(f"\n{mode} {pivot} {eye}: mvpt {a['mvpt']:.5f} vs Cycles {a['cycles']:.5f}, z {a['z']:+.2f}, "
              f"largest block |z| {a['max_block_z']:.2f}")
        assert abs(a["z"]) < 4.0 and a["max_block_z"] < 4.5, (mode, pivot, eye, a)
    swapped = agreement(mv["left"], cy["right"])
    assert swapped["max_block_z"] > 4.5, swapped  # the eyes differ, and the test sees it


def test_a_stereo_shot_has_both_eyes_per_frame(tmp_path):
    scene = _stereo_scene("OFFAXIS")
    scene.camera.keyframe_insert("location", frame=1)
    scene.camera.location.x += 0.3
    scene.camera.keyframe_insert("location", frame=2)
    exported = export_current(tmp_path, frames=(1, 2))
    ids = [v["id"] for v in mvpt.load_file(exported.xml).views]
    assert ids == ["frame0001_left", "frame0001_right", "frame0002_left", "frame0002_right"]


def test_quilt_views_share_the_focal_plane_and_agree_with_cycles():
    """camera.quilt_eyes: five views over a 40-degree cone; the outermost view, rendered by mvpt
    from the converted scene, agrees with Cycles' render of the camera moved and shifted the same
    way (as bench/bench_vs_cycles.py renders a quilt view by view), and a point of the focal
    plane stays at the image's middle in every view."""
    from mathutils import Matrix
    from mvpt.blender import camera
    scene = table_scene()
    add_light("POINT", (1.0, -0.5, 2.5), energy=150.0, shadow_soft_size=0.0)
    cam = scene.camera
    distance = 3.0 * 2 ** 0.5  # the camera is 3 m back and 3 m up, looking 45 degrees down at the origin
    eyes = camera.quilt_eyes(cam.data, 5, 40.0, distance)
    assert [e[0] for e in eyes] == ["view00", "view01", "view02", "view03", "view04"]
    assert eyes[0][1][0][3] == pytest.approx(-distance * np.tan(np.radians(20)))
    with tempfile.TemporaryDirectory() as tmp:
        exported = export_current(tmp, eyes=eyes)
        loaded = mvpt.load_file(exported.xml)
        assert [v["id"] for v in loaded.views] == [e[0] for e in eyes]
        runs = [mvpt.render(loaded, seed=1000 + s, threads=2, method="pt", views=["view00"]) for s in range(SEEDS)]
    mv = np.stack([r.images["view00"] for r in runs]).astype(np.float64)
    base, shift = cam.matrix_world.copy(), cam.data.shift_x
    cam.matrix_world = base @ Matrix(eyes[0][1])
    cam.data.shift_x = shift + eyes[0][2]
    from blender_scenes import cycles_images
    cy = cycles_images(SEEDS)
    a = agreement(mv, cy)
    print(f"\nquilt view 0: mvpt {a['mvpt']:.5f} vs Cycles {a['cycles']:.5f}, z {a['z']:+.2f}, largest block |z| "
          f"{a['max_block_z']:.2f}")
    assert abs(a["z"]) < 4.0 and a["max_block_z"] < 4.5, a
    # The focal point (the origin) projects to the middle of every view: its direction from each
    # eye, in that eye's camera frame, over the shifted frustum's half-width, is zero.
    for name, pose, dx in eyes:
        m = np.array(base @ Matrix(pose))
        p = np.linalg.inv(m) @ np.array([0.0, 0.0, 0.0, 1.0])
        x_image = (p[0] / -p[2]) * cam.data.lens / cam.data.sensor_width  # fraction of the width
        assert x_image - (shift + dx) == pytest.approx(0.0, abs=1e-6), name  # (Blender's float32 matrices)
