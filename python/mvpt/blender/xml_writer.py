"""Mitsuba 3 XML elements for the exported scene: plugins with typed parameters, written as
an indented file that mvpt (and Mitsuba 3) reads."""
from __future__ import annotations

from xml.sax.saxutils import quoteattr


def number(x: float) -> str:
    """A float written exactly enough to read back the same float32 (9 significant digits)."""
    return f"{float(x):.9g}"


class Element:
    """One XML element: a tag, its attributes in order, and child elements."""

    def __init__(self, tag: str, **attributes):
        self.tag = tag
        self.attributes = {k.rstrip("_"): str(v) for k, v in attributes.items()}
        self.children: list[Element] = []
        self.comment = ""

    def add(self, child: "Element") -> "Element":
        self.children.append(child)
        return child

    # Typed parameters (Mitsuba 3's <float>, <rgb>, ...), each returning self to chain them.
    def float(self, name: str, value: float) -> "Element":
        self.add(Element("float", name=name, value=number(value)))
        return self

    def integer(self, name: str, value: int) -> "Element":
        self.add(Element("integer", name=name, value=int(value)))
        return self

    def string(self, name: str, value: str) -> "Element":
        self.add(Element("string", name=name, value=value))
        return self

    def boolean(self, name: str, value: bool) -> "Element":
        self.add(Element("boolean", name=name, value="true" if value else "false"))
        return self

    def rgb(self, name: str, value) -> "Element":
        self.add(Element("rgb", name=name, value=", ".join(number(c) for c in value)))
        return self

    def matrix(self, name: str, m) -> "Element":
        """A to_world transform from a 4x4 matrix (rows of four numbers)."""
        self.add(Element("transform", name=name)).add(matrix_element(m))
        return self

    def text(self, indent: int = 0) -> str:
        pad = "    " * indent
        attrs = "".join(f" {k}={quoteattr(v)}" for k, v in self.attributes.items())
        head = f"{pad}<!-- {self.comment.replace('--', '- -')} -->\n" if self.comment else ""
        if not self.children:
            return f"{head}{pad}<{self.tag}{attrs}/>\n"
        body = "".join(c.text(indent + 1) for c in self.children)
        return f"{head}{pad}<{self.tag}{attrs}>\n{body}{pad}</{self.tag}>\n"


def animation(name: str, keys) -> Element:
    """An animated transform (Mitsuba 3's <animation>): keyframes [(time, 4x4 rows)]."""
    a = Element("animation", name=name)
    for t, m in keys:
        a.add(Element("transform", time=number(t))).add(matrix_element(m))
    return a


def matrix_element(m) -> Element:
    """<matrix> of a 4x4 matrix given as rows."""
    return Element("matrix", value=" ".join(number(m[i][j]) for i in range(4) for j in range(4)))


def plugin(kind: str, type_: str, id_: str = "") -> Element:
    """A plugin element such as <bsdf type="diffuse" id="...">."""
    return Element(kind, type=type_, id=id_) if id_ else Element(kind, type=type_)


def scene_text(scene: Element, header_comment: str) -> str:
    return f"<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<!-- {header_comment.replace('--', '- -')} -->\n" + scene.text()
