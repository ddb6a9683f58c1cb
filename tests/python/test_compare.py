"""`mvpt compare`: runs read from output directories, JSON summaries and EXR files; per-view and
overall metrics equal the metrics module's on the same images; clear errors for bad inputs."""
from __future__ import annotations

import json

import numpy as np
import pytest

import mvpt
from mvpt import cli, metrics
from mvpt.compare import compare_paths
from mvpt.output import write_outputs
from mvpt.runs import load_run

from small_scenes import scene, sensor

pytest.importorskip("flip_evaluator", reason="mvpt compare computes FLIP with flip-evaluator")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A two-view scene rendered at 2, 8 and 64 spp into three output directories."""
    d = tmp_path_factory.mktemp("compare")
    xml = scene(sensor("left", res=12, spp=2, origin="-1, 1, 4") + sensor("right", res=12, spp=2, origin="1, 1, 4"))
    sc = mvpt.load_string(xml)
    dirs = {}
    for spp in (2, 8, 64):
        r = mvpt.render(sc, spp=spp, seed=spp, threads=1)
        dirs[spp] = d / f"spp{spp}"
        write_outputs(r, dirs[spp], "two")
    return dirs


def test_cli_prints_every_view_and_writes_json(runs, tmp_path, capsys):
    out = tmp_path / "cmp.json"
    code = cli.main(["compare", str(runs[2]), str(runs[8]), "--reference", str(runs[64]), "--json", str(out)])
    assert code == 0
    table = capsys.readouterr().out
    for name in ("spp2", "spp8", "left", "right", "(overall)", "relMSE", "FLIP"):
        assert name in table
    data = json.loads(out.read_text())
    assert set(data["runs"]) == {"spp2", "spp8"}
    assert "eps=0.01" in data["definitions"]["relmse"]
    # more samples, less error (64 spp reference: 2 spp is far noisier than 8 spp)
    assert data["runs"]["spp2"]["overall"]["relmse"] > data["runs"]["spp8"]["overall"]["relmse"]
    assert data["runs"]["spp2"]["overall"]["flip"] > data["runs"]["spp8"]["overall"]["flip"]


def test_numbers_equal_the_metrics_on_the_exr_images(runs):
    ref, results = compare_paths([runs[8]], runs[64])
    test = load_run(runs[8])
    for vid in ("left", "right"):
        x = mvpt._core.read_image(str(runs[8] / f"two_{vid}.exr"))
        r = mvpt._core.read_image(str(runs[64] / f"two_{vid}.exr"))
        np.testing.assert_array_equal(test.images[vid], x)
        e = results["spp8"].views[vid]
        assert e.rmse == pytest.approx(metrics.rmse(x, r), rel=1e-12)
        assert e.relmse == pytest.approx(metrics.relmse(x, r), rel=1e-12)
        assert e.flip == pytest.approx(metrics.flip(x, r), rel=1e-9)


def test_single_exr_files_are_one_view_each(runs, capsys):
    code = cli.main(["compare", str(runs[2] / "two_left.exr"), "--reference", str(runs[64] / "two_left.exr"),
                     "--no-flip"])
    assert code == 0
    out = capsys.readouterr().out
    assert "two_left" in out and "n/a" in out  # FLIP skipped


def test_json_summary_selects_a_run(runs, capsys):
    assert cli.main(["compare", str(runs[8] / "two.json"), "-r", str(runs[64]), "--no-flip"]) == 0
    assert "two" in capsys.readouterr().out


def test_bad_inputs_are_one_line_errors(runs, tmp_path, capsys):
    assert cli.main(["compare", str(tmp_path / "nope"), "-r", str(runs[64])]) == 1
    err = capsys.readouterr().err
    assert err.startswith("mvpt: error:") and "does not exist" in err
    assert cli.main(["compare", str(runs[8] / "two_left.exr"), "-r", str(runs[64])]) == 1
    assert "has no view 'two_left'" in capsys.readouterr().err
    (tmp_path / "a.json").write_text("{}")
    (tmp_path / "b.json").write_text("{}")
    assert cli.main(["compare", str(tmp_path), "-r", str(runs[64])]) == 1
    assert "2 (a.json, b.json)" in capsys.readouterr().err
