"""Bad scene files: each gives ONE clear mvpt.SceneError naming file:line:col and what was
expected, and the CLI prints a single `mvpt: error: file:line:col: ...` line and exits non-zero.

Every case names the text its error must point at (`at`, the first occurrence in the file
`in_file`); the expected line and column are computed from where that text is, so a message
that points at the wrong line fails."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

import mvpt
from mvpt import cli

from small_scenes import scene, sensor

CLI = [sys.executable, "-m", "mvpt.cli"]
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))


@dataclass
class Case:
    xml: str
    at: str                      # text whose position the error must name
    message: str                 # regex the message (after file:line:col: ) must match
    files: dict = field(default_factory=dict)   # extra files: name -> text or bytes
    in_file: str = "scene.xml"   # file that contains `at`
    defines: dict = field(default_factory=dict)


def _with_shape(inner: str) -> str:
    return scene(body=f'    <shape type="cube">\n        {inner}\n    </shape>\n')


GOOD_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
MESH_ATTRIBUTE_BSDF = ('<bsdf type="diffuse"><texture name="reflectance" type="mesh_attribute">'
                       '<string name="name" value="vertex_color"/></texture></bsdf>')
COLOR_PLY = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
             "property list uchar int vertex_indices\nend_header\n"
             "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n")

CASES = {
    # --- XML syntax -------------------------------------------------------------------
    "unclosed_tag": Case(scene(body='    <shape type="cube">\n        <ref id="white"/>\n'),
                         '<shape type="cube">\n        <ref', r"<shape> .*not closed|never closed"),
    "unclosed_at_eof": Case(scene().replace("</scene>\n", ""), '<scene version', r"<scene> .*not closed|never closed"),
    "unclosed_inner": Case(scene(body='    <shape type="cube">\n        <bsdf type="diffuse">\n    </shape>\n'),
                           '<bsdf type="diffuse">\n    </shape>', r"<bsdf> is not closed \(expected </bsdf> before the </shape> at .*:\d+:5\)"),
    "extra_close_tag": Case(scene(body='    <shape type="cube"/>\n    </shape>\n'), '</shape>\n</scene>',
                            r"</shape> closes no open element \(expected </scene>\)"),
    "bad_attribute_syntax": Case(scene(sensor(fov="40").replace('value="40"', "value=40")),
                                 "40/>", r"malformed XML: bad attribute syntax \(expected name=\"value\"\)"),
    "bad_start_tag": Case(scene(body='    <shape type="cube"/ >\n'), ' >\n', r"malformed XML: bad start tag"),
    "missing_version": Case(scene(header="<scene>"), "<scene>", r"version"),
    "root_not_scene": Case('<scena version="3.0.0">\n</scena>\n', "<scena", r"root element must be <scene>"),
    "empty_file": Case("", "", r"no root element|empty"),
    # --- structure ----------------------------------------------------------------------
    "mvpath_splits_word": Case(scene().replace('<integrator type="path">',
                                               '<integrator type="mvpath"><string name="splits" value="many"/>'),
                               '<string name="splits"', r"'splits' must be 'auto' or an integer in \[1, 64\], got 'many'"),
    "unknown_plugin_type": Case(scene(body='    <shape type="spheroid"/>\n'), '<shape type="spheroid"',
                                r"unknown shape type 'spheroid'.*known:.*rectangle"),
    "unknown_element": Case(_with_shape('<colour name="x" value="1"/>'), "<colour", r"unknown element <colour>"),
    "unknown_attribute_object": Case(scene(body='    <shape type="cube" colour="red"/>\n'), 'colour="red"',
                                     r"unknown attribute 'colour'.*expected: type, id, name"),
    "unknown_attribute_value": Case(_with_shape('<boolean name="flip_normals" value="true" units="deg"/>'),
                                    'units="deg"', r"<boolean> has an unknown attribute 'units'"),
    "unused_parameter": Case(_with_shape('<bsdf type="diffuse">\n            <float name="radiuss" value="1"/>\n        </bsdf>'),
                             '<float name="radiuss"', r"bsdf 'diffuse' does not use a parameter named 'radiuss'"),
    # Misspelt names get the closest known name as a hint.
    "typo_parameter": Case(_with_shape('<bsdf type="diffuse"><rgb name="reflectanse" value="0.5"/></bsdf>'),
                           '<rgb name="reflectanse"', r"named 'reflectanse' \(<rgb>\) \(did you mean 'reflectance'\?\)"),
    "typo_element": Case(_with_shape('<flaot name="x" value="1"/>'), "<flaot", r"unknown element <flaot> \(did you mean <float>\?\)"),
    "typo_plugin_type": Case(scene(body='    <shape type="rectangel"/>\n'), '<shape type="rectangel"',
                             r"unknown shape type 'rectangel' \(did you mean 'rectangle'\?\)"),
    "typo_transform_op": Case(_with_shape('<transform name="to_world"><rotat y="1" angle="3"/></transform>'), "<rotat ",
                              r"unknown transform operation <rotat> \(did you mean <rotate>\?\)"),
    "normalmap_without_texture": Case(_with_shape('<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>'),
                                      '<bsdf type="normalmap">', r"normalmap needs a 'normalmap' texture"),
    "normalmap_two_bsdfs": Case(_with_shape('<bsdf type="normalmap"><bsdf type="diffuse"/>'
                                            '<bsdf type="conductor"/></bsdf>'),
                                '<bsdf type="conductor"/>', r"normalmap accepts one nested bsdf"),
    "bumpmap_without_texture": Case(_with_shape('<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>'),
                                    '<bsdf type="bumpmap">', r"bumpmap needs a nested texture \(the height field\)"),
    "mesh_attribute_on_a_cube": Case(_with_shape(MESH_ATTRIBUTE_BSDF), '<shape type="cube">\n        <bsdf',
                                     r"material reads the mesh attribute 'vertex_color', which the shape does not "
                                     r"have \(it has no attributes: they come from PLY files\)"),
    "mesh_attribute_missing_from_ply": Case(
        scene(body='    <shape type="ply">\n        <string name="filename" value="m.ply"/>\n        '
                   + MESH_ATTRIBUTE_BSDF.replace("vertex_color", "face_color") + '\n    </shape>\n'),
        '<shape type="ply">', r"mesh attribute 'face_color', which the shape does not have \(it has: vertex_color\)",
        files={"m.ply": COLOR_PLY}),
    "mesh_attribute_name": Case(_with_shape(MESH_ATTRIBUTE_BSDF.replace("vertex_color", "color")),
                                '<string name="name" value="color"',
                                r"mesh_attribute 'name' must start with 'vertex_' or 'face_', got 'color'"),
    "mesh_attribute_as_radiance": Case(
        _with_shape('<emitter type="area"><texture name="radiance" type="mesh_attribute">'
                    '<string name="name" value="vertex_color"/></texture></emitter>'),
        '<texture name="radiance"', r"parameter 'radiance' of the emitter 'area' is looked up by uv: a mesh_attribute "
                                    r"texture can only be a BSDF's parameter"),
    "normalmap_without_bsdf": Case(_with_shape('<bsdf type="normalmap"><texture name="normalmap" type="rawconstant">'
                                               '<vector name="value" value="0.5, 0.5, 1"/></texture></bsdf>'),
                                   '<bsdf type="normalmap">', r"normalmap needs a nested bsdf"),
    "rawconstant_without_value": Case(_with_shape('<bsdf type="diffuse"><texture name="reflectance" type="rawconstant"/>'
                                                  '</bsdf>'),
                                      '<texture name="reflectance" type="rawconstant"/>',
                                      r"rawconstant needs a <float> or <vector> 'value'"),
    "lanczos_lobes": Case(scene(sensor(film_extra='<rfilter type="lanczos"><integer name="lobes" value="0"/></rfilter>')),
                          '<integer name="lobes" value="0"', r"'lobes' must be an integer in \[1, 64\], got 0"),
    # Mitsuba's documentation names the Mitchell-Netravali parameters A and B; its code reads B and C.
    "mitchell_a": Case(scene(sensor(film_extra='<rfilter type="mitchell"><float name="A" value="0.3"/></rfilter>')),
                       '<float name="A"', r"rfilter 'mitchell' does not use a parameter named 'A'"),
    "unused_child": Case(_with_shape('<film type="hdrfilm"/>'), '<film type="hdrfilm"/>',
                         r"shape 'cube' does not accept a nested film"),
    "duplicate_parameter": Case(scene(sensor(film_extra='\n            <integer name="width" value="8"/>')),
                                '<integer name="width" value="8"', r"parameter 'width' is given twice \(first at .*:\d+:\d+\)"),
    "duplicate_id": Case(scene(body='    <bsdf type="diffuse" id="white"/>\n'), '<bsdf type="diffuse" id="white"/>',
                         r"duplicate id 'white' \(first declared at .*scene.xml:\d+:\d+\)"),
    "ref_unknown_id": Case(_with_shape('<ref id="nothere"/>'), '<ref id="nothere"', r"<ref> to unknown id 'nothere'"),
    "ref_self": Case(scene(body='    <bsdf type="diffuse" id="loop"><ref id="loop"/></bsdf>\n'
                               '    <shape type="cube"><ref id="loop"/></shape>\n'),
                     '<ref id="loop"/></bsdf>', r"refers to an object that contains it \(declared at .*scene\.xml:\d+:5\)"),
    "ref_before_untyped_object": Case(scene(body='    <shape type="cube"><ref id="later"/></shape>\n    <bsdf id="later"/>\n'),
                                      '<bsdf id="later"/>', r"<bsdf> is missing its 'type' attribute"),
    "deep_nesting": Case(scene(body="    " + "<shape>" * 256 + '<shape id="deep">' + "<shape>" * 43 + "</shape>" * 300 + "\n"),
                         '<shape id="deep">', r"nested more than 256 levels"),
    "include_missing": Case(scene(body='    <include filename="missing.xml"/>\n'), '<include filename="missing.xml"',
                            r"included file 'missing.xml' not found"),
    "include_cycle": Case(scene(body='    <include filename="a.xml"/>\n'), '<include filename="scene.xml"',
                          r"include cycle: scene\.xml -> a\.xml -> scene\.xml",
                          files={"a.xml": '<scene version="3.0.0">\n    <include filename="scene.xml"/>\n</scene>\n'},
                          in_file="a.xml"),
    "include_self": Case(scene(body='    <include filename="scene.xml"/>\n'), '<include filename="scene.xml"',
                         r"include cycle: scene\.xml -> scene\.xml"),
    "error_inside_include": Case(scene(body='    <include filename="a.xml"/>\n'), '<float name="radiuss"',
                                 r"does not use a parameter named 'radiuss'",
                                 files={"a.xml": '<scene version="3.0.0">\n    <bsdf type="diffuse" id="x">\n'
                                                 '        <float name="radiuss" value="1"/>\n    </bsdf>\n</scene>\n'},
                                 in_file="a.xml"),
    "undefined_variable": Case(scene(sensor(res="$resolution")), 'value="$resolution"',
                               r"undefined variable '\$resolution'.*<default name=\"resolution\""),
    "area_emitter_outside_shape": Case(scene(body='    <emitter type="area"/>\n'), '<emitter type="area"/>',
                                       r"'area' emitter must be placed inside a <shape>"),
    "no_sensor": Case(scene(sensors=""), '<scene version', r"no <sensor>"),
    # --- files ---------------------------------------------------------------------------
    "missing_mesh": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="nothere.obj"/>\n    </shape>\n'),
                         '<string name="filename"', r"file 'nothere.obj' not found"),
    "empty_obj": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="empty.obj"/>\n    </shape>\n'),
                      '<string name="filename"', r"empty\.obj.*contains no faces", files={"empty.obj": ""}),
    "corrupt_obj_index": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="bad.obj"/>\n    </shape>\n'),
                              '<string name="filename"', r"bad\.obj", files={"bad.obj": "v 0 0 0\nv 1 0 0\nf 1 2 9\n"}),
    # Normal and texture-coordinate indices out of range (the fuzzers' crashes), far and near,
    # absolute and relative (negative, counted back from the last one read).
    **{f"obj_bad_{what}_{i}": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="bad.obj"/>\n'
                                               '    </shape>\n'), '<string name="filename"',
                                   rf"bad\.obj': face 1 uses {what.replace('_', ' ')} index .* but the file has",
                                   files={"bad.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n" + face})
       for what, faces in (("normal", ("f 1//1 2//1 3//100000000", "f 1//1 2//1 3//5", "f 1//1 2//1 3//-9")),
                           ("texture_coordinate", ("f 1/1 2/1 3/7", "f 1/1 2/1 3/-5", "f 1/99999999 2/1 3/1")))
       for i, face in enumerate(faces)},
    "corrupt_obj_binary": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="bin.obj"/>\n    </shape>\n'),
                               '<string name="filename"', r"bin\.obj", files={"bin.obj": bytes(range(256)) * 8}),
    # tinyobjloader reads what is no number as 0 silently: the OBJ reader checks the numbers
    # itself and names their line and column in the OBJ file.
    **{f"obj_vertex_{name}": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="v.obj"/>\n'
                                             '    </shape>\n'), at, message, in_file="v.obj",
                                  files={"v.obj": "v 0 0 0\n" + line + "\nv 0 1 0\nf 1 2 3\n"})
       for name, line, at, message in (
           ("inf", "v 1e999 0 0", "1e999", r"'1e999' is not a finite number in float range \(in a vertex position"),
           ("beyond_float", "v 1 1e39 0", "1e39", r"'1e39' is not a finite number in float range"),
           ("nan", "v nan 0 0", "nan", r"'nan' is not a finite number"),
           ("word", "v 1 zero 0", "zero", r"'zero' is not a number \(in a vertex position"),
           ("too_few", "v 1 0", "v 1 0", r"'v' needs 3 numbers, got 2"))},
    "obj_normal_word": Case(scene(body='    <shape type="obj">\n        <string name="filename" value="n.obj"/>\n    </shape>\n'),
                            "up", r"'up' is not a number \(in a vertex normal", in_file="n.obj",
                            files={"n.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 up\nf 1//1 2//1 3//1\n"}),
    "corrupt_texture": Case(_with_shape('<bsdf type="diffuse">\n            <texture type="bitmap" name="reflectance">\n'
                                        '                <string name="filename" value="bad.png"/>\n'
                                        '            </texture>\n        </bsdf>'),
                            '<string name="filename"', r"cannot read image 'bad.png'", files={"bad.png": b"\x89PNG garbage"}),
    "missing_texture": Case(_with_shape('<bsdf type="diffuse">\n            <texture type="bitmap" name="reflectance">\n'
                                        '                <string name="filename" value="nothere.png"/>\n'
                                        '            </texture>\n        </bsdf>'),
                            '<string name="filename"', r"file 'nothere.png' not found"),
    # --- values --------------------------------------------------------------------------
    "negative_resolution": Case(scene(sensor(res="-16")), '<integer name="width"', r"width.*between 1 and|resolution"),
    "zero_resolution": Case(scene(sensor(film_extra="").replace('name="height" value="16"', 'name="height" value="0"')),
                            '<integer name="height"', r"height|resolution"),
    "fov_zero": Case(scene(sensor(fov="0")), '<float name="fov"', r"'fov' must lie in \(0, 180\)"),
    "fov_180": Case(scene(sensor(fov="180")), '<float name="fov"', r"'fov' must lie in \(0, 180\)"),
    "fov_negative": Case(scene(sensor(fov="-5")), '<float name="fov"', r"'fov' must lie in \(0, 180\)"),
    "nan_value": Case(scene(sensor(fov="nan")), 'value="nan"', r"float 'fov': expected a finite number, got 'nan'"),
    "inf_value": Case(scene(sensor(fov="inf")), 'value="inf"', r"float 'fov': expected a finite number, got 'inf'"),
    "nan_in_rgb": Case(_with_shape('<bsdf type="diffuse"><rgb name="reflectance" value="0.5, nan, 0.5"/></bsdf>'),
                       'value="0.5, nan', r"rgb 'reflectance': expected a finite number"),
    "non_numeric": Case(scene(sensor(fov="forty")), 'value="forty"', r"float 'fov': expected a number, got 'forty'"),
    "non_integer": Case(scene(sensor(spp="4.5")), 'value="4.5"', r"integer 'sample_count': expected an integer"),
    # Integers beyond their type are errors, never truncations (2^32 + 1 once rendered as depth 1).
    **{f"int_range_{name}_{value}": Case(scene(max_depth=value) if name == "max_depth" else
                                         scene(sensor(spp=value)) if name == "sample_count" else
                                         scene(sensor(seed=value)),
                                         f'<integer name="{name}"', rf"'{name}' must be an integer in \[-?\d+, \d+\], got {value}")
       for name, values in (("max_depth", (4294967297, -2, 2**31)), ("sample_count", (2**31, 0, -4)),
                            ("seed", (2**40, 2**32, -1)))
       for value in values},
    "matrix_beyond_float": Case(_with_shape('<transform name="to_world">\n            '
                                            '<matrix value="1e39 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1"/>\n        </transform>'),
                                '<matrix value="1e39', r"transform is not finite in single precision"),
    "crop_offset_near_2_63": Case(scene(sensor(film_extra='\n            <integer name="crop_offset_x" value="9223372036854775800"/>'
                                                          '\n            <integer name="crop_width" value="100"/>')),
                                  '<integer name="crop_width"', r"crop window .* does not fit in the 16x16 film"),
    "cdata_section": Case(_with_shape('<![CDATA[ <bsdf type="diffuse"/> ]]>'), "<![CDATA[",
                          r"a CDATA section inside <shape>"),
    "defaults_that_double": Case(scene().replace('<scene version="3.0.0">', '<scene version="3.0.0">\n    <default name="a0" value="xxxxxxxx"/>' +
                                                 "".join(f'\n    <default name="a{i + 1}" value="$a{i}$a{i}"/>' for i in range(24)), 1),
                                 'value="$a17$a17"', r"substituting \$a17 makes a value longer than 1 MiB"),
    "bad_boolean": Case(_with_shape('<boolean name="flip_normals" value="maybe"/>'), 'value="maybe"',
                        r"expected true or false"),
    "rgb_wrong_count": Case(_with_shape('<bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5"/></bsdf>'),
                            'value="0.5, 0.5"', r"expected 1 or 3 numbers"),
    "bad_crop_window": Case(scene(sensor(film_extra='\n            <integer name="crop_offset_x" value="10"/>'
                                                    '\n            <integer name="crop_width" value="10"/>')),
                            '<integer name="crop_width"', r"crop window .* does not fit in the 16x16 film"),
    "near_clip_ge_far_clip": Case(scene(sensor(extra='\n        <float name="near_clip" value="10"/>'
                                                     '\n        <float name="far_clip" value="1"/>')),
                                  '<float name="near_clip"', r"near_clip < far_clip"),
    "singular_matrix": Case(_with_shape('<transform name="to_world">\n            <matrix value="1 0 0 0  0 0 0 0  0 0 1 0  0 0 0 1"/>\n        </transform>'),
                            "<matrix", r"<matrix> is singular"),
    "zero_scale": Case(_with_shape('<transform name="to_world"><scale y="0"/></transform>'), '<scale y="0"', r"singular"),
    "shear_sensor": Case(scene(sensor().replace(
        '<lookat origin="0, 1, 4" target="0, 0.5, 0" up="0, 1, 0"/>',
        '<matrix value="1 0.5 0 0  0 1 0 4  0 0 1 4  0 0 0 1"/>')), '<transform name="to_world"><matrix',
        r"to_world.*(shear|scale)"),
    "wrong_value_type": Case(scene(sensor().replace('<float name="fov" value="40"/>', '<string name="fov" value="40"/>')),
                             '<string name="fov"', r"'fov' must be a float, got <string>"),
    "wrong_child_type": Case(_with_shape('<bsdf type="diffuse"><transform name="reflectance"/></bsdf>'),
                             '<transform name="reflectance"', r"'reflectance' must be an rgb colour, a spectrum or a float, got <transform>"),
    # --- <spectrum> ------------------------------------------------------------------------
    "spectrum_not_increasing": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" '
                                                'value="400:0.5, 500:0.6, 500:0.7"/></bsdf>'), 'value="400:0.5',
                                    r"spectrum 'reflectance': wavelengths must increase strictly \(pair 3\)"),
    "spectrum_bad_number": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" '
                                            'value="400:0.5, 500:0.6x"/></bsdf>'), 'value="400:0.5',
                                r"spectrum 'reflectance' value in '500:0.6x': expected a number, got '0.6x'"),
    "spectrum_nan": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" '
                                     'value="400:nan, 500:0.6"/></bsdf>'), 'value="400:nan',
                         r"spectrum 'reflectance' value in '400:nan': expected a finite number, got 'nan'"),
    "spectrum_not_a_pair": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" '
                                            'value="400:0.5, 500"/></bsdf>'), 'value="400:0.5',
                                r"spectrum 'reflectance': expected wavelength:value pairs .*got '500'"),
    "spectrum_one_pair": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" value="500:0.5"/></bsdf>'),
                              'value="500:0.5', r"spectrum 'reflectance': needs at least two wavelength:value pairs"),
    "spectrum_value_and_file": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" value="0.5" '
                                                'filename="r.spd"/></bsdf>'), '<spectrum',
                                    r"needs either a 'value' or a 'filename' attribute \(not both\)"),
    "spectrum_file_missing": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" '
                                              'filename="nothere.spd"/></bsdf>'), 'filename="nothere.spd"',
                                  r"file 'nothere.spd' not found"),
    "spectrum_blackbody": Case(scene(body='    <emitter type="point">\n        <spectrum name="intensity" type="blackbody">'
                                          '<float name="temperature" value="3000"/></spectrum>\n    </emitter>\n'),
                               'type="blackbody"', r"<spectrum type=\"blackbody\"> .*spectral variants; mvpt renders in RGB"),
    "spectrum_file_bad_line": Case(_with_shape('<bsdf type="diffuse"><spectrum name="reflectance" '
                                               'filename="r.spd"/></bsdf>'), '500 0.5 0.7',
                                   r"spectrum 'reflectance': expected 'wavelength value' on each line, got 3 numbers",
                                   files={"r.spd": "# comment\n400 0.5\n500 0.5 0.7\n"}, in_file="r.spd"),
}


def _write_case(case: Case, tmp_path: Path) -> Path:
    path = tmp_path / "scene.xml"
    path.write_text(case.xml)
    for name, text in case.files.items():
        p = tmp_path / name
        p.write_bytes(text) if isinstance(text, bytes) else p.write_text(text)
    return path


def _expected_loc(case: Case, tmp_path: Path) -> tuple[str, int, int]:
    text = case.xml if case.in_file == "scene.xml" else case.files[case.in_file]
    offset = text.find(case.at)
    assert offset >= 0, f"test bug: {case.at!r} not in {case.in_file}"
    line = text.count("\n", 0, offset) + 1
    col = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return str(tmp_path / case.in_file), line, col


def _check_message(msg: str, case: Case, tmp_path: Path) -> None:
    assert "\n" not in msg.strip(), f"error spans several lines: {msg!r}"
    file, line, col = _expected_loc(case, tmp_path)
    prefix = f"{file}:{line}:{col}: "
    assert msg.startswith(prefix), f"expected the error at {prefix!r}, got {msg!r}"
    assert re.search(case.message, msg[len(prefix):]), f"message {msg!r} does not match {case.message!r}"


@pytest.mark.parametrize("name", list(CASES))
def test_load_error(name, tmp_path):
    case = CASES[name]
    path = _write_case(case, tmp_path)
    with pytest.raises(mvpt.SceneError) as info:
        mvpt.load_file(path, **case.defines)
    msg = str(info.value)
    if "texture" in name and "unknown texture type 'bitmap'" in msg:
        pytest.skip("the bitmap texture plugin does not exist yet")
    _check_message(msg, case, tmp_path)
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("name", list(CASES))
def test_cli_load_error(name, tmp_path, capsys):
    case = CASES[name]
    path = _write_case(case, tmp_path)
    out = tmp_path / "out"
    rc = cli.main(["render", str(path), "-o", str(out)])
    captured = capsys.readouterr()
    if "texture" in name and "unknown texture type 'bitmap'" in captured.err:
        pytest.skip("the bitmap texture plugin does not exist yet")
    assert rc == 1
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("mvpt: error: ")
    _check_message(lines[0][len("mvpt: error: "):], case, tmp_path)
    assert captured.out == ""
    assert not out.exists() or not any(out.iterdir()), "nothing may be written for a bad scene"


@pytest.mark.parametrize("name", ["unclosed_tag", "unknown_plugin_type", "include_cycle", "corrupt_obj_binary"])
def test_cli_subprocess_no_traceback(name, tmp_path):
    """The real entry point: one line on stderr, exit code 1, no traceback, no crash."""
    case = CASES[name]
    path = _write_case(case, tmp_path)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    proc = subprocess.run([sys.executable, "-m", "mvpt.cli", "render", str(path), "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=60, env=env)
    assert proc.returncode == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("mvpt: error: "), proc.stderr
    _check_message(lines[0][len("mvpt: error: "):], case, tmp_path)


def test_scene_error_attributes(tmp_path):
    """SceneError carries the location as attributes, for tools that want to jump to it."""
    case = CASES["unused_parameter"]
    path = _write_case(case, tmp_path)
    with pytest.raises(mvpt.SceneError) as info:
        mvpt.load_file(path)
    file, line, col = _expected_loc(case, tmp_path)
    assert (info.value.file, info.value.line, info.value.column) == (file, line, col)
    assert "radiuss" in info.value.message and not info.value.message.startswith(file)


def test_load_string_error_names_string():
    with pytest.raises(mvpt.SceneError, match=r"^<string>:1:\d+: .*version"):
        mvpt.load_string("<scene/>")


def test_define_overrides_default_and_bad_define(tmp_path):
    xml = scene(sensor(res="$res")).replace('<scene version="3.0.0">',
                                            '<scene version="3.0.0">\n    <default name="res" value="16"/>')
    path = tmp_path / "scene.xml"
    path.write_text(xml)
    assert mvpt.load_file(path).views[0]["width"] == 16
    assert mvpt.load_file(path, res=8).views[0]["width"] == 8
    with pytest.raises(mvpt.SceneError, match=r"integer 'width': expected an integer, got 'abc'"):
        mvpt.load_file(path, res="abc")


def test_unused_define(tmp_path):
    """As Mitsuba: a define the scene never uses as $name is an error (usually a typo)."""
    path = tmp_path / "scene.xml"
    path.write_text(scene(sensor(res="$res")))
    assert mvpt.load_file(path, res=8).views[0]["width"] == 8
    with pytest.raises(mvpt.SceneError, match=r"the define rez=8 is not used: the scene has no \$rez"):
        mvpt.load_file(path, res=8, rez=8)


def test_missing_scene_file(tmp_path):
    with pytest.raises(mvpt.SceneError, match="not found"):
        mvpt.load_file(tmp_path / "nothere.xml")


@pytest.mark.parametrize("where", ["element", "attribute", "value", "filename", "comment"])
def test_bytes_that_are_not_utf8(tmp_path, capsys, where):
    """A scene byte that is not UTF-8 is one error at its line and column, shown escaped (it once
    made a traceback where a name or value reached Python)."""
    text = scene(body='    <shape type="obj" id="mesh">\n        <string name="filename" value="m.obj"/>\n    </shape>\n'
                      '    <!-- note -->\n').encode()
    (tmp_path / "m.obj").write_text(GOOD_OBJ)
    old = {"element": b"<shape type", "attribute": b'name="filename"', "value": b'id="mesh"',
           "filename": b'value="m.obj"', "comment": b"<!-- note"}[where]
    new = old[:3] + b"\xe9" + old[3:]  # a Latin-1 byte
    path = tmp_path / "scene.xml"
    path.write_bytes(text.replace(old, new, 1))
    offset = text.index(old) + 3
    line = text[:offset].count(b"\n") + 1
    col = offset - (text.rfind(b"\n", 0, offset) + 1) + 1
    with pytest.raises(mvpt.SceneError) as e:
        mvpt.load_file(path)
    assert str(e.value) == f"{path}:{line}:{col}: a byte that is not UTF-8 text: \\xE9 (scene files are UTF-8)"
    assert cli.main(["render", str(path), "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("mvpt: error: ") and "\\xE9" in err[0]


@pytest.mark.parametrize("args", [["-D", b"res=\xff"], [b"--views", b"\xff"], ["-o", b"out\xff"],
                                  ["--rig", b"grid:2x2,spacing=\xff"], [b"-D\xff=1"]])
def test_arguments_that_are_not_utf8(tmp_path, args):
    path = tmp_path / "scene.xml"
    path.write_text(scene())
    argv = [a if isinstance(a, bytes) else a.encode() for a in CLI + ["render", str(path), "-q"] + args]
    proc = subprocess.run(argv, capture_output=True, cwd=tmp_path, env=ENV)
    err = proc.stderr.decode("utf-8", "backslashreplace").strip().splitlines()
    assert proc.returncode in (1, 2) and len(err) == 1 and err[0].startswith("mvpt: error: "), err
    assert "\\xff" in err[0].lower(), err


def _rgbe(rgb):
    """RGBE bytes of a float RGB (values > 0), as Radiance stores them."""
    import math
    m = max(rgb)
    e = math.frexp(m)[1]
    return bytes([int(v / 2.0 ** e * 256) for v in rgb] + [e + 128])


def _radiance(width: int, height: int, rle: bool) -> tuple:
    """A Radiance HDR file (new run-length scanlines, or flat) and the image stb decodes from it."""
    import numpy as np
    rng = np.random.default_rng(3)
    px = [[_rgbe([float(v) for v in rng.uniform(0.1, 4.0, 3)]) for _ in range(width)] for _ in range(height)]
    for row in px:  # a run of equal pixels in each row
        row[2:7] = [row[2]] * 5
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width))
    for row in px:
        if not rle:
            out += b"".join(row)
            continue
        out += bytes([2, 2, width >> 8, width & 255])
        for c in range(4):
            comp, x = [p[c] for p in row], 0
            while x < width:
                run = 1
                while x + run < width and run < 127 and comp[x + run] == comp[x]:
                    run += 1
                if run >= 3:
                    out += bytes([128 + run, comp[x]])
                    x += run
                else:
                    lit = min(width - x, 128, 2)
                    out += bytes([lit]) + bytes(comp[x:x + lit])
                    x += lit
    expected = np.array([[[p[c] * 2.0 ** (p[3] - 136) for c in range(3)] for p in row] for row in px], dtype=np.float32)
    return bytes(out), expected


@pytest.mark.parametrize("rle", [True, False])
def test_truncated_radiance_hdr_is_an_error(tmp_path, rle):
    """stb_image read a truncated Radiance file as if its missing scanlines were there."""
    import numpy as np
    data, expected = _radiance(24, 10, rle)
    whole = tmp_path / "whole.hdr"
    whole.write_bytes(data)
    np.testing.assert_allclose(mvpt._core.read_image(str(whole)), expected, rtol=1e-6)
    for cut in (len(data) - 1, len(data) - 50, len(data) // 2, 60):
        part = tmp_path / f"cut{cut}.hdr"
        part.write_bytes(data[:cut])
        with pytest.raises(RuntimeError, match="truncated or corrupt Radiance HDR"):
            mvpt._core.read_image(str(part))
    # In a scene: one error naming the texture.
    (tmp_path / "tex.hdr").write_bytes(data[: len(data) // 2])
    xml = _with_shape('<bsdf type="diffuse">\n            <texture type="bitmap" name="reflectance">\n'
                      '                <string name="filename" value="tex.hdr"/>\n            </texture>\n        </bsdf>')
    (tmp_path / "scene.xml").write_text(xml)
    with pytest.raises(mvpt.SceneError, match=r"tex\.hdr.*truncated or corrupt Radiance HDR"):
        mvpt.load_file(tmp_path / "scene.xml")


def test_scenes_that_cannot_produce_light_warn(tmp_path, capsys):
    dark = tmp_path / "dark.xml"
    dark.write_text('<scene version="3.0.0">\n<integrator type="path"/>\n' + sensor() + '<shape type="cube"/>\n</scene>\n')
    assert cli.main(["render", str(dark), "-q", "-o", str(tmp_path / "a")]) == 0
    assert "mvpt: warning: the scene has no emitter: every image is black" in capsys.readouterr().err
    away = tmp_path / "away.xml"  # lit, but the camera looks into the void
    away.write_text(scene(sensor(origin="0, 0, 40").replace('target="0, 0.5, 0"', 'target="0, 0, 80"')))
    r = mvpt.render(mvpt.load_file(away), spp=2)
    assert r.stats["warnings"] == ["every view is black: no light reaches the cameras (do they look at the scene?)"]
    assert mvpt.render(mvpt.load_string(scene()), spp=2).stats["warnings"] == []
