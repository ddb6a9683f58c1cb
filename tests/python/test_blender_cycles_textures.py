"""Image textures and an HDRI world, rendered by Cycles and, converted, by mvpt, agree within the
statistics of their seeds (docs/blender.md, "How it was checked"): a floor whose colour is an
asymmetric image texture through its UV map (a flip of u or v, or the wrong colour space, moves
or changes the pattern), and the table-top lit only by an asymmetric environment map through
an Environment Texture with a Mapping rotation (a wrong turn of the map moves the light).
The same test as test_blender_cycles.py: whole image |z| < 4, every 8x8 block |z| < 4.5, and
mvpt's images with the texture or the map turned the wrong way must fail it."""
import math

import numpy as np
import pytest

from blender_scenes import agreement, bpy, cycles_images, diffuse_material, empty_scene, mvpt_images, add_camera, add_mesh

SEEDS = 12
Z_WHOLE, Z_BLOCK = 4.0, 4.5


def _passes(a: dict) -> bool:
    return abs(a["z"]) < Z_WHOLE and a["max_block_z"] < Z_BLOCK


def _image(tmp_path, name: str, w: int, h: int, pixels: np.ndarray, ext: str, colourspace: str):
    """An image of (h, w, 4) float pixels, top row first, saved to tmp_path and loaded by Blender."""
    img = bpy.data.images.new(name, w, h, float_buffer=ext == "exr", alpha=True)
    img.pixels[:] = pixels[::-1].reshape(-1).tolist()  # Blender stores the bottom row first
    path = tmp_path / f"{name}.{ext}"
    img.filepath_raw = str(path)
    img.file_format = "OPEN_EXR" if ext == "exr" else "PNG"
    img.save()
    bpy.data.images.remove(img)
    loaded = bpy.data.images.load(str(path))
    loaded.colorspace_settings.name = colourspace
    return loaded


def _quadrants(w: int, h: int) -> np.ndarray:
    """Four quadrants of different colours and a bright top-left patch: any flip shows."""
    p = np.zeros((h, w, 4), np.float32)
    p[..., 3] = 1.0
    p[: h // 2, : w // 2, :3] = (0.9, 0.2, 0.1)
    p[: h // 2, w // 2:, :3] = (0.1, 0.8, 0.2)
    p[h // 2:, : w // 2, :3] = (0.2, 0.3, 0.9)
    p[h // 2:, w // 2:, :3] = (0.7, 0.7, 0.7)
    p[: h // 8, : w // 8, :3] = 1.0
    return p


def test_image_texture_through_the_uv_map(tmp_path):
    scene = empty_scene()
    image = _image(tmp_path, "quadrants", 16, 16, _quadrants(16, 16), "png", "sRGB")
    floor = diffuse_material("floor", (0.5, 0.5, 0.5))
    nodes, links = floor.node_tree.nodes, floor.node_tree.links
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = image
    tex.interpolation = "Closest"
    links.new(tex.outputs["Color"], nodes["Diffuse BSDF"].inputs["Color"])
    add_mesh("plane", floor, size=4.0)
    add_camera((0.0, 0.0, 3.0), (0, 0, 0), lens=30.0)  # straight down, the floor filling the view
    world = bpy.data.worlds.new("world")
    scene.world = world
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    cy = cycles_images(SEEDS)
    mv, exported = mvpt_images(SEEDS)
    assert not exported.warnings, exported.warnings
    a = agreement(mv, cy)
    flipped = agreement(mv[:, :, ::-1], cy)  # the texture's u flipped shows as the image mirrored
    print(f"\ntexture: mvpt {a['mvpt']:.5f} vs Cycles {a['cycles']:.5f}, z {a['z']:+.2f}, largest block |z| "
          f"{a['max_block_z']:.2f}; mirrored: largest block |z| {flipped['max_block_z']:.1f}")
    assert _passes(a), a
    assert not _passes(flipped), flipped


def test_environment_texture_with_a_mapping_rotation(tmp_path):
    scene = empty_scene()
    w, h = 64, 32
    sky = np.full((h, w, 4), 0.2, np.float32)
    sky[..., 3] = 1.0
    sky[4:10, 8:16, :3] = (40.0, 30.0, 20.0)   # a bright patch high up at one side
    sky[h // 2:, :, :3] = (0.3, 0.25, 0.2)      # a darker lower half
    image = _image(tmp_path, "sky", w, h, sky, "exr", "Linear Rec.709")
    world = bpy.data.worlds.new("world")
    scene.world = world
    nodes, links = world.node_tree.nodes, world.node_tree.links
    env = nodes.new("ShaderNodeTexEnvironment")
    env.image = image
    env.interpolation = "Closest"
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(50))
    coords = nodes.new("ShaderNodeTexCoord")
    links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    links.new(env.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 1.5
    add_mesh("plane", diffuse_material("floor", (0.5, 0.5, 0.5)), size=8.0)
    add_mesh("cube", diffuse_material("box", (0.8, 0.7, 0.6)), size=0.8, location=(0.3, 0.2, 0.4))
    add_camera((0.0, -3.0, 3.0), (45, 0, 0), lens=30.0)
    cy = cycles_images(SEEDS)
    mv, exported = mvpt_images(SEEDS)
    assert not exported.warnings, exported.warnings
    a = agreement(mv, cy)
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(-50))  # turned the wrong way
    wrong, _ = mvpt_images(SEEDS)
    b = agreement(wrong, cy)
    print(f"\nenvironment: mvpt {a['mvpt']:.5f} vs Cycles {a['cycles']:.5f}, z {a['z']:+.2f}, largest block "
          f"|z| {a['max_block_z']:.2f}; turned the wrong way: z {b['z']:+.1f}, largest block |z| {b['max_block_z']:.1f}")
    assert _passes(a), a
    assert not _passes(b), b
