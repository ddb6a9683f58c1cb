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


# -- Mitsuba 0.6 scenes, upgraded on load --------------------------------------------------

def legacy_pair():
    """The same scene in the Mitsuba 0.6 format and, written by hand, in the Mitsuba 3 format
    (what the upgrade must produce, including the mappings of 0.6-only features)."""
    old = """<scene version="0.6.0">
    <default name="sampleCount" value="4"/>
    <integrator type="sppm"><integer name="maxDepth" value="5"/><integer name="photonCount" value="1000"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="toWorld"><lookAt origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sampleCount" value="$sampleCount"/></sampler>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="10"/>
            <float name="gamma" value="2.2"/><boolean name="banner" value="false"/><rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.8, 0.9, 1"/></emitter>
    <shape type="obj"><string name="filename" value="meshes/icosphere.obj"/><boolean name="faceNormals" value="true"/>
        <bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.5, 0.4, 0.3"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="1.2" y="0" z="0"/><float name="radius" value="0.4"/>
        <bsdf type="roughdiffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/><float name="alpha" value="1"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="-1.2" y="0" z="0"/><float name="radius" value="0.4"/>
        <bsdf type="roughconductor"><float name="alpha" value="0.2"/><float name="extEta" value="1"/>
            <rgb name="specularReflectance" value="0.9, 0.9, 0.9"/></bsdf></shape>
    <shape type="rectangle"><transform name="toWorld"><translate z="-1"/><scale value="3"/></transform>
        <bsdf type="dielectric"><float name="intIOR" value="1.33"/><float name="extIOR" value="1"/></bsdf></shape>
</scene>"""
    new = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="5"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="10"/><rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.8, 0.9, 1"/></emitter>
    <shape type="obj"><string name="filename" value="meshes/icosphere.obj"/><boolean name="face_normals" value="true"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.4, 0.3"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="1.2" y="0" z="0"/><float name="radius" value="0.4"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.3"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="-1.2" y="0" z="0"/><float name="radius" value="0.4"/>
        <bsdf type="roughconductor"><float name="alpha" value="0.2"/>
            <rgb name="specular_reflectance" value="0.9, 0.9, 0.9"/></bsdf></shape>
    <shape type="rectangle"><transform name="to_world"><translate z="-1"/><scale value="3"/></transform>
        <bsdf type="dielectric"><float name="int_ior" value="1.33"/><float name="ext_ior" value="1"/></bsdf></shape>
</scene>"""
    return old, new


def test_mitsuba_06_scene_renders_as_its_upgrade():
    old, new = legacy_pair()
    a, b = mvpt.load_string(old, SCENES), mvpt.load_string(new, SCENES)
    ra, rb = mvpt.render(a, seed=3), mvpt.render(b, seed=3)
    assert ra.stats["views"][ra.view_ids[0]]["spp"] == 4  # sampleCount through the <default>
    for va, vb in zip(ra.view_ids, rb.view_ids):
        assert (ra.images[va] == rb.images[vb]).all()
    assert b.notes == []


def test_mitsuba_06_upgrade_says_what_it_changed():
    old, _ = legacy_pair()
    notes = mvpt.load_string(old, SCENES).notes
    assert "Mitsuba 0.6.0 format" in notes[0]
    text = "\n".join(notes)
    for said in ["'sppm' integrator is rendered with 'path'", "roughdiffuse (Oren-Nayar) is rendered as diffuse",
                 "display settings (gamma, banner) are ignored"]:
        assert said in text
    assert all("(first at <string>:" in n for n in notes[1:])
    r = mvpt.render(mvpt.load_string(old, SCENES), spp=1)
    assert r.stats["notes"][:len(notes)] == notes


def test_mitsuba_06_snake_case_follows_mitsuba():
    """Mitsuba 3's conversion: an underscore before a capital that follows a lower-case
    letter, the run of capitals lowered ('intIOR' -> 'int_ior'); a parameter mvpt does not
    know is then reported under its new name."""
    old, _ = legacy_pair()
    bad = old.replace('<float name="fov" value="40"/>', '<float name="fooBARBaz" value="40"/>')
    with pytest.raises(mvpt.SceneError, match="foo_barbaz"):
        mvpt.load_string(bad, SCENES)


def test_mitsuba_06_conductor_ext_eta_other_than_one_is_an_error():
    old, _ = legacy_pair()
    with pytest.raises(mvpt.SceneError, match="ext_eta"):
        mvpt.load_string(old.replace('name="extEta" value="1"', 'name="extEta" value="1.33"'), SCENES)


def test_first_default_wins_over_an_included_files(tmp_path):
    """As in Mitsuba, a <default> does not replace a value the name already has: the
    including file's default (declared first) wins over the included file's."""
    (tmp_path / "body.xml").write_text(
        '<scene version="3.0.0"><default name="integrator" value="path"/><default name="depth" value="7"/>'
        '<integrator type="$integrator"><integer name="max_depth" value="$depth"/></integrator></scene>')
    main = ('<scene version="3.0.0"><default name="integrator" value="volpath"/><include filename="body.xml"/>'
            + scene_xml("", "").split('<scene version="3.0.0">')[1].replace(
                '<shape type="obj"><string name="filename" value="icosphere.obj"/></shape>', ""))
    assert mvpt.load_string(main, tmp_path).integrator == "volpath"
    assert mvpt.load_string(main, tmp_path, integrator="path").integrator == "path"


@pytest.mark.parametrize("params,match", [
    ('<integer name="shading_samples" value="2"/><integer name="bsdf_samples" value="1"/>', "not both"),
    ('<integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="0"/>', "at least one"),
    ('<integer name="emitter_samples" value="-1"/>', "emitter_samples")])
def test_direct_integrator_parameters(params, match):
    with pytest.raises(mvpt.SceneError, match=match):
        mvpt.load_string(scene_xml(f'<integrator type="direct">{params}</integrator>'), SCENES)
    assert mvpt.load_string(scene_xml('<integrator type="direct"><integer name="shading_samples" value="2"/>'
                                      '</integrator>'), SCENES).integrator == "direct"
