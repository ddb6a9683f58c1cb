"""method="auto" (docs/multiview-path-tracing.md, "Choosing the method"): multi-view path
tracing where its pilot predicts a gain over path tracing at equal time, else path tracing;
the render is then that method's, bit for bit, and says which it chose and why. The choice
is a function of the scene, views, seed and splits: a resumed render chooses the same."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import mvpt
from mvpt import api, cli

SCENES = Path(__file__).resolve().parents[1] / "scenes" / "mv"


def _same_images(a, b):
    for v in a.images:
        assert np.array_equal(a.images[v], b.images[v]), v
        assert np.array_equal(a.sample_count[v], b.sample_count[v]), v


def test_auto_shares_where_the_pilot_predicts_a_gain():
    s = mvpt.load_file(SCENES / "cornell_phong9.xml", res=16)
    auto = mvpt.render(s, spp=4, seed=3, method="auto")
    choice = auto.stats["auto"]
    assert choice["method"] == "mvpt" and auto.stats["method"] == "mvpt", choice
    assert choice["predicted_gain"] > 1.0 and "predicts" in choice["reason"]
    assert auto.stats["predicted_gain"] == pytest.approx(choice["predicted_gain"])
    _same_images(auto, mvpt.render(s, spp=4, seed=3, method="mvpt"))


def test_auto_path_traces_a_shot_whose_frames_barely_share():
    # Frames of a moving shape whose shutters overlap by half (0.6 partners per sample): the
    # pilot predicts 0.3-0.45 over every seed tried.
    s = mvpt.load_file(SCENES / "moving.xml", res=32)
    gains = [api.choose_method(s, [], seed=k, threads=0)["predicted_gain"] for k in (1, 2, 3)]
    assert all(0.0 < g < 0.7 for g in gains), gains
    auto = mvpt.render(s, spp=4, seed=3, method="auto")
    choice = auto.stats["auto"]
    assert choice["method"] == "pt" and auto.stats["method"] == "pt" and "does not pay" in choice["reason"], choice
    _same_images(auto, mvpt.render(s, spp=4, seed=3, method="pt"))


def test_auto_path_traces_one_view_and_frames_that_share_nothing():
    one = mvpt.load_file(SCENES / "cornell_phong9.xml", res=16)
    r = mvpt.render(one, spp=2, seed=1, method="auto", views=[0])
    assert r.stats["method"] == "pt" and "one view" in r.stats["auto"]["reason"]
    assert r.stats["auto"]["predicted_gain"] is None
    # Two frames whose shutters do not overlap (0-0.5 and 0.75-1.25) while a shape moves: the
    # renderer's own rule, and its reason.
    shot = mvpt.load_file(SCENES / "moving.xml", res=16)
    r = mvpt.render(shot, spp=2, seed=1, method="auto", views=["f0", "f3"])
    assert r.stats["method"] == "pt" and r.stats["auto"]["predicted_gain"] is None
    assert "shutters" in r.stats["auto"]["reason"], r.stats["auto"]


def test_auto_chooses_the_same_on_resume(tmp_path):
    s = mvpt.load_file(SCENES / "cornell_phong9.xml", res=16)
    whole = mvpt.render(s, spp=6, seed=5, method="auto")
    state = tmp_path / "auto.mvpt-state"

    def stop(p):
        if p["pass"] >= 2:
            raise KeyboardInterrupt

    cut = mvpt.render(s, spp=6, seed=5, method="auto", state=state, progress=stop, poll=0.001)
    assert cut.stats["cancelled"] and cut.stats["passes"] < 6
    done = mvpt.render(s, spp=6, seed=5, method="auto", state=state, resume=state)
    assert done.stats["auto"]["method"] == whole.stats["auto"]["method"] == "mvpt"
    _same_images(whole, done)


def test_command_line_says_what_auto_chose(tmp_path, capsys):
    out = tmp_path / "out"
    assert cli.main(["render", str(SCENES / "cornell_phong9.xml"), "-D", "res=16", "--spp", "2",
                     "--method", "auto", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "method auto: mvpt (the pilot predicts" in printed, printed
    stats = json.loads((out / "cornell_phong9.json").read_text())
    assert stats["auto"]["method"] == stats["method"] == "mvpt" and stats["auto"]["predicted_gain"] > 1.0
    assert stats["settings"]["method"] == "auto"


def test_command_line_defaults_to_auto_for_several_views_of_a_path_traced_scene(tmp_path):
    # cornell_phong9.xml names the `path` integrator ($integrator's default); with `mvpath` the
    # scene's own method stays; one view is the scene's.
    runs = {"several": [], "mvpath": ["-D", "integrator=mvpath"], "one": ["--views", "0"]}
    method = {}
    for name, extra in runs.items():
        out = tmp_path / name
        assert cli.main(["render", str(SCENES / "cornell_phong9.xml"), "-D", "res=16", "--spp", "1", *extra,
                         "-o", str(out), "-q"]) == 0
        stats = json.loads((out / "cornell_phong9.json").read_text())
        method[name] = (stats["settings"]["method"], stats["method"])
    assert method == {"several": ("auto", "mvpt"), "mvpath": ("scene", "mvpt"), "one": ("scene", "pt")}, method


def test_auto_is_refused_where_methods_are_checked():
    s = mvpt.load_file(SCENES / "cornell_phong9.xml", res=16)
    with pytest.raises(ValueError, match="'auto'"):
        mvpt.render(s, spp=1, method="autoo")


PROBE = r"""
import gc, resource, sys
import mvpt
from mvpt import _core
sys.path.insert(0, sys.argv[1])
from small_scenes import scene, views
s = mvpt.load_string(scene(views(40, res=320, spp=1)))
def vm_size():
    for line in open("/proc/self/status"):
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
def least(method):  # the fewest MiB of address space above now in which the method's films fit
    base = vm_size()
    for extra in range(32, 8192, 32):
        resource.setrlimit(resource.RLIMIT_AS, (base + extra * 2**20, resource.RLIM_INFINITY))
        try:
            job = _core.RenderJob(s, spp=1, method=method, threads=1)  # (the films are checked here)
        except RuntimeError as e:
            assert "need about" in str(e), e
            continue
        del job
        gc.collect()
        resource.setrlimit(resource.RLIMIT_AS, (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
        return extra
pt, mv = least("pt"), least("mvpt")
assert pt + 128 < mv, (pt, mv)
resource.setrlimit(resource.RLIMIT_AS, (vm_size() + (pt + mv) // 2 * 2**20, resource.RLIM_INFINITY))
r = mvpt.render(s, spp=1, method="auto", threads=1)
print(r.stats["method"], "|", r.stats["auto"]["reason"])
"""


def test_auto_path_traces_where_multi_view_films_do_not_fit(tmp_path):
    # Under an address-space limit that path tracing's films fit and multi-view path tracing's
    # do not, auto path traces and says why (the pilot's own films are refused first).
    import subprocess
    import sys
    run = subprocess.run([sys.executable, "-c", PROBE, str(Path(__file__).parent)], capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr
    method, reason = run.stdout.strip().split(" | ")
    assert method == "pt" and "multi-view path tracing cannot run here" in reason and "need about" in reason, run.stdout
