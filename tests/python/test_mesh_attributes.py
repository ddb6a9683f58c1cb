"""mesh_attribute textures where mvpt defines what Mitsuba 3.9.1 does not (its comparisons are
in test_vs_mitsuba_features.py and test_vs_mitsuba_shared.py): 8-bit colours read as
value / 255, and a 3-channel attribute used as a scalar read as the mean of its channels.
Each pair of scenes differs only in how the same numbers reach the material, so both
methods render them to identical images."""
import numpy as np
import pytest

import mvpt

from small_scenes import scene, views

# A quad (two triangles) whose four vertices carry the same colour and scalar.
HEAD = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n{props}"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n")
CORNERS = ["-1 0.01 -1", "1 0.01 -1", "1 0.01 1", "-1 0.01 1"]


def _ply(path, props, values):
    text = HEAD.format(props="".join(f"property {t} {n}\n" for t, n in props))
    text += "".join(f"{c} {values}\n" for c in CORNERS) + "4 0 1 2 3\n"
    path.write_text(text)
    return path.name


def _render(tmp_path, ply, bsdf, method):
    body = f'    <shape type="ply"><string name="filename" value="{ply}"/>{bsdf}</shape>\n'
    s = mvpt.load_string(scene(views(3, res=12, spp=4), body=body), str(tmp_path))
    return mvpt.render(s, method=method, seed=3, threads=1).images


def _attribute(name):
    return f'<texture type="mesh_attribute" name="{{}}"><string name="name" value="{name}"/></texture>'


@pytest.mark.parametrize("method", ["pt", "mvpt"])
def test_8_bit_colours_are_divided_by_255(tmp_path, method):
    a = _ply(tmp_path / "a.ply", [("uchar", c) for c in ("red", "green", "blue")], "255 51 0")
    b = _ply(tmp_path / "b.ply", [("float", c) for c in ("r", "g", "b")], "1 0.2 0")
    bsdf = '<bsdf type="diffuse">' + _attribute("vertex_color").format("reflectance") + "</bsdf>"
    ia, ib = _render(tmp_path, a, bsdf, method), _render(tmp_path, b, bsdf, method)
    assert any(ia[v].max() > 0 for v in ia)
    for v in ia:
        np.testing.assert_allclose(ia[v], ib[v], rtol=1e-6, atol=0)


@pytest.mark.parametrize("method", ["pt", "mvpt"])
def test_a_colour_as_a_scalar_is_its_channels_mean(tmp_path, method):
    # Channels 0.25, 0.5, 0.75: mean 0.5 (first channel 0.25, luminance 0.46).
    ply = _ply(tmp_path / "m.ply", [("float", f"c_{i}") for i in range(3)] + [("float", "half_0")],
               "0.25 0.5 0.75 0.5")
    blend = ('<bsdf type="blendbsdf">{}<bsdf type="diffuse"><rgb name="reflectance" value="0.1"/></bsdf>'
             '<bsdf type="diffuse"><rgb name="reflectance" value="0.9"/></bsdf></bsdf>')
    colour = _render(tmp_path, ply, blend.format(_attribute("vertex_c").format("weight")), method)
    scalar = _render(tmp_path, ply, blend.format(_attribute("vertex_half").format("weight")), method)
    for v in colour:
        np.testing.assert_allclose(colour[v], scalar[v], rtol=1e-6, atol=0)
