"""A Blender scene (its evaluated dependency graph) as a Mitsuba 3 XML file with PLY meshes
in one folder: <folder>/<name>.xml, <folder>/meshes/*.ply (and textures/ for packed images).

Every object instance of the graph is converted: meshes (and curves, text, surfaces, metaballs,
through their evaluated meshes) as one PLY shape per material slot at the instance's world
matrix, a mesh shared by several instances written once; lights as emitters; the scene camera
and render settings as the sensor and integrator; the world as an environment emitter. The
scene's <default>s spp, width, height and max_depth carry Cycles' samples, the resolution and
the bounce limit (overridable with -D)."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from . import animation as shots, camera, lights, materials, world
from .meshes import mesh_parts
from .ply import write_ply
from .report import Report
from .xml_writer import Element, animation, plugin, scene_text

GEOMETRY = {"MESH", "CURVE", "SURFACE", "META", "FONT"}
SKIPPED = {"CAMERA", "EMPTY", "ARMATURE", "LATTICE", "SPEAKER", "LIGHT_PROBE"}


@dataclass
class Export:
    """The written scene file and what its conversion could not carry over exactly."""
    xml: Path
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)


def safe_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "unnamed"


class _Writer:
    def __init__(self, folder: Path, report: Report):
        self.folder = folder
        self.report = report
        self.materials = materials.Materials(report, folder)
        self.meshes: dict = {}      # evaluated mesh -> [(slot, file)]
        self.groups: dict = {}      # group_key -> shapegroup id (None: its shapes emit)
        self.names: set = set()
        self.bsdf_ids: dict = {}
        self.root = Element("scene", version="3.0.0")

    def unique(self, stem: str) -> str:
        name, i = stem, 1
        while name in self.names:
            i += 1
            name = f"{stem}.{i}"
        self.names.add(name)
        return name

    @staticmethod
    def mesh_key(obj) -> tuple:
        """What identifies an object's evaluated mesh file: its mesh data (for meshes) and slots."""
        return (obj.data.as_pointer() if obj.type == "MESH" else obj.as_pointer(), len(obj.material_slots))

    @staticmethod
    def group_key(obj) -> tuple:
        """What a shapegroup of the object's shapes is shared by: its mesh and its materials."""
        return _Writer.mesh_key(obj) + tuple(s.material.name if s.material else "" for s in obj.material_slots)

    def mesh_files(self, obj) -> list:
        """(slot, relative PLY path) of the object's evaluated mesh, written on first use."""
        key = self.mesh_key(obj)
        if key in self.meshes:
            return self.meshes[key]
        mesh = obj.to_mesh()
        try:
            parts = mesh_parts(mesh, len(obj.material_slots))
        finally:
            obj.to_mesh_clear()
        files = []
        stem = self.unique(safe_name(obj.data.name if obj.data is not None else obj.name))
        for part in parts:
            rel = f"meshes/{stem}" + (f"_{part.slot}" if len(parts) > 1 or part.slot else "") + ".ply"
            write_ply(self.folder / rel, part.positions, part.normals, part.uvs, part.triangles)
            files.append((part.slot, rel))
        self.meshes[key] = files
        return files

    def bsdf_ref(self, material) -> tuple[str, object]:
        surface = self.materials.surface(material)
        key = material.name if material is not None else None
        if key not in self.bsdf_ids:
            bid = "mat-" + safe_name(key) if key is not None else "mat-default"
            surface.bsdf.attributes["id"] = bid
            self.root.add(surface.bsdf)
            self.bsdf_ids[key] = bid
        return self.bsdf_ids[key], surface

    def shapes(self, obj) -> list:
        """The object's shape elements (one per material slot, no transform yet), each with its
        material and that material's emitted radiance (None: none)."""
        out = []
        for slot, rel in self.mesh_files(obj):
            material = obj.material_slots[slot].material if slot < len(obj.material_slots) else None
            bid, surface = self.bsdf_ref(material)
            s = plugin("shape", "ply").string("filename", rel)
            s.add(Element("ref", id=bid))
            out.append((s, material, surface.emission))
        return out

    def add_instance(self, obj, matrix, keys=None) -> bool:
        """The object as an instance of a shapegroup of its shapes (written on first use), at
        `matrix` or moving through `keys`: one copy in memory for every object of the mesh and
        materials. False (nothing written) when a shape emits (mvpt, as Mitsuba, has no
        emitters in shapegroups)."""
        key = self.group_key(obj)
        if key not in self.groups:
            shapes = self.shapes(obj)
            if any(emission is not None for _, _, emission in shapes):
                self.groups[key] = None
            else:
                gid = self.unique("group-" + safe_name(obj.data.name if obj.data is not None else obj.name))
                group = self.root.add(plugin("shape", "shapegroup", gid))
                for shape, _, _ in shapes:
                    group.add(shape)
                self.groups[key] = gid
        gid = self.groups[key]
        if gid is None:
            return False
        s = plugin("shape", "instance")
        s.add(Element("ref", id=gid))
        _place(s, matrix, keys)
        s.comment = safe_name(obj.name)
        self.root.add(s)
        return True

    def add_object(self, obj, matrix, keys=None, shared=False) -> None:
        """The object's shapes at `matrix`, or moving through `keys` [(time, rows)]; as an instance
        of a shapegroup when `shared` (its mesh and materials used by several objects)."""
        if shared and self.add_instance(obj, matrix, keys):
            return
        for s, material, emission in self.shapes(obj):
            _place(s, matrix, keys)
            if emission is not None:
                s.add(plugin("emitter", "area").rgb("radiance", emission))
                self.report.warn(f"material '{material.name}' emits from the side its normals face only "
                                 f"(Cycles: both sides; the same for closed meshes)")
            s.comment = safe_name(obj.name)
            self.root.add(s)


def _place(shape: Element, matrix, keys) -> None:
    """A shape's to_world: the matrix, or the animation through `keys` [(time, rows)]."""
    if keys:
        shape.add(animation("to_world", keys))
    else:
        shape.matrix("to_world", matrix)


def _rows(matrix):
    return tuple(tuple(float(matrix[i][j]) for j in range(4)) for i in range(4))


def export_depsgraph(depsgraph, folder, name: str = "scene", frames=None, eyes=None, size=None) -> Export:
    """Write the scene of `depsgraph` (evaluated) to `folder`/`name`.xml and its meshes: at its
    current frame, or the frames (first, last) of Blender's numbering as a shot (one view per
    frame, docs/blender.md, "Animation"), its geometry, materials and lights those of the first.
    `eyes` (camera.quilt_eyes) replaces the camera (or its stereo eyes) by those views; `size`
    (width, height) is every view's instead of the render resolution (a Looking Glass device's)."""
    folder = Path(folder)
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    report = Report()
    scene = depsgraph.scene_eval
    shot = None
    if frames is not None:
        shot = shots.shot_range(scene.original, frames, report)
        shots.sample_poses(scene.original, shot, _rows)
        depsgraph = _current_depsgraph()
        scene = depsgraph.scene_eval
    w = _Writer(folder, report)
    spp = camera.samples(scene)
    width, height = size or camera.resolution(scene)
    for k, v in (("spp", spp), ("width", width), ("height", height), ("max_depth", camera.max_depth(scene))):
        w.root.add(Element("default", name=k, value=v))
    w.root.add(camera.integrator(scene, report))
    if eyes is None:
        eyes = camera.stereo_eyes(scene, report) if scene.camera is not None else []
    if shot is None:
        for eye in eyes or [None]:
            w.root.add(camera.sensor(scene, report, spp, ident=eye[0] if eye else "camera", eye=eye, size=size))
    else:
        for sensor in _shot_sensors(scene, shot, report, spp, eyes, size):
            w.root.add(sensor)
    for element in world.convert_world(scene.world, report):
        w.root.add(element)
    uses: dict = {}
    for inst in depsgraph.object_instances:
        if inst.object.type in GEOMETRY:
            key = w.group_key(inst.object)
            uses[key] = uses.get(key, 0) + 1
    for inst in depsgraph.object_instances:
        obj = inst.object
        keys = _object_keys(shot, inst, report) if shot is not None else None
        if obj.type in GEOMETRY:
            w.add_object(obj, _rows(inst.matrix_world), keys, shared=uses[w.group_key(obj)] > 1)
        elif obj.type == "LIGHT":
            if keys:
                report.warn(f"light '{obj.name}' moves over the frames: it is converted at its pose of frame "
                            f"{shot.frames[0]}")
            for element in lights.convert_light(obj, _rows(inst.matrix_world), report):
                w.root.add(element)
        elif obj.type not in SKIPPED:
            report.warn(f"object '{obj.name}' of type {obj.type} cannot be converted; left out")
    if shot is not None:
        _check_deformation(depsgraph, shot, report)
    if scene.cycles.use_adaptive_sampling if hasattr(scene, "cycles") else False:
        report.note(f"Cycles' adaptive sampling is not converted: every pixel takes {spp} samples")
    xml = folder / f"{safe_name(name)}.xml"
    xml.write_text(scene_text(w.root, f"converted by mvpt from the Blender scene '{scene.name}'"), encoding="utf-8")
    return Export(xml, report.warnings, report.notes)


def export_current(folder, name: str = "scene", frames=None, eyes=None, size=None) -> Export:
    """Write the current Blender scene (bpy.context's) to `folder`: its current frame, or the
    frames (first, last) as a shot; `eyes` (camera.quilt_eyes) as its views, of `size`."""
    return export_depsgraph(_current_depsgraph(), folder, name, frames, eyes, size)


def _current_depsgraph():
    import bpy
    return bpy.context.evaluated_depsgraph_get()


def _shot_sensors(scene, shot, report: Report, spp: int, eyes=(), size=None) -> list:
    """One sensor per frame of the shot, `frame%04d` (Blender's frame number), open over its
    shutter with the camera's poses on it; with stereo `eyes`, one per eye and frame,
    `frame%04d_left` and `_right`."""
    out = []
    for f, eye in ((f, eye) for f in shot.frames for eye in (eyes or [None])):
        on = shot.within(f)
        if shot.length > 0:
            poses = [(shot.time(shot.instants[i]), shot.camera[i]) for i in on]
            shutter = shot.shutter(f)
        else:
            poses = [(shot.time(f), shot.camera[on[0]])]
            shutter = (shot.time(f), shot.time(f))
        ident = f"frame{f:04d}" + (f"_{eye[0]}" if eye else "")
        out.append(camera.sensor(scene, report, spp, ident=ident, shutter=shutter, poses=poses, eye=eye, size=size))
    return out


def _object_keys(shot, inst, report: Report):
    """The instance's keyframes [(time, rows)] over the shot's instants, or None when it does
    not move (or is not present at every instant: then its pose at the first frame, warned)."""
    poses = shot.objects.get(shots.instance_key(inst))
    if poses is None or len(poses) != len(shot.instants):
        report.warn(f"object '{inst.object.name}' is not present at every frame: converted at its pose of frame "
                    f"{shot.frames[0]}")
        return None
    if not shots.moves(poses):
        return None
    return [(shot.time(x), m) for x, m in zip(shot.instants, poses)]


def _check_deformation(depsgraph, shot, report: Report) -> None:
    """A warning for each mesh whose evaluated vertices differ between the first and the last
    frame (armatures, shape keys, animated modifiers): its mesh of the first frame is used."""
    import bpy
    import numpy as np
    scene = depsgraph.scene_eval.original

    def vertices(graph) -> dict:
        out = {}
        for obj in graph.objects:
            if obj.type != "MESH":
                continue
            mesh = obj.to_mesh()
            try:
                co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
                mesh.vertices.foreach_get("co", co)
                out[obj.name] = co
            finally:
                obj.to_mesh_clear()
        return out

    first = vertices(depsgraph)
    scene.frame_set(shot.frames[-1])
    last = vertices(bpy.context.evaluated_depsgraph_get())
    scene.frame_set(shot.frames[0])
    for name, co in first.items():
        other = last.get(name)
        if other is not None and (other.shape != co.shape or not np.array_equal(other, co)):
            report.warn(f"object '{name}' changes shape over the frames (a deformation): its mesh of frame "
                        f"{shot.frames[0]} is used at every frame")
