"""Colour inputs of shader nodes: a constant RGB, or an Image Texture node as a Mitsuba
`bitmap` (its file, sRGB or raw by the image's colour space, bilinear or nearest, repeat or
clamp), looked up by the mesh's active render UV map. Images packed into the .blend are written
next to the scene (textures/)."""
from __future__ import annotations

import os
import re
from pathlib import Path

from . import sockets
from .report import Report
from .xml_writer import plugin

WRAP = {"REPEAT": "repeat", "EXTEND": "clamp", "MIRROR": "mirror"}


class Textures:
    def __init__(self, report: Report, folder: Path):
        self.report = report
        self.folder = Path(folder)
        self.files: dict = {}

    def constant_colour(self, node, name: str, where: str):
        """The input's constant colour; a node driving it is reported, and its value is used."""
        if sockets.is_linked(node, name):
            self.report.warn(f"{where}: input '{name}' of node '{node.name}' is driven by a node; "
                             f"its own colour is used")
        return sockets.rgb(node, name)

    def colour(self, element, param: str, node, name: str, where: str) -> None:
        """Add parameter `param` to `element`: the input's image texture or constant colour."""
        source = sockets.linked_node(node.inputs[name]) if name in node.inputs else None
        if source is not None and source.bl_idname == "ShaderNodeTexImage":
            texture = self._bitmap(source, where)
            if texture is not None:
                texture.attributes["name"] = param
                element.add(texture)
                return
        elif source is not None:
            self.report.warn(f"{where}: input '{name}' of node '{node.name}' is driven by node '{source.name}' "
                             f"({source.bl_idname}), which is not converted; its own colour is used")
        element.rgb(param, sockets.rgb(node, name))

    def _bitmap(self, node, where: str):
        image = node.image
        if image is None:
            self.report.warn(f"{where}: Image Texture '{node.name}' has no image; its input's colour is used")
            return None
        path = self._file(image, where)
        if path is None:
            return None
        if sockets.is_linked(node, "Vector"):
            self.report.warn(f"{where}: the texture coordinates of Image Texture '{node.name}' are not converted "
                             f"(the active UV map is used)")
        if node.projection != "FLAT":
            self.report.warn(f"{where}: Image Texture '{node.name}' projection {node.projection} is read as FLAT")
        t = plugin("texture", "bitmap").string("filename", path)
        t.string("filter_type", "nearest" if node.interpolation == "Closest" else "bilinear")
        if node.extension not in WRAP:
            self.report.warn(f"{where}: Image Texture '{node.name}' extension {node.extension} is read as REPEAT")
        t.string("wrap_mode", WRAP.get(node.extension, "repeat"))
        if image.colorspace_settings.name in ("Non-Color", "Raw", "Generic Data", "Linear Rec.709"):
            t.boolean("raw", True)
        return t

    def _file(self, image, where: str):
        """The image's file as an absolute path (packed images written under textures/)."""
        if image.name in self.files:
            return self.files[image.name]
        path = None
        if image.packed_file is not None or image.source == "GENERATED":
            path = self._write_packed(image, where)
        elif image.source == "FILE":
            import bpy
            path = os.path.abspath(bpy.path.abspath(image.filepath, library=image.library))
            if not os.path.isfile(path):
                self.report.warn(f"{where}: image '{image.name}' file {path} does not exist; its input's colour is used")
                path = None
        else:
            self.report.warn(f"{where}: image '{image.name}' ({image.source}) is not a still image; "
                             f"its input's colour is used")
        self.files[image.name] = path
        return path

    def _write_packed(self, image, where: str):
        folder = self.folder / "textures"
        folder.mkdir(parents=True, exist_ok=True)
        name = re.sub(r"[^A-Za-z0-9_.-]", "_", image.name)
        target = folder / (Path(name).stem + ".exr")
        copy = image.copy()  # saving changes the image's file settings: a copy keeps the user's
        try:
            copy.filepath_raw = str(target)
            copy.file_format = "OPEN_EXR"
            copy.save()
        except RuntimeError as e:
            self.report.warn(f"{where}: image '{image.name}' could not be written ({e}); its input's colour is used")
            return None
        finally:
            import bpy
            bpy.data.images.remove(copy)
        return str(target)
