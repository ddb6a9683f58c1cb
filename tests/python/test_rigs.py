"""Camera rigs and animated shots from Python and the CLI (README, "Camera rigs and shots"):
the `rig=` option and `--rig`, the shared focal plane of the 5x5 light-field grid, per-frame
shutters, clear errors, and every example scene in scenes/ loading and rendering."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mvpt
from mvpt import cli

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
EXAMPLES = sorted(SCENES.glob("*.xml"))

BASE = """<scene version="3.0.0">
    <sensor type="perspective" id="base">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 1, 5" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="2"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="sphere"><float name="radius" value="0.5"/><point name="center" x="0" y="0.5" z="0"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>"""


def ids(scene) -> list:
    return [v["id"] for v in scene.views]


def test_rig_option_ids_and_counts():
    assert ids(mvpt.load_string(BASE, rig="stereo:ipd=0.064")) == ["left", "right"]
    assert ids(mvpt.load_string(BASE, rig="grid:3x2,spacing=0.05")) == [f"r{r}c{c}" for r in range(2) for c in range(3)]
    assert ids(mvpt.load_string(BASE, rig="linear:n=45,baseline=0.5")) == [f"view{i:03d}" for i in range(45)]
    assert len(mvpt.load_string(BASE, rig="orbit:n=60,radius=5").views) == 60
    assert ids(mvpt.load_string(BASE)) == ["base"]


def test_path_rig_frames_have_the_requested_shutters(tmp_path):
    keys = tmp_path / "keys.json"
    keys.write_text(json.dumps({"keys": [
        {"time": 0, "position": [0, 1, 5], "target": [0, 0.5, 0]},
        {"time": 4, "position": [3, 1, 4], "target": [0, 0.5, 0]}]}))
    fps, shutter = 24.0, 1.5
    scene = mvpt.load_string(BASE, rig=f"path:{keys},frames=100,fps={fps},shutter={shutter}")
    views = scene.views
    assert ids(scene) == [f"frame{i:04d}" for i in range(100)]
    for i, v in enumerate(views):
        o, c = v["shutter"]
        assert o == pytest.approx(i / fps, abs=1e-6)
        assert c == pytest.approx(i / fps + shutter / fps, abs=1e-6)
    # shutter > 1 frame time: each frame's shutter closes after the next one opens.
    assert all(views[i]["shutter"][1] > views[i + 1]["shutter"][0] for i in range(99))
    # The camera moves within a frame: rays at the shutter's two ends leave from different points.
    o0, _ = scene.camera_generate_ray(50, [8, 6], time=views[50]["shutter"][0])
    o1, _ = scene.camera_generate_ray(50, [8, 6], time=views[50]["shutter"][1])
    assert np.linalg.norm(np.subtract(o1, o0)) > 1e-3


def test_lightfield_grid_shares_its_focal_plane():
    """A point on the focal plane projects to the same pixel in all 25 views; off it, not."""
    scene = mvpt.load_file(SCENES / "lightfield-5x5.xml", res=32)
    views = ids(scene)
    assert len(views) == 25 and views[12] == "lf_r2c2"
    centre = 12  # the base camera itself: no offset, no shear
    o, axis = scene.camera_generate_ray(centre, [16, 16])
    axis = np.asarray(axis)
    focus = 4.3
    rng = np.random.default_rng(1)
    for _ in range(20):
        x = rng.uniform(4, 28, size=2)
        o, d = scene.camera_generate_ray(centre, list(x))
        d = np.asarray(d)
        on = np.asarray(o) + d * (focus / d.dot(axis))
        near = np.asarray(o) + d * (0.6 * focus / d.dot(axis))
        px_on = np.array([scene.camera_project(v, list(on)) for v in range(25)])
        px_near = np.array([scene.camera_project(v, list(near)) for v in range(25)])
        assert np.abs(px_on - x).max() < 2e-3
        assert np.ptp(px_near[:, 0]) > 0.5 and np.ptp(px_near[:, 1]) > 0.5


@pytest.mark.parametrize("spec, message", [
    ("grid:5x5,spacing=nan", "--rig grid:5x5,spacing=nan: grid rig 'spacing': expected a finite number, got 'nan'"),
    ("grid:0x5,spacing=0.1", "at least one view"),
    ("linear:n=0,baseline=1", "at least one view"),
    ("path:keys.json,frames=0", "at least one view"),
    ("helix:n=3", "unknown rig type 'helix'"),
    ("orbit:n=3", "--rig orbit:n=3: the orbit rig needs 'radius'"),
])
def test_rig_errors(spec, message):
    with pytest.raises(mvpt.SceneError) as e:
        mvpt.load_string(BASE, rig=spec)
    assert message in str(e.value)


def test_unparsable_key_file_names_its_line(tmp_path):
    keys = tmp_path / "keys.json"
    keys.write_text('{"keys": [\n  {"time": 0, "position": [0, 1, 5], "target": [0, 0, 0]},\n  {"time": 1 "position": []}\n]}\n')
    with pytest.raises(mvpt.SceneError) as e:
        mvpt.load_string(BASE, rig=f"path:{keys},frames=3")
    assert e.value.file == str(keys) and e.value.line == 3
    assert "expected '}' or ','" in e.value.message


def test_cli_rig(tmp_path, capsys):
    scene = tmp_path / "scene.xml"
    scene.write_text(BASE)
    out = tmp_path / "out"
    assert cli.main(["render", str(scene), "--rig", "grid:2x2,spacing=0.1,focus_distance=5", "--spp", "1",
                     "-q", "-o", str(out)]) == 0
    assert sorted(p.name for p in out.glob("*.exr")) == [f"scene_r{r}c{c}.exr" for r in range(2) for c in range(2)]
    assert json.loads((out / "scene.json").read_text())["settings"]["rig"] == "grid:2x2,spacing=0.1,focus_distance=5"
    capsys.readouterr()
    assert cli.main(["render", str(scene), "--rig", "grid:2x2,spacing=nan", "-q", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mvpt: error: --rig grid:2x2,spacing=nan: grid rig 'spacing'")
    # Finite in double but not once the views are made in single precision: an error at the option.
    for spec, name in (("grid:2x2,spacing=1e39", "spacing"), ("orbit:n=3,radius=2e30", "radius"),
                       ("linear:n=3,baseline=-1e31", "baseline")):
        assert cli.main(["render", str(scene), "--rig", spec, "-q", "-o", str(out)]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0] == f"mvpt: error: --rig {spec}: {spec.split(':')[0]} rig '{name}' must lie " \
                                           f"within +-1e30, got {spec.split('=')[-1]}", err


EXPECTED_VIEWS = {"cornell-glossy-9": 9, "lightfield-5x5": 25, "stereo": 2, "shot-100": 100, "glossy-ggx-9": 9,
                  "fog-ggx-9": 9, "fog-lightfield-5x5": 25}


def test_example_scene_list():
    assert sorted(p.stem for p in EXAMPLES) == sorted(EXPECTED_VIEWS)


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_scene_renders(path):
    """Each example scene loads and renders a few samples per pixel to finite, non-black images."""
    scene = mvpt.load_file(path, res=16, spp=2)
    assert len(scene.views) == EXPECTED_VIEWS[path.stem]
    result = mvpt.render(scene, spp=2, seed=1)
    assert result.stats["nonfinite_samples"] == 0
    for vid, img in result.images.items():
        assert img.shape == (16, 16, 3)
        assert np.isfinite(img).all(), vid
        assert img.mean() > 0.01, vid
    if path.stem == "shot-100":
        shutters = [v["shutter"] for v in scene.views]
        assert shutters[1][0] == pytest.approx(1 / 24) and shutters[0][1] == pytest.approx(1.5 / 24)
        assert all(shutters[i][1] > shutters[i + 1][0] for i in range(99))


def test_rig_of_a_sensor_with_named_film_and_sampler():
    """A base camera that declares its film and sampler with ids (as Mitsuba's own scenes do):
    the first view keeps the ids (references to them still work), the others do not declare
    them again. Both the --rig option and the rig element."""
    named = BASE.replace('<sampler type="independent">', '<sampler type="independent" id="sampler">').replace(
        '<film type="hdrfilm">', '<film type="hdrfilm" id="film">')
    scene = mvpt.load_string(named, rig="grid:3x3,spacing=0.05")
    assert len(scene.views) == 9 and all((v["width"], v["height"], v["spp"]) == (16, 12, 2) for v in scene.views)
    # A rig element, and one more sensor after it that refers to the base camera's film and sampler.
    sensor = named[named.index("<sensor"):named.index("</sensor>") + len("</sensor>")]
    extra = ('<sensor type="perspective" id="extra"><ref id="sampler"/><ref id="film"/>'
             '<transform name="to_world"><lookat origin="1, 1, 5" target="0, 0.5, 0" up="0, 1, 0"/></transform>'
             '</sensor>')
    xml = named.replace(sensor, f'<mvpt:rig type="linear" n="3" baseline="0.2">{sensor}</mvpt:rig>{extra}')
    scene = mvpt.load_string(xml.replace('<scene version="3.0.0">', '<scene version="3.0.0" xmlns:mvpt="urn:mvpt">'))
    assert ids(scene) == ["view000", "view001", "view002", "extra"]
    assert (scene.views[3]["width"], scene.views[3]["spp"]) == (16, 2)
