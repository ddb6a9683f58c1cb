"""The Mitsuba backend (docs/mitsuba-backend.md) on Mitsuba 3's llvm_ad_rgb: multi-view path
tracing in Dr.Jit converges to the images of its own path tracing and of the C++ renderer's
(per-block tests over independent seeds, box and gaussian filters, a pinhole and two thin
lenses), its weights sum to one per pixel and pass in expectation, a chunked pass equals an
unchunked one bit for bit, and what it cannot render is refused with one line."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import mvpt

sys.path.insert(0, str(Path(__file__).parent))
from mitsuba_compare import block_estimate_from_seeds, compare_estimates  # noqa: E402

HERE = Path(__file__).resolve().parents[1]
SCENE = HERE / "scenes" / "mv" / "thinlens_metal.xml"
REPO = HERE.parent
VIEWS = ["pin", "lens_small", "lens_large"]  # (the fourth view moves: refused)
SEEDS = 16


@pytest.fixture(scope="module")
def backend():
    mi = pytest.importorskip("mitsuba", reason="the Mitsuba backend needs mitsuba==3.9.1 (pip install mitsuba)")
    from mvpt import mitsuba_backend
    before = mi.variant()
    try:
        mitsuba_backend.pick_variant(mi, "llvm_ad_rgb")
    except ValueError as e:
        pytest.skip(f"Mitsuba's llvm_ad_rgb does not run here (Debian's libllvm19 is needed): {e}")
    finally:  # (the variant is global: other tests' modules set theirs once, at import)
        if before is not None:
            mi.set_variant(before)
    return mitsuba_backend


def _blocks(runs):
    return {v: block_estimate_from_seeds([r.images[v] for r in runs], 8, v) for v in VIEWS}


def _render(backend, scene, spp, seed, method="mvpt", **kw):
    return backend.render(scene, spp=spp, seed=seed, views=VIEWS, method=method, variant="llvm_ad_rgb", **kw)


@pytest.mark.parametrize("rfilter", ["box", "gaussian"])
def test_mvpt_converges_to_path_tracing(backend, rfilter):
    """Unbiased: the backend's multi-view path tracing against its own path tracing (the same
    BSDFs and emitters, so no tolerance beyond the noise), and against the C++ renderer's path
    tracing (another implementation of the materials: 1 % on the image means)."""
    scene = mvpt.load_file(SCENE, filter=rfilter)
    mv = _blocks([_render(backend, scene, 12, 100 + i) for i in range(SEEDS)])
    assert _render(backend, scene, 1, 0).stats["multiview"]["mean_sharing"] > 1.5  # views do share
    pt = _blocks([_render(backend, scene, 36, 300 + i, method="pt") for i in range(SEEDS)])
    cpp = _blocks([mvpt.render(scene, spp=24, seed=500 + i, views=VIEWS, method="pt") for i in range(SEEDS)])
    for label, other, tol in (("backend pt", pt, 0.0), ("C++ pt", cpp, 0.01)):
        res = compare_estimates(f"backend mvpt ({rfilter}) vs {label}",
                                [(i, v, mv[v], other[v]) for i, v in enumerate(VIEWS)], block=1, mean_tol=tol)
        print(res.summary())
        assert res.passed, res.summary()


def test_weights_sum_to_one_per_pixel(backend):
    """E[Σ W] = 1 per pixel and pass (docs/multiview-path-tracing.md §5): the balance sums run
    over every view whose shift is valid, from each strategy's side alike. Each 8x8 block's
    mean of the per-pass sums is tested against 1 (z-test over seeds, Šidák-corrected)."""
    from scipy import stats
    scene = mvpt.load_file(SCENE)
    runs = [_render(backend, scene, 8, 700 + i) for i in range(SEEDS)]
    assert runs[0].stats["multiview"]["mean_sharing"] > 1.5
    tests = []
    for v in VIEWS:
        w = np.stack([r.weight_sum[v] for r in runs])[..., None]
        blocks = block_estimate_from_seeds(list(w), 8, v)
        z = (blocks.mean - 1.0) / np.sqrt(np.maximum(blocks.var, 1e-30))
        tests.extend(z.ravel())
    level = 1.0 - (1.0 - 0.01) ** (1.0 / len(tests))
    p = 2 * stats.t.sf(np.abs(tests), SEEDS - 1)
    assert p.min() > level, f"smallest p {p.min():.2e} below {level:.2e}"


def test_chunks_and_runs_give_the_same_bits(backend):
    """Every random number is a function of (seed, view, pixel, pass, dimension) and the sums
    are fixed-point: a pass in chunks of 333 samples equals the whole pass, bit for bit."""
    scene = mvpt.load_file(SCENE, filter="gaussian")
    a = _render(backend, scene, 3, 1)
    b = _render(backend, scene, 3, 1, chunk=333)
    for v in VIEWS:
        assert np.array_equal(a.images[v], b.images[v]), v
    c = _render(backend, scene, 3, 2)
    assert not np.array_equal(a.images["pin"], c.images["pin"])


def test_what_it_cannot_render_is_refused(backend):
    with pytest.raises(ValueError, match="view 'moving' moves"):
        backend.render(mvpt.load_file(SCENE), spp=1, variant="llvm_ad_rgb")
    with pytest.raises(ValueError, match="participating media"):
        backend.render(mvpt.load_file(REPO / "scenes" / "fog-ggx-9.xml", res=8), spp=1, variant="llvm_ad_rgb")
    with pytest.raises(ValueError, match="not read from an XML file"):
        backend.render(mvpt.load_string(SCENE.read_text()), spp=1, views=VIEWS, variant="llvm_ad_rgb")
    with pytest.raises(ValueError, match="runs on cuda_ad_rgb or llvm_ad_rgb, not 'scalar_rgb'"):
        backend.render(mvpt.load_file(SCENE), spp=1, views=VIEWS, variant="scalar_rgb")
    scene = mvpt.load_file(SCENE)
    with pytest.raises(ValueError, match="has no state"):
        mvpt.render(scene, spp=1, views=VIEWS, backend="mitsuba:llvm_ad_rgb", state="x.mvpt-state")
    with pytest.raises(ValueError, match="backend must be"):
        mvpt.render(scene, spp=1, views=VIEWS, backend="pbrt")


def test_the_callers_variant_is_kept(backend):
    """Mitsuba's variant is global state: a render leaves the caller's as it was."""
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    _render(backend, mvpt.load_file(SCENE), 1, 0)
    assert mi.variant() == "scalar_rgb"


def test_command_line(backend, tmp_path):
    """mvpt render --backend mitsuba:llvm_ad_rgb writes the same outputs as the C++ renderer."""
    from mvpt import cli
    out = tmp_path / "out"
    code = cli.main(["render", str(REPO / "scenes" / "glossy-ggx-9.xml"), "-D", "res=16", "--spp", "2", "-q",
                     "--backend", "mitsuba:llvm_ad_rgb", "-o", str(out)])
    assert code == 0
    exrs = sorted(out.glob("*.exr"))
    assert len(exrs) == 9, exrs
    import json
    stats = json.loads((out / "glossy-ggx-9.json").read_text())
    assert stats["backend"] == "mitsuba" and stats["method"] == "mvpt" and stats["passes"] == 2
    assert cli.main(["render", str(SCENE), "--backend", "mitsuba:llvm_ad_rgb", "--views", "pin", "--ray", "local",
                     "-o", str(tmp_path / "r")]) != 0
