"""Loader features that Mitsuba's own scene files use: <path> search directories and the
`moment` integrator wrapper (mvpt always estimates the variance, so it loads as its child)."""
from pathlib import Path

import pytest

mvpt = pytest.importorskip("mvpt")

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def scene_xml(integrator: str, path_elem: str = '<path value="meshes"/>') -> str:
    return f"""<scene version="3.0.0">
    {path_elem}
    {integrator}
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="obj"><string name="filename" value="icosphere.obj"/></shape>
</scene>"""


def test_path_element_adds_a_search_directory():
    s = mvpt.load_string(scene_xml('<integrator type="path"/>'), SCENES)
    r = mvpt.render(s, spp=1)
    assert r.images[r.view_ids[0]].shape == (8, 8, 3)


def test_without_path_the_mesh_is_not_found():
    with pytest.raises(mvpt.SceneError, match="icosphere.obj"):
        mvpt.load_string(scene_xml('<integrator type="path"/>', ""), SCENES)


def test_missing_path_directory_is_an_error():
    with pytest.raises(mvpt.SceneError, match="<path> directory 'nowhere' not found"):
        mvpt.load_string(scene_xml('<integrator type="path"/>', '<path value="nowhere"/>'), SCENES)


def test_moment_loads_its_nested_integrator():
    s = mvpt.load_string(scene_xml('<integrator type="moment"><integrator type="path">'
                                   '<integer name="max_depth" value="2"/></integrator></integrator>'), SCENES)
    assert "path" in str(s.integrator)


def test_moment_needs_exactly_one_nested_integrator():
    with pytest.raises(mvpt.SceneError, match="exactly one nested"):
        mvpt.load_string(scene_xml('<integrator type="moment"><integrator type="path"/>'
                                   '<integrator type="path"/></integrator>'), SCENES)
