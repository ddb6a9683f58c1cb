"""Sampling routines of multi-view path tracing (design doc §6–§7):

- the bounce's lobe mixture: χ² of `sample_lobe_mixture` against `lobe_mixture_pdf` for
  several sets of view directions and BSDFs (delta lobes excluded, as in the BSDF tests:
  the smooth part of the mixture must then integrate to the probability of a smooth sample);
  at BSDFs with delta and smooth lobes, the probability of a delta lobe that each BSDF
  reports, and the mixture's delta events, unbiased per view and drawn more often for more
  views (§7, "Delta lobes");
- the material similarity s_M of §6: 1 for diffuse lobes and for identical views, in [0, 1],
  symmetric, decreasing as the views separate and as the lobe sharpens, never NaN;
- MVPT images are bit-identical for any thread count (the design's determinism rule).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mvpt
from bsdf_cases import DELTA, direction, probe
from chi2 import chi2_test

VIEW_SETS = {
    "one": [direction(30, 10)],
    "near": [direction(30, 10), direction(34, 20), direction(26, 0)],
    "spread": [direction(5, 0), direction(45, 90), direction(75, 200), direction(60, -30)],
}
BSDFS = {
    "phong-4": '<bsdf type="phong"><float name="exponent" value="4"/></bsdf>',
    "phong-60": '<bsdf type="phong"><float name="exponent" value="60"/>'
                '<rgb name="diffuse_reflectance" value="0.1"/></bsdf>',
    "roughconductor": '<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>',
    "roughconductor-beckmann-all-normals": '<bsdf type="roughconductor"><string name="distribution" value="beckmann"/>'
                                           '<float name="alpha" value="0.3"/>'
                                           '<boolean name="sample_visible" value="false"/></bsdf>',
    "roughplastic": '<bsdf type="roughplastic"><string name="distribution" value="ggx"/>'
                    '<float name="alpha" value="0.15"/></bsdf>',
    "roughplastic-beckmann-all-normals": '<bsdf type="roughplastic"><float name="alpha" value="0.3"/>'
                                         '<boolean name="sample_visible" value="false"/></bsdf>',
    "plastic": '<bsdf type="plastic"/>',  # a delta coating over a diffuse base
    # Null, delta and diffuse lobes: the mixture draws a delta event or a smooth one (§7).
    "mask-plastic": '<bsdf type="mask"><float name="opacity" value="0.6"/><bsdf type="plastic">'
                    '<rgb name="diffuse_reflectance" value="0.8, 0.3, 0.3"/></bsdf></bsdf>',
    # Both sides: the views below the surface see the back's BRDF (mirrored).
    "twosided-roughconductor": '<bsdf type="twosided"><bsdf type="roughconductor">'
                               '<float name="alpha" value="0.2"/></bsdf></bsdf>',
    "twosided-phong-roughplastic": '<bsdf type="twosided"><bsdf type="phong"><float name="exponent" value="20"/></bsdf>'
                                   '<bsdf type="roughplastic"><float name="alpha" value="0.3"/></bsdf></bsdf>',
}
# BSDFs checked by the eval_pdf_views test alone: diffuse, and wrappers that pass the views to
# their nested BSDFs (a mask's null lobe is not part of the lobe mixture).
VIEWS_ONLY = {
    "diffuse": '<bsdf type="diffuse"/>',
    "mask-roughconductor": '<bsdf type="mask"><float name="opacity" value="0.7"/>'
                           '<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></bsdf>',
    "blend-roughconductor-roughplastic": '<bsdf type="blendbsdf"><float name="weight" value="0.3"/>'
                                         '<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>'
                                         '<bsdf type="roughplastic"><float name="alpha" value="0.3"/></bsdf></bsdf>',
    "blend-phong-diffuse": '<bsdf type="blendbsdf"><float name="weight" value="0.6"/>'
                           '<bsdf type="phong"><float name="exponent" value="20"/></bsdf><bsdf type="diffuse"/></bsdf>',
    "principled": '<bsdf type="principled"><rgb name="base_color" value="0.7, 0.4, 0.2"/><float name="roughness" value="0.4"/>'
                  '<float name="metallic" value="0.3"/><float name="clearcoat" value="0.5"/><float name="sheen" value="0.4"/>'
                  '<float name="anisotropic" value="0.3"/></bsdf>',
    "principled-spec-trans": '<bsdf type="principled"><float name="spec_trans" value="0.6"/>'
                             '<float name="roughness" value="0.3"/></bsdf>',
    "roughdielectric": '<bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf>',
    "roughdielectric-beckmann-all-normals": '<bsdf type="roughdielectric"><string name="distribution" value="beckmann"/>'
                                            '<float name="alpha" value="0.3"/>'
                                            '<boolean name="sample_visible" value="false"/></bsdf>',
    "normalmap-roughconductor": '<bsdf type="normalmap"><rgb name="normalmap" value="0.7, 0.4, 0.85"/>'
                                '<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></bsdf>',
}
# The BSDFs whose views run the lane code, or the products, of eval and pdf (bit-identical values).
SAME_LANES = {"roughconductor", "roughconductor-beckmann-all-normals", "roughplastic",
              "roughplastic-beckmann-all-normals", "twosided-roughconductor", "mask-roughconductor",
              "blend-roughconductor-roughplastic", "plastic", "normalmap-roughconductor",
              "principled", "principled-spec-trans", "roughdielectric", "roughdielectric-beckmann-all-normals"}
PARAMS = [(b, v) for b in BSDFS for v in VIEW_SETS]


@pytest.mark.parametrize("bsdf,views", PARAMS, ids=[f"{b}-{v}" for b, v in PARAMS])
def test_lobe_mixture_chi2(bsdf, views):
    pr = probe(BSDFS[bsdf])
    wis = np.ascontiguousarray(VIEW_SETS[views], dtype=np.float32)

    def sample_fn(n):
        wo, pdf, typ, view, _ = pr.mixture_sample(wis, n, 11)
        valid = (pdf.ravel() > 0) & ((typ.astype(np.uint32).ravel() & DELTA) == 0)
        return wo, valid

    def pdf_fn(wo):
        return pr.mixture_pdf(wis, np.ascontiguousarray(wo, dtype=np.float32)).ravel()

    ok, p, msg = chi2_test(sample_fn, pdf_fn, n_samples=100_000, n_tests=len(PARAMS))
    assert ok, f"{bsdf} {views}: {msg}"


# BSDFs with delta and smooth lobes: the shared bounce draws their kinds apart (§7, "Delta lobes").
MIXED = {
    "plastic": BSDFS["plastic"],
    "mask-plastic": BSDFS["mask-plastic"],
    "twosided-plastic": '<bsdf type="twosided"><bsdf type="plastic"><float name="int_ior" value="1.9"/></bsdf></bsdf>',
    "normalmap-plastic": '<bsdf type="normalmap"><rgb name="normalmap" value="0.6, 0.45, 0.9"/>'
                         '<bsdf type="plastic"/></bsdf>',
    "mask-roughconductor": VIEWS_ONLY["mask-roughconductor"],
}


@pytest.mark.parametrize("bsdf", sorted(MIXED))
@pytest.mark.parametrize("theta", [0, 40, 75])
def test_delta_probability_matches_sampling(bsdf, theta):
    """Bsdf::delta_probability is the share of delta lobes among the BSDF's own samples
    (binomial, 5 sigma; the sampler is seeded, so the test is deterministic)."""
    pr = probe(MIXED[bsdf])
    wi = direction(theta, 30)
    p = pr.delta_probability(*wi)
    assert 0.0 < p < 1.0
    n = 40_000
    _, w, _, typ = pr.sample(*wi, n, 7)
    k = int(np.count_nonzero((typ.astype(np.uint32).ravel() & DELTA) != 0))
    assert abs(k - n * p) < 5 * np.sqrt(n * p * (1 - p)) + 1, (k, n * p)


@pytest.mark.parametrize("bsdf", sorted(MIXED))
@pytest.mark.parametrize("views", ["near", "spread"])
def test_mixture_delta_events_are_unbiased(bsdf, views):
    """A delta event of the mixture serves only its view, with the weight |S| f / P: per view,
    its expected value is the view's own delta albedo, E[f/p 1{delta}] of the BSDF's own
    sampling (two Monte Carlo means, 5 sigma of their difference, per channel)."""
    pr = probe(MIXED[bsdf])
    wis = np.ascontiguousarray(VIEW_SETS[views], dtype=np.float32)
    n, m = 200_000, len(wis)
    _, pdf, typ, view, w = pr.mixture_sample(wis, n, 5)
    delta = ((typ.astype(np.uint32).ravel() & DELTA) != 0) & (pdf.ravel() > 0)
    assert delta.any()
    for c, wi in enumerate(wis):
        mine = np.where((delta & (view.ravel() == c))[:, None], w * m, 0.0)
        _, w1, _, typ1 = pr.sample(*wi, n, 6)
        own = np.where(((typ1.astype(np.uint32).ravel() & DELTA) != 0)[:, None], w1, 0.0)
        se = np.sqrt(mine.var(axis=0) / n + own.var(axis=0) / n)
        diff = np.abs(mine.mean(axis=0) - own.mean(axis=0))
        assert np.all(diff < 5 * se + 1e-6), (c, mine.mean(axis=0), own.mean(axis=0), se)


def test_mixture_draws_more_delta_events_for_more_views():
    """With n views a delta event has odds n^(3/8) times those of one view's own choice."""
    pr = probe(BSDFS["plastic"])
    wi = direction(20, 0)
    p = pr.delta_probability(*wi)
    for m in (1, 4, 25):
        wis = np.ascontiguousarray([wi] * m, dtype=np.float32)
        _, pdf, typ, _, _ = pr.mixture_sample(wis, 40_000, 9)
        q = np.mean((typ.astype(np.uint32).ravel() & DELTA) != 0)
        odds = m ** 0.375 * p / (1 - p)
        expected = odds / (1 + odds)
        assert abs(q - expected) < 5 * np.sqrt(expected * (1 - expected) / 40_000), (m, q, expected)


def test_lobe_mixture_picks_views_uniformly():
    pr = probe(BSDFS["phong-4"])
    wis = np.ascontiguousarray(VIEW_SETS["spread"], dtype=np.float32)
    _, _, _, view, _ = pr.mixture_sample(wis, 40_000, 3)
    counts = np.bincount(view.ravel().astype(int), minlength=len(wis))
    expected = 40_000 / len(wis)
    assert np.all(np.abs(counts - expected) < 5 * np.sqrt(expected)), counts


@pytest.mark.parametrize("bsdf", sorted(BSDFS))
def test_eval_pdf_matches_eval_and_pdf(bsdf):
    """The shading of a shared vertex uses Bsdf::eval_pdf (one evaluation for both)."""
    pr = probe(BSDFS[bsdf])
    rng = np.random.default_rng(4)
    wo = rng.normal(size=(500, 3))
    wo = np.ascontiguousarray(wo / np.linalg.norm(wo, axis=1, keepdims=True), dtype=np.float32)
    for wi in VIEW_SETS["spread"]:
        f, p = pr.eval_pdf(*wi, wo)
        np.testing.assert_allclose(f, pr.eval(*wi, wo), rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(p, pr.pdf(*wi, wo), rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("bsdf", sorted(BSDFS) + sorted(VIEWS_ONLY))
@pytest.mark.parametrize("views", [5, 37, 70])
def test_eval_pdf_views_matches_eval_and_pdf(bsdf, views):
    """The shared next-event estimate and the bounce evaluate every sharing view's lobe at one
    direction with Bsdf::eval_pdf_views (one vector loop over blocks of 16 views); viewers
    below the surface included (for `twosided`, runs of views on either side; 70 views: the
    wrappers' runs of 64). The microfacet BSDFs run the same lane code in both, smooth plastic
    the same products, so their values are bit-identical; the others regroup their products
    (to within rounding)."""
    pr = probe({**BSDFS, **VIEWS_ONLY}[bsdf])
    rng = np.random.default_rng(5)
    wo = rng.normal(size=(400, 3))
    wo = np.ascontiguousarray(wo / np.linalg.norm(wo, axis=1, keepdims=True), dtype=np.float32)
    extra = rng.normal(size=(views - 5, 3))
    extra[:, 2] = np.abs(extra[:, 2]) * np.where(np.arange(views - 5) % 7 == 6, -1, 1)  # some below
    extra /= np.linalg.norm(extra, axis=1, keepdims=True)
    wis = np.ascontiguousarray(VIEW_SETS["spread"] + [direction(120, 30)] + list(extra), dtype=np.float32)
    f, p = pr.eval_pdf_views(wis, wo)
    # Not vacuous: a quarter of the pairs at least lie above the surface (above both frames' for
    # the normal map, whose tilt also mirrors its normal for some of the views).
    assert np.count_nonzero(p) > 0.25 * p.size
    for c, wi in enumerate(wis):
        if bsdf in SAME_LANES:
            np.testing.assert_array_equal(f[:, 3 * c:3 * c + 3], pr.eval(*wi, wo))
            np.testing.assert_array_equal(p[:, c], np.ravel(pr.pdf(*wi, wo)))
        else:
            np.testing.assert_allclose(f[:, 3 * c:3 * c + 3], pr.eval(*wi, wo), rtol=1e-5, atol=1e-7)
            np.testing.assert_allclose(p[:, c], np.ravel(pr.pdf(*wi, wo)), rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("monte_carlo", [False, True])
def test_material_similarity_properties(monte_carlo):
    diffuse = probe('<bsdf type="diffuse"/>')
    assert diffuse.material_similarity(direction(10, 0), direction(70, 180), monte_carlo) == 1.0
    for e in (4, 30, 200):
        pr = probe(f'<bsdf type="phong"><float name="exponent" value="{e}"/></bsdf>')
        a = direction(30, 0)
        assert pr.material_similarity(a, a, monte_carlo) == pytest.approx(1.0, abs=1e-5)
        prev = 1.0
        for sep in (2, 8, 20, 45):
            b = direction(30, sep)
            s_ab, s_ba = pr.material_similarity(a, b, monte_carlo), pr.material_similarity(b, a, monte_carlo)
            assert 0.0 <= s_ab <= 1.0 and np.isfinite(s_ab)
            assert s_ab == pytest.approx(s_ba, abs=1e-6)       # symmetric (it enters D from both sides)
            assert s_ab <= prev + 1e-6                        # views further apart share less
            prev = s_ab
    # A sharper lobe shares less for the same separation.
    a, b = direction(30, 0), direction(30, 10)
    s = [probe(f'<bsdf type="phong"><float name="exponent" value="{e}"/></bsdf>').material_similarity(a, b, monte_carlo)
         for e in (4, 30, 200)]
    assert s[0] > s[1] > s[2]
    # Grazing and below-horizon views never give NaN.
    pr = probe('<bsdf type="roughconductor"><float name="alpha" value="0.01"/></bsdf>')
    for b in (direction(89.9, 0), direction(30, 0, below=True)):
        v = pr.material_similarity(direction(30, 0), b, monte_carlo)
        assert np.isfinite(v) and 0.0 <= v <= 1.0


def test_mvpt_is_bit_identical_for_any_thread_count():
    scene = mvpt.load_file(Path(__file__).resolve().parents[1] / "scenes" / "mv" / "moving.xml", res=16)
    a = mvpt.render(scene, spp=6, seed=5, threads=1, method="mvpt")
    b = mvpt.render(scene, spp=6, seed=5, threads=2, method="mvpt")
    for v in a.images:
        assert np.array_equal(a.images[v], b.images[v]), v
        assert np.array_equal(a.sample_count[v], b.sample_count[v]), v   # adaptive maps included
        assert np.array_equal(a.contributions[v], b.contributions[v]), v
    assert a.stats["multiview"] == b.stats["multiview"]
    # The statistics of design §9, per view and overall.
    total = a.stats["multiview"]
    assert total["native_samples"] == sum(a.sample_count[v].sum() for v in a.images)
    assert total["contributions"] == sum(a.contributions[v].sum() for v in a.images)
    for v, s in a.stats["views"].items():
        m = s["multiview"]
        assert m["native_samples"] == a.sample_count[v].sum() and m["native_samples_per_second"] > 0
        assert 1.0 <= m["mean_sharing"] <= len(a.images) and m["rays_per_native_sample"] >= 1.0
        # (Summed by the renderer as it develops the images.)
        assert m["contributions_per_pixel"] == pytest.approx(a.contributions[v].mean(dtype=np.float64), rel=1e-6)
        assert s["mean"] == pytest.approx(a.images[v].reshape(-1, 3).mean(axis=0, dtype=np.float64), rel=1e-6)


# Static thin lenses of two apertures in a row over a floor with a sphere and a cube.
THIN_LENS_ROW = """<scene version="3.0.0">
    <integrator type="mvpath">$options<integer name="max_depth" value="4"/></integrator>
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"/></shape>
    <shape type="sphere"><point name="center" x="-0.3" y="0.4" z="0"/><float name="radius" value="0.4"/>
        <bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></shape>
    <shape type="cube"><transform name="to_world"><scale value="0.25"/><rotate y="1" angle="30"/>
        <translate x="0.5" y="0.25" z="0.4"/></transform><bsdf type="diffuse"/></shape>
    <shape type="sphere"><point name="center" x="0" y="3" z="1.5"/><float name="radius" value="0.4"/>
        <emitter type="area"><rgb name="radiance" value="12, 11, 10"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
""" + "".join(f"""    <sensor type="thinlens"><float name="fov" value="40"/>
        <float name="aperture_radius" value="{0.02 + 0.04 * (i % 2)}"/><float name="focus_distance" value="3"/>
        <transform name="to_world"><lookat origin="{-0.45 + 0.3 * i}, 1.0, 3.0" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
    </sensor>
""" for i in range(4)) + "</scene>"


def _with_rig_cells(name: str, cells: int):
    return _with_options(name, f'<integer name="rig_cells" value="{cells}"/>')


def _with_options(name: str, option: str):
    if name == "thin_lens_row":
        return mvpt.load_string(THIN_LENS_ROW.replace("$options", option), ".")
    scenes = Path(__file__).resolve().parents[1] / "scenes" / "mv"
    xml = (scenes / f"{name}.xml").read_text()
    src = '<integrator type="$integrator">'
    assert src in xml
    return mvpt.load_string(xml.replace(src, f'<integrator type="mvpath">{option}', 1), scenes)


@pytest.mark.parametrize("name", ["cornell_phong9", "thin_lens_row"])
def test_rig_visibility_cells_change_no_pixel(name):
    """Cells proven to see the whole rig (accel/rig_visibility.h) skip only visibility rays
    that Embree finds unblocked: the images equal those traced ray by ray, bit for bit, for
    one and two threads. (Declaring every cell unblocked fails this test on both scenes.)"""
    a = mvpt.render(_with_rig_cells(name, 0), spp=4, seed=9, threads=2, method="mvpt")
    on = _with_rig_cells(name, 16)
    for threads in (1, 2):
        b = mvpt.render(on, spp=4, seed=9, threads=threads, method="mvpt")
        for v in a.images:
            assert np.array_equal(a.images[v], b.images[v]), (v, threads)


@pytest.mark.parametrize("name, splits", [("cornell_phong9", 3), ("thin_lens_row", 2)])
def test_batches_of_native_samples_change_no_pixel(name, splits):
    """The pending samples of a tile are traced and splatted in batches of `batch_entries`
    entries (mv_native_samples): after every native sample, every few, or once per tile, the
    images are the same bit for bit, for one and two threads."""
    def scene(batch):
        option = f'<integer name="splits" value="{splits}"/>'
        return _with_options(name, option + (f'<integer name="batch_entries" value="{batch}"/>' if batch else ""))
    a = mvpt.render(scene(1 << 24), spp=4, seed=5, threads=2, method="mvpt")
    assert a.stats["splits"] == splits
    for batch, threads in ((1, 1), (1, 2), (40, 2), (None, 1)):
        b = mvpt.render(scene(batch), spp=4, seed=5, threads=threads, method="mvpt")
        for v in a.images:
            assert np.array_equal(a.images[v], b.images[v]), (v, batch, threads)
