"""mvpt against Cycles as its users render a Looking Glass quilt: one Cycles render per view.

    python bench/bench_vs_cycles.py                       # 45 views of 48x64, 20 s per method
    python bench/bench_vs_cycles.py --views 9 --time 5    # a quick run
    python bench/bench_vs_cycles.py --shot 24             # a 24-frame camera move instead of a quilt

Builds a table-top in bpy (a wood-textured floor, a gold and a rough plastic sphere, a glass
sphere, an HDRI world and a small area light; the assets of ../shared/scenes, or generated
ones without it) and a quilt of --views views over a --cone view cone focused on the table
(mvpt.blender.camera.quilt_eyes). At equal wall-clock time --time, setup included:

- **Cycles per view**, as the Looking Glass add-on renders a quilt: for each view the camera is
  moved and shifted and Cycles renders it (CPU, its defaults: adaptive sampling, light tree,
  Blackman-Harris filter; denoising off, since a denoised image is not an estimate of the
  image) and writes its EXR, its own seed per view, each view given --time / views minus the
  setup that a one-sample render of a view measures (Cycles' time limit; at least MIN_LIMIT,
  so with many views Cycles may take longer than --time, and the ratios are then taken at
  equal time as relMSE x time);
- **mvpt `pt`** and **mvpt `mvpt`**: the scene converted once (mvpt.blender) with the same views,
  rendered together for --time.

With --shot FRAMES the views are the frames of a camera move across the table instead (24 fps,
motion blur off, nothing else moving): Cycles renders the frames one by one, as an animation is
rendered, and mvpt the frame range as one shot (`export_current(frames=...)`, one view per frame).

Each is scored against its own long reference (--ref-spp samples per pixel of the same renderer:
the two model the Principled BSDF differently, docs/blender.md), by the relMSE of the views
(ε = 0.01) and by the relMSE a display shows (each view blended with its neighbours, 1/4, 1/2,
1/4). Printed: each method's wall time and relMSE, Cycles' relMSE x time over the method's
(at equal time, > 1: the method is ahead), the time the method needs for Cycles' error (its
time x its relMSE / Cycles' relMSE), and Cycles' and mvpt's path-traced samples per second. The references' own noise is not
subtracted (Cycles gives no variance): with --ref-spp far above what --time reaches, it is a
few per cent of the errors, which it raises alike."""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: The least time limit per view given to Cycles (when its setup alone exceeds --time / views, it
#: then takes longer than --time, and the ratios below are taken at equal time by relMSE x time).
MIN_LIMIT = 0.05
TEXTURES = ROOT.parent / "shared" / "scenes" / "m3data-testsuite" / "common" / "textures"


def _generated(folder: Path) -> tuple[str, str]:
    """A checker floor texture and a sky with a bright patch, when ../shared is absent."""
    import bpy
    wood = bpy.data.images.new("floor", 64, 64)
    y, x = np.mgrid[0:64, 0:64]
    c = np.where(((x // 8) + (y // 8)) % 2 == 0, 0.6, 0.3)[..., None] * np.array([1.0, 0.8, 0.6])
    wood.pixels[:] = np.concatenate([c, np.ones((64, 64, 1))], axis=2).reshape(-1).tolist()
    wood.filepath_raw, wood.file_format = str(folder / "floor.png"), "PNG"
    wood.save()
    sky = bpy.data.images.new("sky", 128, 64, float_buffer=True)
    s = np.full((64, 128, 3), 0.4)
    s[40:52, 20:36] = (30.0, 26.0, 20.0)
    s[:32] *= 0.6
    sky.pixels[:] = np.concatenate([s, np.ones((64, 128, 1))], axis=2).reshape(-1).tolist()
    sky.filepath_raw, sky.file_format = str(folder / "sky.exr"), "OPEN_EXR"
    sky.save()
    return str(folder / "floor.png"), str(folder / "sky.exr")


def build_scene(width: int, height: int, folder: Path):
    """The table-top in bpy; returns the scene."""
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
    scene.render.threads_mode = "AUTO"
    scene.render.image_settings.file_format, scene.render.image_settings.color_depth = "OPEN_EXR", "32"
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    floor_tex, sky_tex = ((str(TEXTURES / "wood.jpg"), str(TEXTURES / "museum.exr")) if TEXTURES.is_dir()
                          else _generated(folder))
    world = bpy.data.worlds.new("world")
    scene.world = world
    env = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(sky_tex)
    world.node_tree.links.new(env.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])

    def principled(name, base, metallic=0.0, rough=0.5, transmission=0.0, texture=None):
        m = bpy.data.materials.new(name)
        if m.node_tree is None:  # (Blender 5 makes every material with its node tree)
            m.use_nodes = True
        p = m.node_tree.nodes["Principled BSDF"]
        p.inputs["Base Color"].default_value = (*base, 1.0)
        p.inputs["Metallic"].default_value = metallic
        p.inputs["Roughness"].default_value = rough
        p.inputs["Transmission Weight"].default_value = transmission
        if texture:
            t = m.node_tree.nodes.new("ShaderNodeTexImage")
            t.image = bpy.data.images.load(texture)
            m.node_tree.links.new(t.outputs["Color"], p.inputs["Base Color"])
        return m

    def add(kind, material, **kw):
        getattr(bpy.ops.mesh, f"primitive_{kind}_add")(**kw)
        obj = bpy.context.object
        obj.data.materials.append(material)
        if kind == "uv_sphere":
            bpy.ops.object.shade_smooth()
        return obj

    add("plane", principled("floor", (0.5, 0.5, 0.5), texture=floor_tex), size=4.0)
    add("uv_sphere", principled("gold", (1.0, 0.78, 0.34), metallic=1.0, rough=0.25), radius=0.32,
        location=(-0.55, 0.2, 0.32))
    add("uv_sphere", principled("plastic", (0.75, 0.12, 0.1), rough=0.45), radius=0.28, location=(0.55, 0.35, 0.28))
    add("uv_sphere", principled("glass", (1.0, 1.0, 1.0), rough=0.0, transmission=1.0), radius=0.3,
        location=(0.05, -0.45, 0.3))
    light = bpy.data.objects.new("light", bpy.data.lights.new("light", "AREA"))
    light.data.energy, light.data.size = 60.0, 0.5
    light.location = (0.8, -0.6, 2.4)
    scene.collection.objects.link(light)
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.data.lens = 50.0
    cam.location = (0.0, -3.6, 1.6)
    cam.rotation_euler = (math.radians(66), 0.0, 0.0)
    cam.data.dof.focus_distance = 3.8
    return scene


def quilt_setups(scene, eyes) -> list:
    """(view name, a function that sets the scene's camera to that view) per quilt view."""
    from mathutils import Matrix
    cam = scene.camera
    base, shift = cam.matrix_world.copy(), cam.data.shift_x

    def setup(pose, dx):
        def apply():
            cam.matrix_world = base @ Matrix(pose)
            cam.data.shift_x = shift + dx
        return apply
    return [(name, setup(pose, dx)) for name, pose, dx in eyes]


def shot_setups(scene, frames: int) -> list:
    """(view name, a function that sets the scene to that frame) per frame of a `frames`-frame
    camera move (frame 1 on; mvpt names a shot's views frame0001, ...)."""
    return [(f"frame{f:04d}", (lambda f=f: scene.frame_set(f))) for f in range(1, frames + 1)]


def animate_camera(scene, frames: int) -> None:
    """A dolly of the camera across the table over frames 1..`frames` (24 fps, no motion blur:
    every frame an instant), nothing else moving."""
    cam = scene.camera
    scene.frame_start, scene.frame_end, scene.render.fps = 1, frames, 24
    scene.render.use_motion_blur = False
    start = cam.location.copy()
    for f, dx in ((1, -0.6), (frames, 0.6)):
        cam.location = (start.x + dx, start.y, start.z)
        cam.keyframe_insert("location", frame=f)
    scene.frame_set(1)


def cycles_views(scene, setups, samples: int, time_limit: float, seed: int, folder: Path) -> tuple[dict, float]:
    """One Cycles render per view (quilt_setups, shot_setups); the images and the wall time."""
    import bpy
    cam = scene.camera
    base, shift, frame = cam.matrix_world.copy(), cam.data.shift_x, scene.frame_current
    scene.cycles.samples, scene.cycles.time_limit = samples, time_limit
    out = {}
    seconds = 0.0
    try:
        for i, (name, apply) in enumerate(setups):
            apply()
            scene.cycles.seed = seed * 1000 + i
            scene.render.filepath = str(folder / f"{name}.exr")
            t0 = time.perf_counter()  # (the render and its file, as a user's quilt render writes them)
            bpy.ops.render.render(write_still=True)
            seconds += time.perf_counter() - t0
            image = bpy.data.images.load(scene.render.filepath)
            w, h = image.size
            out[name] = np.array(image.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1, :, :3]
            bpy.data.images.remove(image)
    finally:
        scene.frame_set(frame)
        cam.matrix_world, cam.data.shift_x = base, shift
    return out, seconds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--views", type=int, default=45)
    ap.add_argument("--cone", type=float, default=40.0, help="view cone in degrees (Looking Glass Portrait: 40)")
    ap.add_argument("--width", type=int, default=48)
    ap.add_argument("--height", type=int, default=64)
    ap.add_argument("--time", type=float, default=20.0, help="seconds per method, setup included")
    ap.add_argument("--ref-spp", type=int, default=512)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--shot", type=int, default=0, metavar="FRAMES",
                    help="instead of a quilt, a camera move of FRAMES frames across the table (Cycles renders "
                         "frame by frame; mvpt the frame range as one shot)")
    args = ap.parse_args(argv)
    try:
        import bpy  # noqa: F401
    except ImportError:
        print('bench_vs_cycles needs Blender\'s Python module: pip install "mvpt[blender]" (Python 3.11)')
        return 1
    import mvpt
    from mvpt import metrics
    from mvpt.blender import camera, export_current
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        scene = build_scene(args.width, args.height, folder)
        if args.shot:
            animate_camera(scene, args.shot)
            setups = shot_setups(scene, args.shot)
            exported = export_current(folder / "xml", frames=(1, args.shot))
            what = f"a {args.shot}-frame camera move"
        else:
            eyes = camera.quilt_eyes(scene.camera.data, args.views, args.cone, scene.camera.data.dof.focus_distance)
            setups = quilt_setups(scene, eyes)
            exported = export_current(folder / "xml", eyes=eyes)
            what = f"{args.views} views over {args.cone:g} degrees"
        loaded = mvpt.load_file(exported.xml)
        views = len(setups)
        print(f"{what}, {args.width}x{args.height}, {args.time:g} s per method", flush=True)
        # References, each renderer its own.
        t0 = time.perf_counter()
        cy_ref, cy_ref_time = cycles_views(scene, setups, args.ref_spp, 0.0, 999, folder / "ref")
        print(f"Cycles reference: {args.ref_spp} spp in {cy_ref_time:.0f} s", flush=True)
        mv_ref = mvpt.render(loaded, spp=args.ref_spp, seed=999, method="pt")
        print(f"mvpt reference: {args.ref_spp} spp in {mv_ref.stats['seconds']:.0f} s", flush=True)
        pixels = views * args.width * args.height
        cycles_rate = pixels * args.ref_spp / cy_ref_time
        # Cycles' setup per view: a one-sample render of the views.
        _, one = cycles_views(scene, setups, 1, 0.0, 998, folder / "one")
        setup = one / views
        limit = max(MIN_LIMIT, args.time / views - setup)
        cy, cy_time = cycles_views(scene, setups, 1 << 16, limit, args.seed, folder / "eq")
        results = {"Cycles per view": (cy, cy_time, cy_ref)}
        for method in ("pt", "mvpt"):
            r = mvpt.render(loaded, time=args.time, seed=args.seed, method=method)
            results[f"mvpt {method}"] = (r.images, r.stats["wall_time"], mv_ref.images)
            if method == "pt":
                mvpt_rate = r.stats["samples_per_second"]
        print(f"\nCycles' setup {setup:.2f} s per view, time limit {limit:.2f} s per view; references took "
              f"{time.perf_counter() - t0:.0f} s in all")
        base = {k: (metrics.errors(images, ref, with_flip=False).overall.relmse, metrics.display_relmse(images, ref)[0])
                for k, (images, _, ref) in results.items()}
        c_view, c_display = base["Cycles per view"]
        c_time = results["Cycles per view"][1]
        print("\n| method | wall time (s) | relMSE | Cycles / method at equal time | as a display shows it "
              "| Cycles / method at equal time | time to Cycles' relMSE (s) |")
        print("|---|---|---|---|---|---|---|")
        for k, (_, seconds, _) in results.items():
            e, d = base[k]
            # relMSE falls as 1/time for every method here: compare relMSE x time.
            print(f"| {k} | {seconds:.1f} | {e:.3e} | {c_view * c_time / (e * seconds):.2f} | {d:.3e} | "
                  f"{c_display * c_time / (d * seconds):.2f} | {seconds * e / c_view:.1f} |")
        print(f"\npath-traced samples per second: Cycles {cycles_rate / 1e6:.3f} M (its reference, setup included), "
              f"mvpt {mvpt_rate / 1e6:.3f} M (pt at equal time); mvpt's conversion warnings: {len(exported.warnings)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
