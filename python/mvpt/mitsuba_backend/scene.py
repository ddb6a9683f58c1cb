"""The mvpt scene's geometry, materials and emitters as a Mitsuba 3 scene: its XML file read
by Mitsuba itself, without the views (mvpt draws them from its own cameras, rigs expanded),
without the integrator (its settings come from mvpt's) and without mvpt's own elements."""
from __future__ import annotations

import os
import re

_COMMENT = re.compile(r"<!--.*?-->", re.S)
_BLOCKS = [re.compile(p, re.S) for p in (
    r"<mvpt:(\w+)\b[^>]*?/>", r"<mvpt:(\w+)\b[^>]*?>.*?</mvpt:\1\s*>",
    r"<sensor\b[^>]*?/>", r"<sensor\b[^>]*?>.*?</sensor\s*>",
    r"<integrator\b[^>]*?/>", r"<integrator\b[^>]*?>.*?</integrator\s*>")]
_XMLNS = re.compile(r'\s+xmlns:mvpt\s*=\s*"[^"]*"')


def refusal(scene, index: list) -> str:
    """Why the backend cannot render the views `index` of `scene` (one line), or ''."""
    if scene.has_media:
        return "it has participating media"
    if scene.has_moving_shapes:
        return "some shapes move"
    for i in index:
        if scene.camera_model(i)["projection"] is None:
            return f"view '{scene.views[i]['id']}' moves or is not a perspective or thin-lens camera"
    files = [f for f in scene.source_files if f.endswith(".xml")]
    if not files:
        return "it was not read from an XML file"
    return ""


def mitsuba_xml(text: str) -> str:
    """The XML without comments, sensors, the integrator and mvpt's elements."""
    text = _COMMENT.sub("", text)
    for block in _BLOCKS:
        text = block.sub("", text)
    return _XMLNS.sub("", text)


def load_mitsuba_scene(mi, scene):
    """Mitsuba's scene of `scene`'s XML file, with its <default> overrides."""
    path = [f for f in scene.source_files if f.endswith(".xml")][0]
    with open(path, encoding="utf-8") as f:
        xml = mitsuba_xml(f.read())
    resolver = mi.file_resolver()
    resolver.prepend(os.path.dirname(os.path.abspath(path)))
    # Mitsuba refuses overrides that no element reads (those of the views, say).
    texts = [xml] + [mitsuba_xml(open(f, encoding="utf-8").read()) for f in scene.source_files
                     if f.endswith(".xml") and f != path]
    defines = {k: v for k, v in dict(scene.defines).items() if any(f"${k}" in t for t in texts)}
    try:
        return mi.load_string(xml, **defines)
    except Exception as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise ValueError(f"{path}: Mitsuba could not read the scene: {first}") from None
