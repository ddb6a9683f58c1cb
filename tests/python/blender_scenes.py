"""Small Blender scenes built with bpy by the tests (factory settings, an empty scene), and
renders of them by Cycles (CPU) and by mvpt, several seeds each, for statistical comparisons.

Cycles is set to render what mvpt renders: a box filter one pixel wide, no denoising, no
clamping, no adaptive sampling, no light threshold, one bounce limit for every kind of bounce."""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest

bpy = pytest.importorskip("bpy", reason="Blender's Python module is not installed (pip install \"mvpt[blender]\")")

import mvpt  # noqa: E402
from mvpt.blender import export_current  # noqa: E402

RES = 32
BOUNCES = 2


def empty_scene(res: int = RES, samples: int = 16):
    """Factory settings, no objects, Cycles on the CPU set up as the module says."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.render.resolution_x = scene.render.resolution_y = res
    scene.render.resolution_percentage = 100
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    c = scene.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.max_bounces = BOUNCES
    for kind in ("diffuse", "glossy", "transmission", "volume", "transparent_max"):
        setattr(c, kind + "_bounces", BOUNCES)
    return scene


def diffuse_material(name: str, colour) -> object:
    m = bpy.data.materials.new(name)
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.clear()
    d = nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*colour, 1.0)
    out = nodes.new("ShaderNodeOutputMaterial")
    links.new(d.outputs[0], out.inputs["Surface"])
    return m


def add_mesh(kind: str, material, **kw):
    getattr(bpy.ops.mesh, f"primitive_{kind}_add")(**kw)
    obj = bpy.context.object
    if material is not None:
        obj.data.materials.append(material)
    return obj


def add_camera(location, rotation_deg, lens: float = 35.0):
    cam = bpy.data.cameras.new("camera")
    cam.lens = lens
    obj = bpy.data.objects.new("camera", cam)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    obj.rotation_euler = tuple(math.radians(a) for a in rotation_deg)
    bpy.context.scene.camera = obj
    return obj


def add_light(kind: str, location, rotation_deg=(0, 0, 0), **settings):
    light = bpy.data.lights.new(kind.lower(), kind)
    for k, v in settings.items():
        setattr(light, k, v)
    obj = bpy.data.objects.new(kind.lower(), light)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    obj.rotation_euler = tuple(math.radians(a) for a in rotation_deg)
    return obj


def set_world_colour(colour, strength: float):
    world = bpy.data.worlds.new("world")
    bpy.context.scene.world = world
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*colour, 1.0)
    background.inputs["Strength"].default_value = strength


def table_scene():
    """A grey floor filling the view, a white cube on it casting a shadow, seen from above at an
    angle: direct light, a shadow and one diffuse inter-reflection, no light in view."""
    scene = empty_scene()
    add_mesh("plane", diffuse_material("floor", (0.5, 0.5, 0.5)), size=8.0)
    add_mesh("cube", diffuse_material("box", (0.8, 0.7, 0.6)), size=0.8, location=(0.3, 0.2, 0.4))
    add_camera((0.0, -3.0, 3.0), (45, 0, 0), lens=30.0)
    return scene


def cycles_images(seeds: int) -> np.ndarray:
    """Cycles renders of the current scene with seeds 0..seeds-1: (seeds, H, W, 3), top row first."""
    scene = bpy.context.scene
    out = []
    with tempfile.TemporaryDirectory() as folder:
        for seed in range(seeds):
            scene.cycles.seed = seed
            scene.render.filepath = str(Path(folder) / f"cycles_{seed}.exr")
            bpy.ops.render.render(write_still=True)
            image = bpy.data.images.load(scene.render.filepath)
            w, h = image.size
            pixels = np.array(image.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1, :, :3]
            bpy.data.images.remove(image)
            out.append(pixels)
    return np.stack(out)


def mvpt_images(seeds: int, folder=None):
    """mvpt renders of the current scene, converted by mvpt.blender, with seeds 0..seeds-1 and
    Cycles' samples per pixel: ((seeds, H, W, 3), the Export)."""
    with tempfile.TemporaryDirectory() as tmp:
        exported = export_current(folder or tmp)
        scene = mvpt.load_file(exported.xml)
        images = [mvpt.render(scene, seed=1000 + s, threads=2).images["camera"] for s in range(seeds)]
    return np.stack(images).astype(np.float64), exported


def block_means(images: np.ndarray, block: int = 8) -> np.ndarray:
    """Per image, the mean of R, G and B over each block x block tile: (seeds, H/b, W/b)."""
    n, h, w, _ = images.shape
    y = images.mean(axis=3)
    return y.reshape(n, h // block, block, w // block, block).mean(axis=(2, 4))


def agreement(mv: np.ndarray, cy: np.ndarray, scale: float = 1.0) -> dict:
    """z-scores of mvpt (times `scale`) against Cycles: of the whole image's mean and of each
    8x8 block's, each from the spread of the seeds' estimates (standard errors of both)."""
    def z(a, b):
        se = np.sqrt(a.var(axis=0, ddof=1) / len(a) + b.var(axis=0, ddof=1) / len(b))
        return (a.mean(axis=0) - b.mean(axis=0)) / se
    mv = mv * scale
    whole_m, whole_c = mv.mean(axis=(1, 2, 3)), cy.mean(axis=(1, 2, 3))
    blocks = z(block_means(mv), block_means(cy))
    return {"mvpt": float(whole_m.mean()), "cycles": float(whole_c.mean()), "z": float(z(whole_m, whole_c)),
            "max_block_z": float(np.abs(blocks).max()), "blocks": blocks}
