"""`mvpt bench-equal-time`: the reference is rendered once and reused, every method renders for the
same time at each curve budget, and the HTML report is written, self-contained (every image a
decodable data: URI, every other reference an existing file) and loads in headless Chromium."""
from __future__ import annotations

import base64
import hashlib
import io
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from mvpt import bench, cli

from browser import dump_dom
from small_scenes import scene, sensor

pytest.importorskip("matplotlib", reason="the report's plots need matplotlib")
pytest.importorskip("flip_evaluator", reason="the report's FLIP numbers need flip-evaluator")
from PIL import Image  # noqa: E402

# Per view: reference crop, crop outline, one crop and one FLIP map per method; and two plots.
def _image_count(methods) -> int:
    return 2 * (2 + 2 * len(methods)) + 2


# "mvpt" joins as soon as this build's mvpt.render takes method= (the multi-view integrator).
METHODS = ["pt", "mvpt"] if bench.render_supports_method() else ["pt"]


class _Refs(HTMLParser):
    """Every src/href of a page."""

    def __init__(self):
        super().__init__()
        self.imgs, self.links = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append(a.get("src", ""))
        for key in ("href", "src"):
            if key in a and tag != "img":
                self.links.append(a[key])


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """One small benchmark: 2 views of 16x16, 0.4 s per method, a 32-spp reference; run twice.

    Crops are 8x8 here, so each view also shows where its crop lies (one more image)."""
    from mvpt import report as report_module
    d = tmp_path_factory.mktemp("bench")
    xml = scene(sensor("left", res=16, spp=2, origin="-1, 1, 4") + sensor("right", res=16, spp=2, origin="1, 1, 4"))
    path = d / "two.xml"
    path.write_text(xml)
    out = d / "report"
    argv = ["bench-equal-time", str(path), "--time", "0.4", "--methods", ",".join(METHODS),
            "--reference-spp", "32", "--seed", "3", "--threads", "1", "-o", str(out), "-q"]
    crop, report_module.CROP = report_module.CROP, 8
    try:
        assert cli.main(argv) == 0
        ref_json = out / "reference" / "two.json"
        first_ref = ref_json.stat().st_mtime_ns
        assert cli.main(argv) == 0  # second run: the matching reference is reused, not re-rendered
    finally:
        report_module.CROP = crop
    return {"out": out, "scene": path, "argv": argv, "ref_mtime": (first_ref, ref_json.stat().st_mtime_ns)}


def test_reference_is_rendered_once_and_reused(report):
    first, second = report["ref_mtime"]
    assert first == second
    summary = json.loads((report["out"] / "reference" / "two.json").read_text())
    assert summary["settings"]["bench_reference"]["reference_spp"] == 32
    assert all(v["spp"] == 32 for v in summary["views"].values())


def test_an_edited_scene_renders_its_reference_again(tmp_path):
    """A saved reference is reused only for the same scene bytes: after an edit it is rendered
    again (whatever the file's time stamp says)."""
    path = tmp_path / "one.xml"
    out = tmp_path / "out"
    argv = ["bench-equal-time", str(path), "--time", "0.05", "--methods", "pt", "--reference-spp", "4",
            "--seed", "1", "--threads", "1", "-o", str(out), "-q"]
    summaries = []
    for origin in ("0, 1, 4", "0, 1, 5"):
        path.write_text(scene(sensor("v", res=8, spp=1, origin=origin)))
        assert cli.main(argv) == 0
        summaries.append(json.loads((out / "reference" / "one.json").read_text()))
    digests = [s["settings"]["bench_reference"]["scene_sha1"] for s in summaries]
    assert digests[1] == hashlib.sha1(path.read_bytes()).hexdigest() != digests[0]
    assert summaries[0]["views"]["v"]["mean"] != summaries[1]["views"]["v"]["mean"]


def test_every_method_runs_each_budget_and_is_scored(report):
    data = json.loads((report["out"] / "bench.json").read_text())
    assert sorted(data["methods"]) == sorted(METHODS)
    for m, r in data["methods"].items():
        budgets = [p["budget"] for p in r["curve"]]
        assert budgets == pytest.approx([0.05, 0.1, 0.2, 0.4])
        assert all(p["relmse"] > 0 for p in r["curve"])
        errs = r["errors"]
        assert set(errs["views"]) == {"left", "right"}
        assert 0 < errs["overall"]["flip"] < 1
        assert errs["overall"]["relmse"] == pytest.approx(r["curve"][-1]["relmse"])
        for vid in ("left", "right"):
            assert (report["out"] / m / f"two_{vid}.exr").is_file()
    assert data["command"][:2] == ["mvpt", "bench-equal-time"]


def test_report_metrics_match_a_recomputation(report):
    from mvpt import metrics
    from mvpt.runs import load_run

    data = json.loads((report["out"] / "bench.json").read_text())
    ref = load_run(report["out"] / "reference")
    run = load_run(report["out"] / "pt")
    e = metrics.errors(run.images, ref.images)
    assert data["methods"]["pt"]["errors"]["overall"]["relmse"] == pytest.approx(e.overall.relmse, rel=1e-9)
    assert data["methods"]["pt"]["errors"]["views"]["left"]["flip"] == pytest.approx(e.views["left"].flip, rel=1e-6)


def test_html_is_self_contained_and_every_image_decodes(report):
    page = report["out"] / "index.html"
    text = page.read_text()
    refs = _Refs()
    refs.feed(text)
    assert len(refs.imgs) == _image_count(METHODS)
    for src in refs.imgs:
        if src.startswith("data:"):
            assert src.startswith("data:image/png;base64,")
            img = Image.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1])))
            img.load()
            assert img.width > 0 and img.height > 0
        else:
            assert (page.parent / src).is_file(), f"the report references a missing file: {src}"
    for link in refs.links:
        assert link.startswith(("data:", "#")) or (page.parent / link).is_file(), link
    assert "mvpt bench-equal-time" in text and "--reference-spp 32" in text
    assert re.search(r"relMSE = mean \(x-r\)&sup2;/\(r&sup2;\+0.01\)", text)


def test_report_loads_in_headless_chromium(report):
    dom, console = dump_dom(report["out"] / "index.html")
    m = re.search(r'<p id="load-status"([^>]*)>(.*?)</p>', dom, re.S)
    assert m, "the page has no load-status element"
    attrs = dict(re.findall(r'data-(\w+)="([^"]*)"', m.group(1)))
    assert attrs.get("state") == "loaded", f"the page did not finish loading: {m.group(0)}"
    assert int(attrs["images"]) == _image_count(METHODS)
    assert attrs["broken"] == "0", m.group(2)
    assert attrs["errors"] == "0", m.group(2)
    assert not console, f"console output: {console}"


def test_unknown_method_is_a_clear_error(tmp_path, capsys):
    xml = tmp_path / "one.xml"
    xml.write_text(scene(sensor("cam", res=8, spp=1)))
    code = cli.main(["bench-equal-time", str(xml), "--time", "0.1", "--methods", "pt,nosuch",
                     "--reference-spp", "4", "-o", str(tmp_path / "r"), "-q"])
    assert code == 1
    err = capsys.readouterr().err
    assert "nosuch" in err and err.startswith("mvpt: error:")


def test_bench_rejects_a_bad_time():
    with pytest.raises(ValueError, match="time budget"):
        bench.run_bench(bench.BenchConfig(scene=Path("x.xml"), time=0.0))


def test_best_crop_finds_the_largest_error_window():
    from mvpt.report import best_crop

    err = np.zeros((40, 30))
    err[25:29, 3:6] = 1.0
    y, x, h, w = best_crop(err, 8)
    assert (h, w) == (8, 8)
    assert y <= 25 and y + h >= 29 and x <= 3 and x + w >= 6
    assert best_crop(err, 100) == (0, 0, 40, 30)  # views smaller than the crop are shown whole


def test_reference_noise_is_subtracted_and_judged(report):
    """The reference's own noise (from its variance) is reported and subtracted; a 32-spp
    reference against renders of 0.4 s is too noisy to judge them, and the page says so."""
    data = json.loads((report["out"] / "bench.json").read_text())
    noise = data["reference"]["noise_relmse"]
    assert noise["overall"] > 0 and set(noise) == {"left", "right", "overall"}
    for m in METHODS:
        raw = data["methods"][m]["errors"]["overall"]["relmse"]
        assert data["methods"][m]["relmse_corrected"]["overall"] == pytest.approx(raw - noise["overall"])
        assert all(p["relmse_corrected"] == pytest.approx(p["relmse"] - noise["overall"])
                   for p in data["methods"][m]["curve"])
    assert any("too noisy to judge" in w for w in data["warnings"])
    html = (report["out"] / "index.html").read_text()
    assert "class=warning" in html and "too noisy to judge" in html


def test_display_error_is_reported_beside_the_per_view_one(report):
    """The error a display shows (each view blended with its neighbours along its row) is in
    bench.json and on the page, raw and with the reference's blended noise subtracted, and
    matches a recomputation from the written runs and the reference's variance."""
    from mvpt import metrics
    from mvpt.runs import load_run

    data = json.loads((report["out"] / "bench.json").read_text())
    ref = load_run(report["out"] / "reference")
    raw_ref_noise = data["reference"]["display_noise_relmse"]
    assert raw_ref_noise > 0
    for m in METHODS:
        run = load_run(report["out"] / m)
        raw, noise = metrics.display_relmse(run.images, ref.images, ref.variance)
        shown = data["methods"][m]["display"]
        assert shown["relmse"] == pytest.approx(raw, rel=1e-9)
        assert shown["relmse_corrected"] == pytest.approx(raw - noise, rel=1e-9)
        assert noise == pytest.approx(raw_ref_noise, rel=1e-9)
        # Two views of 16x16 blended 3/4 : 1/4 are not the views themselves: the numbers differ.
        assert shown["relmse"] != pytest.approx(data["methods"][m]["errors"]["overall"]["relmse"], rel=1e-3)
    html = (report["out"] / "index.html").read_text()
    assert "as a display shows the views" in html
