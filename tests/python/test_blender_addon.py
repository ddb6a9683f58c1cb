"""The Blender add-on (docs/blender.md, "The add-on"): registered in Blender (bpy as a module, in
background mode), F12 with the engine "mvpt" renders the scene camera's view into Blender's
render result, equal to mvpt's own render of the converted scene with the same settings; a rig
writes every view and its quilt; a shot one view per frame; the installable zip registers the
same engine."""
import importlib.util
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from blender_scenes import add_light, bpy, table_scene

import mvpt
from mvpt.blender import addon, export_current


@pytest.fixture
def engine():
    addon.register()
    yield
    addon.unregister()


def _scene(tmp_path):
    scene = table_scene()
    add_light("POINT", (1.0, -0.5, 2.5), energy=150.0, shadow_soft_size=0.0)
    scene.render.engine = addon.ENGINE
    scene.mvpt.spp = 4
    scene.mvpt.seed = 3
    scene.mvpt.output = str(tmp_path / "views") + "/"
    scene.render.filepath = str(tmp_path / "f12.exr")
    return scene


def _f12(scene) -> np.ndarray:
    """F12 in background mode: the render result as saved, top row first, RGB."""
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    w, h = image.size
    pixels = np.array(image.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1, :, :3]
    bpy.data.images.remove(image)
    return pixels


def test_f12_renders_the_camera_as_mvpt_does(engine, tmp_path):
    scene = _scene(tmp_path)
    shown = _f12(scene)
    exported = export_current(tmp_path / "xml")
    own = mvpt.render(mvpt.load_file(exported.xml), spp=4, seed=3, method="mvpt").images["camera"]
    assert shown.shape == own.shape == (32, 32, 3)
    assert np.array_equal(shown, own)  # the same render, bit for bit (float32 EXR)
    assert (tmp_path / "views" / "untitled_camera.exr").exists()


def test_f12_renders_a_rig_and_its_quilt(engine, tmp_path):
    scene = _scene(tmp_path)
    scene.mvpt.mode = "RIG"
    scene.mvpt.rig = "linear:n=4,baseline=0.3"
    scene.mvpt.method = "pt"
    _f12(scene)
    written = sorted(p.name for p in (tmp_path / "views").iterdir())
    assert sum(p.endswith(".exr") for p in written) == 4, written
    assert any("_qs2x2a1" in p and p.endswith(".png") for p in written), written


def test_f12_renders_the_frame_range_as_a_shot(engine, tmp_path):
    scene = _scene(tmp_path)
    scene.frame_start, scene.frame_end = 1, 3
    cam = scene.camera
    cam.keyframe_insert("location", frame=1)
    cam.location.x += 0.5
    cam.keyframe_insert("location", frame=3)
    scene.frame_set(1)
    scene.mvpt.mode = "SHOT"
    _f12(scene)
    written = sorted(p.name for p in (tmp_path / "views").glob("*.exr"))
    assert written == [f"untitled_frame{f:04d}.exr" for f in (1, 2, 3)]


def test_the_zip_installs_the_same_engine(tmp_path):
    zip_path = tmp_path / "mvpt_blender.zip"
    run = subprocess.run([sys.executable, "-m", "mvpt", "blender-addon", "-o", str(zip_path)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    with zipfile.ZipFile(zip_path) as z:
        assert z.namelist() == ["mvpt_blender/__init__.py"]
        z.extractall(tmp_path / "addons")
    spec = importlib.util.spec_from_file_location("mvpt_blender", tmp_path / "addons" / "mvpt_blender" / "__init__.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.bl_info["category"] == "Render" and module.bl_info["name"] == "mvpt"
    module.register()
    try:
        assert addon.ENGINE in {getattr(e, "bl_idname", None) for e in bpy.types.RenderEngine.__subclasses__()}
        bpy.context.scene.render.engine = addon.ENGINE  # (an engine Blender does not know is a TypeError)
        assert hasattr(bpy.types.Scene, "mvpt")
    finally:
        module.unregister()
    assert not hasattr(bpy.types.Scene, "mvpt")


def test_f12_renders_a_looking_glass_quilt(engine, tmp_path):
    scene = _scene(tmp_path)
    scene.mvpt.mode = "QUILT"
    scene.mvpt.views, scene.mvpt.cone = 6, 35.0
    scene.camera.data.dof.focus_distance = 4.2
    shown = _f12(scene)
    written = sorted(p.name for p in (tmp_path / "views").iterdir())
    assert [p for p in written if p.endswith(".exr")] == [f"untitled_view{i:02d}.exr" for i in range(6)]
    assert any("_qs3x2a1" in p and p.endswith(".png") for p in written), written
    # The image editor shows view 0, the leftmost.
    from mvpt.runs import load_run
    views = load_run(tmp_path / "views").images
    assert np.array_equal(shown, np.asarray(views["view00"], dtype=np.float32)[..., :3])
    assert not np.array_equal(shown, np.asarray(views["view05"], dtype=np.float32)[..., :3])


def test_f12_renders_a_device_quilt(engine, tmp_path):
    # Looking Glass Portrait at 5 % of its view size: 48 views of 21x28 in its 8x6 layout; the
    # image editor shows view 0 at Blender's own render size (400x400 at 5 %: 20x20).
    scene = _scene(tmp_path)
    scene.mvpt.mode, scene.mvpt.device, scene.mvpt.spp = "QUILT", "portrait", 1
    scene.render.resolution_x = scene.render.resolution_y = 400
    scene.render.resolution_percentage = 5
    scene.camera.data.dof.focus_distance = 4.2
    shown = _f12(scene)
    assert shown.shape == (20, 20, 3)
    written = sorted(p.name for p in (tmp_path / "views").iterdir())
    assert sum(p.endswith(".exr") for p in written) == 48
    assert [p for p in written if "_qs" in p] == ["untitled_qs8x6a0.75.png"], written
    from mvpt.runs import load_run
    view0 = np.asarray(load_run(tmp_path / "views").images["view00"], dtype=np.float32)[..., :3]
    assert view0.shape == (28, 21, 3)
    assert np.array_equal(shown, addon.shown_view(view0, (20, 20)))
