"""Blender scenes in mvpt: a .blend file, or the scene bpy holds, converted to a Mitsuba 3 XML
scene with PLY meshes (docs/blender.md). Needs Blender's Python module: pip install "mvpt[blender]".

    scene = mvpt.load_blend("shot.blend", spp=64)                  # an mvpt Scene
    result = mvpt.blender.export_blend("shot.blend", "shot_xml/")  # the files, to keep and edit
    result.xml, result.warnings, result.notes

Importing this package does not import bpy; its functions do, when called."""
from .exporter import Export, export_current, export_depsgraph
from .load import BlendWarning, export_blend, load_blend, open_blend, require_bpy
from .report import BlendError

__all__ = ["BlendError", "BlendWarning", "Export", "export_blend", "export_current", "export_depsgraph",
           "load_blend", "open_blend", "require_bpy"]
