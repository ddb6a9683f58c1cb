"""What the Blender exporter writes: meshes split by material slot with Blender's corner normals
(flat and smooth) and uvs, shared mesh files, exact and approximated materials with their
warnings, light power conversions, the camera's field of view, and the scene's defaults."""
import math
import re

import numpy as np
import pytest

from blender_scenes import add_camera, add_light, add_mesh, bpy, diffuse_material, empty_scene

import mvpt
from mvpt.blender import export_current


def _ply(path):
    """Vertex and face arrays of a binary PLY written by the exporter."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    n_v = int(re.search(r"element vertex (\d+)", header).group(1))
    props = re.findall(r"property float (\w+)", header)
    vertices = np.frombuffer(data, "<f4", n_v * len(props), end).reshape(n_v, len(props))
    faces = np.frombuffer(data, [("c", "u1"), ("i", "<i4", (3,))], offset=end + vertices.nbytes)
    return dict(zip(props, vertices.T)), faces["i"]


def _scene():
    empty_scene(res=16, samples=4)
    add_camera((0, -4, 2), (65, 0, 0))


def test_flat_and_smooth_normals_and_slots(tmp_path):
    _scene()
    flat = add_mesh("cube", diffuse_material("a", (0.5, 0.5, 0.5)), size=1.0)
    flat.data.materials.append(diffuse_material("b", (0.1, 0.2, 0.3)))
    for i, poly in enumerate(flat.data.polygons):
        poly.material_index = i % 2
    smooth = add_mesh("uv_sphere", None, radius=0.5, location=(2, 0, 0))
    bpy.ops.object.shade_smooth()
    exported = export_current(tmp_path)
    files = sorted(p.name for p in (tmp_path / "meshes").iterdir())
    assert files == ["Cube_0.ply", "Cube_1.ply", "Sphere.ply"], files
    v, f = _ply(tmp_path / "meshes" / "Cube_0.ply")
    assert len(f) == 6 and {"u", "v"} <= set(v)  # three quads, as triangles
    normals = np.stack([v["nx"], v["ny"], v["nz"]], 1)
    assert np.allclose(np.abs(normals).max(axis=1), 1.0)  # flat: axis-aligned face normals
    v, f = _ply(tmp_path / "meshes" / "Sphere.ply")
    p, n = np.stack([v["x"], v["y"], v["z"]], 1), np.stack([v["nx"], v["ny"], v["nz"]], 1)
    radial = np.sum(n * p, axis=1) / np.linalg.norm(p, axis=1)
    assert radial.min() > 0.98  # smooth: close to radial at every vertex,
    assert len(np.unique(n[f].round(4).reshape(len(f), -1), axis=0)) == len(f)  # differing over each face
    mvpt.load_file(exported.xml)


def test_instances_share_a_mesh_file(tmp_path):
    _scene()
    a = add_mesh("cube", None, size=0.5)
    b = bpy.data.objects.new("copy", a.data)
    bpy.context.scene.collection.objects.link(b)
    b.location = (1, 0, 0)
    exported = export_current(tmp_path)
    text = exported.xml.read_text()
    # One shapegroup of the mesh, in memory once, and an instance of it per object.
    assert text.count('value="meshes/Cube.ply"') == 1
    assert text.count('type="shapegroup"') == 1 and text.count('type="instance"') == 2
    assert len(list((tmp_path / "meshes").iterdir())) == 1
    assert len(mvpt.load_file(exported.xml).views) == 1


def test_instances_render_as_separate_copies(tmp_path):
    """The instanced scene and the same scene with a copy of the mesh per object render alike
    (the per-block test of test_blender_cycles.py, mvpt against mvpt); an emitting shared mesh
    is written as separate shapes (no emitters in shapegroups)."""
    from blender_scenes import agreement, table_scene
    table_scene()
    add_light("POINT", (1.0, -0.5, 2.5), energy=150.0, shadow_soft_size=0.0)
    cube = bpy.data.objects["Cube"]
    for x in (-1.0, -0.4):
        other = bpy.data.objects.new(f"copy{x}", cube.data)
        bpy.context.scene.collection.objects.link(other)
        other.location = (x, 0.6, 0.4)
        other.rotation_euler = (0.0, 0.0, 0.5)

    def images(folder):
        exported = export_current(folder)
        scene = mvpt.load_file(exported.xml)
        return exported.xml.read_text(), np.stack([mvpt.render(scene, spp=8, seed=500 + i, method="pt").images["camera"]
                                                   for i in range(12)]).astype(np.float64)
    text, shared = images(tmp_path / "shared")
    assert text.count('type="instance"') == 3
    for obj in bpy.data.objects:
        if obj.name.startswith("copy"):
            obj.data = obj.data.copy()
    text, copies = images(tmp_path / "copies")
    assert 'type="instance"' not in text
    a = agreement(shared, copies)
    assert abs(a["z"]) < 4.0 and a["max_block_z"] < 4.5, a
    # An emitting mesh used twice stays two shapes.
    glow = bpy.data.materials.new("glow")
    nodes = glow.node_tree.nodes
    nodes.clear()
    emission = nodes.new("ShaderNodeEmission")
    glow.node_tree.links.new(emission.outputs[0], nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    lamp = add_mesh("plane", glow, size=0.2, location=(0, 0, 2))
    twin = bpy.data.objects.new("twin", lamp.data)
    bpy.context.scene.collection.objects.link(twin)
    twin.location = (0.5, 0, 2)
    text = export_current(tmp_path / "glow").xml.read_text()
    assert text.count('type="area"') == 2


def test_unknown_node_warns_once_with_fallback(tmp_path):
    _scene()
    m = bpy.data.materials.new("odd")
    nodes = m.node_tree.nodes
    nodes.clear()
    toon = nodes.new("ShaderNodeBsdfToon")
    out = nodes.new("ShaderNodeOutputMaterial")
    m.node_tree.links.new(toon.outputs[0], out.inputs["Surface"])
    add_mesh("cube", m, size=0.5)
    add_mesh("cube", m, size=0.5, location=(1, 0, 0))
    exported = export_current(tmp_path)
    hits = [w for w in exported.warnings if "material 'odd'" in w]
    assert len(hits) == 1 and toon.name in hits[0] and "diffuse 0.8" in hits[0], exported.warnings


def test_principled_without_specular_is_exact_otherwise_warned(tmp_path):
    _scene()
    plain = bpy.data.materials.new("plain")
    plain.node_tree.nodes["Principled BSDF"].inputs["Specular IOR Level"].default_value = 0.0
    shiny = bpy.data.materials.new("shiny")
    shiny.node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 0.5
    add_mesh("cube", plain, size=0.5)
    add_mesh("cube", shiny, size=0.5, location=(1, 0, 0))
    exported = export_current(tmp_path)
    assert not [w for w in exported.warnings if "'plain'" in w]
    assert [w for w in exported.warnings if "'shiny'" in w and "approximated" in w]
    text = exported.xml.read_text()
    assert "roughconductor" in text and "roughplastic" in text and "blendbsdf" in text
    mvpt.load_file(exported.xml)


def test_light_units(tmp_path):
    _scene()
    add_light("POINT", (0, 0, 2), energy=100.0, shadow_soft_size=0.0, color=(1.0, 0.5, 0.25))
    add_light("SUN", (0, 0, 3), energy=2.0, angle=0.0)
    add_light("AREA", (0, 0, 2), energy=30.0, shape="RECTANGLE", size=2.0, size_y=0.5)
    add_light("SPOT", (0, 0, 2), energy=50.0, spot_size=math.radians(60), spot_blend=0.0, shadow_soft_size=0.0)
    exported = export_current(tmp_path)
    text = exported.xml.read_text()
    i = 100 / (4 * math.pi)
    assert f'name="intensity" value="{i:.9g}, {i / 2:.9g}, {i / 4:.9g}"' in text
    assert 'name="irradiance" value="2, 2, 2"' in text
    assert f'name="radiance" value="{30 / (math.pi * 1.0):.9g}' in text
    assert re.search(r'name="cutoff_angle" value="(29.99999\d*|30(\.0*\d)?)"', text)
    mvpt.load_file(exported.xml)


def test_camera_and_defaults(tmp_path):
    empty_scene(res=32, samples=7)
    bpy.context.scene.render.resolution_x = 40
    bpy.context.scene.render.resolution_percentage = 50
    add_camera((0, -4, 2), (65, 0, 0), lens=50.0)
    exported = export_current(tmp_path)
    text = exported.xml.read_text()
    assert '<default name="spp" value="7"/>' in text and '<default name="width" value="20"/>' in text
    assert '<default name="max_depth" value="4"/>' in text  # Cycles' 2 bounces + 2
    fov = 2 * math.degrees(math.atan(36 / 100))
    assert f'name="fov" value="{fov:.9g}"' in text and 'value="larger"' in text
    scene = mvpt.load_file(exported.xml)
    assert (scene.views[0]["width"], scene.views[0]["height"]) == (20, 16)


def test_no_camera_is_an_error(tmp_path):
    empty_scene()
    add_mesh("cube", None)
    with pytest.raises(ValueError, match="no camera"):
        export_current(tmp_path)
