"""mvpt as a Blender render engine (docs/blender.md, "The add-on"): F12 with the engine "mvpt"
converts the evaluated scene (mvpt.blender's exporter), renders it with multi-view path tracing
or path tracing, shows the camera's view (the first view) in Blender's image editor and writes
every view, and for a rig the Looking Glass quilt, to the scene's mvpt output folder.

What it renders (`scene.mvpt.mode`): the scene camera; a Looking Glass quilt (`views` over a
view `cone`, focused at the camera's focus distance: camera.quilt_eyes); a rig around it
(`scene.mvpt.rig`, the CLI's --rig: linear:n=45,baseline=..., grid:...); or the scene's frame
range as a shot (one view per frame). Progress shows in Blender's status bar; Esc cancels (the
passes finished are kept). `register()` installs it in the running Blender (bpy as a module
included); `write_addon_zip` writes the zip that Blender's preferences install.

(No `from __future__ import annotations` here: Blender reads the settings' properties from the
class annotations, which must be the property objects themselves.)"""
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .. import __version__

ENGINE = "MVPT"

#: The add-on as Blender installs it: a package that registers this module's engine (mvpt itself
#: must be importable by Blender's Python: `<blender's python> -m pip install mvpt`).
ZIP_INIT = '''"""mvpt: multi-view path tracing as a Blender render engine."""
bl_info = {{
    "name": "mvpt",
    "description": "Multi-view path tracing: many views of one scene (quilts, stereo, shots) at once",
    "version": ({major}, {minor}, {patch}),
    "blender": (4, 2, 0),
    "location": "Render Properties > Render Engine > mvpt",
    "category": "Render",
}}


def register():
    try:
        from mvpt.blender import addon
    except ImportError as e:
        raise ImportError("the mvpt add-on needs the mvpt package in Blender's Python: "
                          "run Blender's python with -m pip install mvpt (" + str(e) + ")") from None
    addon.register()


def unregister():
    from mvpt.blender import addon
    addon.unregister()
'''


def write_addon_zip(path) -> Path:
    """The installable add-on (Blender: Preferences > Add-ons > Install from Disk): a zip of the
    package `mvpt_blender`, whose register() registers the engine of this module."""
    path = Path(path)
    parts = (__version__.split(".") + ["0", "0", "0"])[:3]
    numbers = [int("".join(c for c in p if c.isdigit()) or 0) for p in parts]
    text = ZIP_INIT.format(major=numbers[0], minor=numbers[1], patch=numbers[2])
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("mvpt_blender/__init__.py", text)
    return path


def _classes():
    """The engine, its settings and its panel (bpy imported here: this module loads without it)."""
    import bpy
    from ..looking_glass import DEVICES

    class MvptSettings(bpy.types.PropertyGroup):
        mode: bpy.props.EnumProperty(name="Render", default="CAMERA", items=[
            ("CAMERA", "Camera", "the scene camera's view"),
            ("QUILT", "Looking Glass quilt", "the views of a quilt over a view cone, focused at the camera's focus "
                                             "distance, and the quilt"),
            ("RIG", "Rig", "the views of an mvpt rig around the scene camera, and their quilt"),
            ("SHOT", "Shot", "the scene's frame range, one view per frame")])
        method: bpy.props.EnumProperty(name="Method", default="auto", items=[
            ("auto", "Automatic", "multi-view path tracing where its pilot predicts a gain over path tracing at "
                                  "equal time, else path tracing"),
            ("mvpt", "Multi-view path tracing", "share paths between the views"),
            ("pt", "Path tracing", "every view on its own")])
        device: bpy.props.EnumProperty(name="Device", default="CUSTOM", items=[
            ("CUSTOM", "Custom", "Views below, a near-square quilt, the render resolution per view")] + [
            (key, d.label, f"{d.views} views in a {d.columns}x{d.rows} quilt of views of aspect {d.aspect:g}, "
                           f"the device's view size times the render's resolution %")
            for key, d in DEVICES.items()])
        views: bpy.props.IntProperty(name="Views", default=45, min=2, max=1000,
                                     description="the quilt's views with a Custom device (Looking Glass Portrait: 48)")
        cone: bpy.props.FloatProperty(name="View cone", default=40.0, min=1.0, max=120.0,
                                      description="degrees spanned by the quilt's views (Looking Glass Portrait: 40)")
        rig: bpy.props.StringProperty(name="Rig", default="linear:n=45,baseline=0.5",
                                      description="mvpt's rig specification (mvpt render --rig)")
        spp: bpy.props.IntProperty(name="Samples", default=0, min=0,
                                   description="samples per pixel (0: Cycles' samples)")
        time: bpy.props.FloatProperty(name="Time budget", default=0.0, min=0.0, unit="TIME_ABSOLUTE",
                                      description="seconds (0: none)")
        seed: bpy.props.IntProperty(name="Seed", default=0, min=0)
        output: bpy.props.StringProperty(name="Output", default="//mvpt/", subtype="DIR_PATH",
                                         description="where every view (and a rig's quilt) is written")

    class MvptRenderEngine(bpy.types.RenderEngine):
        bl_idname = ENGINE
        bl_label = "mvpt"
        bl_use_preview = False

        def render(self, depsgraph):
            render_scene(self, depsgraph)

    class MVPT_PT_settings(bpy.types.Panel):
        bl_label = "mvpt"
        bl_space_type = "PROPERTIES"
        bl_region_type = "WINDOW"
        bl_context = "render"
        COMPAT_ENGINES = {ENGINE}

        @classmethod
        def poll(cls, context):
            return context.engine in cls.COMPAT_ENGINES

        def draw(self, context):
            settings = context.scene.mvpt
            shown = {"rig": "RIG", "device": "QUILT", "views": "QUILT", "cone": "QUILT"}
            for name in ("mode", "method", "device", "views", "cone", "rig", "spp", "time", "seed", "output"):
                if shown.get(name, settings.mode) == settings.mode:
                    row = self.layout.row()
                    row.enabled = name != "views" or settings.device == "CUSTOM"
                    row.prop(settings, name)

    return MvptSettings, MvptRenderEngine, MVPT_PT_settings


_registered: list = []


def register() -> None:
    """Register the engine, its settings (scene.mvpt) and its panel in the running Blender."""
    import bpy
    if _registered:
        return
    classes = _classes()
    for c in classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.mvpt = bpy.props.PointerProperty(type=classes[0])
    _registered.extend(classes)


def unregister() -> None:
    import bpy
    if not _registered:
        return
    del bpy.types.Scene.mvpt
    for c in reversed(_registered):
        bpy.utils.unregister_class(c)
    _registered.clear()


def quilt_views(scene) -> tuple:
    """The views of the add-on's quilt of `scene`: (camera.quilt_eyes, their size (None: the
    render resolution), the quilt's (columns, rows) (None, None: near-square)). A Looking Glass
    device (looking_glass.DEVICES) sets the views, their size (its own times the render's
    resolution percentage) and the layout; Custom takes `Views`."""
    from ..looking_glass import device
    from . import camera
    settings = scene.mvpt
    d = device(settings.device) if settings.device != "CUSTOM" else None
    views = d.views if d else settings.views
    eyes = camera.quilt_eyes(scene.camera.data, views, settings.cone, camera.focus_distance(scene.camera))
    if d is None:
        return eyes, None, (None, None)
    return eyes, d.view_size(scene.render.resolution_percentage / 100.0), (d.columns, d.rows)


def shown_view(image: np.ndarray, size: tuple) -> np.ndarray:
    """`image` (H, W, C) at Blender's render size `size` (width, height), where a device's view
    size differs from it: the nearest pixel of each (the views written are the renders)."""
    width, height = size
    h, w = image.shape[:2]
    if (w, h) == (width, height):
        return image
    rows = np.minimum((np.arange(height) + 0.5) * h / height, h - 1).astype(int)
    cols = np.minimum((np.arange(width) + 0.5) * w / width, w - 1).astype(int)
    return image[rows][:, cols]


def render_scene(engine, depsgraph) -> None:
    """The engine's render: convert, render with progress and cancel, show and write the views."""
    import bpy
    from .. import api
    from ..output import write_outputs
    from ..quilt import write_quilt
    from . import camera
    from .exporter import export_depsgraph
    scene = depsgraph.scene
    settings = scene.mvpt
    frames = (scene.frame_start, scene.frame_end) if settings.mode == "SHOT" else None
    eyes, size, layout = quilt_views(scene) if settings.mode == "QUILT" else (None, None, (None, None))
    with tempfile.TemporaryDirectory(prefix="mvpt-blend-") as folder:
        exported = export_depsgraph(depsgraph, folder, "scene", frames=frames, eyes=eyes, size=size)
        for text in exported.warnings:
            engine.report({"WARNING"}, text)
        loaded = api.load_file(exported.xml, rig=settings.rig if settings.mode == "RIG" else None)

        def progress(p: dict) -> None:
            engine.update_progress(float(p.get("fraction", 0.0)))
            engine.update_stats("", f"mvpt: pass {p.get('pass', 0)}, {p.get('elapsed', 0.0):.1f} s")
            if engine.test_break():
                raise KeyboardInterrupt  # api.render stops and keeps the passes finished
        result = api.render(loaded, spp=settings.spp, time=settings.time, seed=settings.seed,
                            method=settings.method, progress=progress, poll=0.1)
    if result.stats.get("auto"):
        engine.report({"INFO"}, f"mvpt: method auto: {result.stats['auto']['method']} ({result.stats['auto']['reason']})")
    if result.stats.get("passes", 0) == 0:
        engine.report({"WARNING"}, "mvpt: cancelled before the first pass finished")
        return
    out = Path(bpy.path.abspath(settings.output)) if settings.output else None
    stem = Path(bpy.data.filepath).stem or "untitled"
    if out is not None:
        write_outputs(result, out, stem, settings={"blender": bpy.data.filepath, "mode": settings.mode})
        if settings.mode in ("RIG", "QUILT"):
            write_quilt([result.images[v] for v in result.view_ids], out, stem, *layout)
    first = shown_view(np.asarray(result.images[result.view_ids[0]], dtype=np.float32), camera.resolution(scene))
    height, width = first.shape[:2]
    rgba = np.concatenate([first[::-1, :, :3], np.ones((height, width, 1), np.float32)], axis=2)
    shown = engine.begin_result(0, 0, width, height)
    shown.layers[0].passes["Combined"].rect = rgba.reshape(-1, 4)
    engine.end_result(shown)


def addon_zip_command(path) -> int:
    """`mvpt blender-addon [-o ZIP]`."""
    written = write_addon_zip(path)
    print(f"wrote {written} (Blender: Preferences > Add-ons > Install from Disk; mvpt must be importable "
          f"by Blender's Python)")
    return 0
