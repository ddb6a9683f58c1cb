"""Participating media in path tracing (the `volpath` integrator): chi-square tests of the phase
functions, furnace tests (media of albedo 1 under a uniform environment), one scene per medium
feature against Mitsuba 3's `volpath` (scalar_rgb, block t-tests of mitsuba_compare.py, two
sensors each), determinism, and the errors of bad media input."""
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
from chi2 import chi2_test  # noqa: E402
from media_scenes import LIGHTS, SENSORS, blob_grid, fog_scene, heterogeneous, homogeneous, medium_xml, write_vol  # noqa: E402

mvpt = pytest.importorskip("mvpt")
from mvpt import _probes  # noqa: E402

# ---------------------------------------------------------------- phase functions

PHASES = [("isotropic", '<phase type="isotropic"/>'), ("hg-default", '<phase type="hg"/>'),
          ("hg-0.3", '<phase type="hg"><float name="g" value="0.3"/></phase>'),
          ("hg-backward", '<phase type="hg"><float name="g" value="-0.6"/></phase>'),
          ("hg-0.9", '<phase type="hg"><float name="g" value="0.9"/></phase>')]
# The forward peak (at -wi) on the equator of the histogram, where its cells are narrowest, and oblique.
WIS = [(-1.0, 0.0, 0.0), (0.48, -0.6, 0.64)]


@pytest.mark.parametrize("name,xml", PHASES, ids=[p[0] for p in PHASES])
@pytest.mark.parametrize("wi", WIS, ids=["equator", "oblique"])
def test_phase_sampling_chi2(name, xml, wi):
    probe = _probes.PhaseProbe(xml)

    def sample_fn(n):
        wo = probe.sample(*wi, n, 5)
        return wo, np.ones(n, dtype=bool)

    ok, p, msg = chi2_test(sample_fn, lambda wo: probe.eval(*wi, wo).ravel(), n_samples=400_000,
                           n_tests=len(PHASES) * len(WIS))
    assert ok, f"{name}, wi={wi}: {msg}"


def test_henyey_greenstein_values():
    """p integrates to 1 over the sphere (any wi), is reciprocal, and peaks forward (wo = -wi) for g > 0."""
    probe = _probes.PhaseProbe('<phase type="hg"><float name="g" value="0.7"/></phase>')
    rng = np.random.default_rng(3)
    d = rng.normal(size=(400_000, 3))
    d = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    wi = np.array([0.0, 0.6, 0.8], dtype=np.float32)
    mc = probe.eval(*wi, d).ravel().mean() * 4 * np.pi
    assert abs(mc - 1) < 0.02
    a, b = d[:100], d[100:200]
    pab = np.array([probe.eval(*x, y[None]).item() for x, y in zip(a, b)])
    pba = np.array([probe.eval(*y, x[None]).item() for x, y in zip(a, b)])
    np.testing.assert_allclose(pab, pba, rtol=1e-5)
    g = 0.7
    assert probe.eval(*wi, -wi[None]).item() == pytest.approx((1 + g) / (4 * np.pi * (1 - g) ** 2), rel=1e-5)


# ---------------------------------------------------------------- forced scattering

def test_forced_scattering_distances_and_weights():
    """Medium::sample_within (the in-scattering of multi-view path tracing, design §10): the
    distances follow the channel mixture of exponentials truncated to [0, t_end)
    (Kolmogorov-Smirnov), a channel without extinction never scatters (its third of the draws
    scatters nowhere), and each channel's mean weight is the albedo times its probability of
    scattering before t_end (z-test; exactly zero without extinction)."""
    sigma, albedo, t_end, n = np.array([2.0, 0.5, 0.0]), 0.7, 1.3, 200_000
    probe = _probes.MediumProbe('<medium type="homogeneous"><rgb name="sigma_t" value="2, 0.5, 0"/>'
                              f'<float name="albedo" value="{albedo}"/></medium>')
    r = probe.sample_within(t_end, n, 4).astype(np.float64)
    scattered = np.isfinite(r[:, 0])
    assert abs(scattered.mean() - 2 / 3) < 4 * np.sqrt(2 / 9 / n)
    t = r[scattered, 0]
    assert t.min() >= 0 and t.max() < t_end
    mass = 1 - np.exp(-sigma[:2] * t_end)
    p = stats.kstest(t, lambda x: np.mean([(1 - np.exp(-s * x)) / m for s, m in zip(sigma[:2], mass)], axis=0)).pvalue
    assert p > 1e-3, p
    expected = albedo * (1 - np.exp(-sigma * t_end))
    mean, se = r[:, 1:].mean(0), r[:, 1:].std(0) / np.sqrt(n)
    assert np.all(np.abs(mean - expected) <= 4 * se), (mean, expected, se)
    assert np.all(r[:, 3] == 0)


# ---------------------------------------------------------------- free flights along camera segments

FLIGHT_SIGMA = {"a": np.array([2.0, 0.5, 1.0]), "b": np.array([0.3, 1.5, 0.0])}
FLIGHT_SCENE = f"""<scene version="3.0.0"><integrator type="volpath"/>
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
  <shape type="cube"><transform name="to_world"><scale value="3, 3, 0.5"/><translate z="-1.5"/></transform>
    <bsdf type="null"/><medium type="homogeneous" name="interior"><rgb name="sigma_t" value="2, 0.5, 1"/></medium></shape>
  <shape type="cube"><transform name="to_world"><scale value="3, 3, 0.75"/><translate z="0.75"/></transform>
    <bsdf type="null"/><medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.3, 1.5, 0"/></medium></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="5"/><translate z="3"/></transform></shape>
</scene>"""


def _flight_depth(t):
    """Optical depth per channel from z = -5 to distance t along +z: pieces a (t in [3, 4]) and
    b (t in [5, 6.5]) of the scene above, vacuum between them, the wall at t = 8."""
    t = np.asarray(t, dtype=np.float64)[..., None]
    return (FLIGHT_SIGMA["a"] * np.clip(t - 3.0, 0.0, 1.0) + FLIGHT_SIGMA["b"] * np.clip(t - 5.0, 0.0, 1.5))


def test_flight_along_segment_chi2():
    """flight_along_segment (the medium vertices of multi-view path tracing, design §10) through
    two media with null boundaries and vacuum between them: the distances follow the channel
    mixture 1/3 sum_c sigma_c T_c over the whole segment (chi-square over 20 bins inside the
    media and one for "no scattering"), a channel without extinction never scatters in its
    piece, and the density and transmittance it reports at each point are the analytic ones."""
    probe = _probes.SegmentProbe(FLIGHT_SCENE)
    n = 200_000
    r = probe.flights((0.0, 0.0, -5.0), (0.0, 0.0, 1.0), 100.0, n, 7).astype(np.float64)
    t = r[:, 0]
    edges = np.concatenate([np.linspace(3.0, 4.0, 11), np.linspace(5.0, 6.5, 11)])
    cdf = lambda x: 1.0 - np.exp(-_flight_depth(x)).mean(-1)  # noqa: E731 (P(scattered before x))
    expected = np.diff(cdf(edges))
    expected[10] = 0.0  # the vacuum between the media
    expected = np.append(expected, 1.0 - cdf(8.0))
    counts = np.append(np.histogram(t[np.isfinite(t)], edges)[0], np.sum(~np.isfinite(t)))
    keep = expected > 0
    assert counts[~keep].sum() == 0
    chi2, p = stats.chisquare(counts[keep], expected[keep] * n)
    assert p > 1e-3, (chi2, p, counts, expected * n)
    s = np.isfinite(t)
    sigma = np.where(((t[s] >= 3) & (t[s] <= 4))[:, None], FLIGHT_SIGMA["a"], FLIGHT_SIGMA["b"])
    tr = np.exp(-_flight_depth(t[s]))
    np.testing.assert_allclose(r[s, 2:], tr, rtol=2e-4, atol=1e-6)
    np.testing.assert_allclose(r[s, 1], (sigma * tr).mean(-1), rtol=2e-4)


# ---------------------------------------------------------------- furnace tests

def furnace_scene(medium, sensor_inside=False):
    """Media of albedo 1 inside a null ball under a constant environment of radiance 1: every
    pixel is exactly 1 (scattering without absorption keeps a uniform radiance field). The ball
    is a few mean free paths across, so that paths leave it in tens of steps and Russian
    roulette keeps the per-pixel estimates light-tailed enough for z-tests."""
    air = medium_xml(medium, "medium") if sensor_inside else ""
    sensors = "".join(
        f"""<sensor type="perspective"><float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="{o}" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/><rfilter type="box"/></film>
        {air}</sensor>""" for o in (("0, 0.3, 1", "0.2, -0.1, 0.4") if sensor_inside else ("0, 0.3, 3", "0.2, -0.1, 2.5")))
    return f"""<scene version="3.0.0">
    <integrator type="volpath"/>
    {sensors}
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="sphere"><float name="radius" value="{1.5 if sensor_inside else 1}"/><bsdf type="null"/>
        {medium_xml(medium, "interior")}</shape>
</scene>"""


FURNACES = {
    "homogeneous": homogeneous('<float name="sigma_t" value="3"/><float name="albedo" value="1"/>'),
    "homogeneous-rgb-hg": homogeneous('<rgb name="sigma_t" value="0.6, 0.8, 1"/><float name="scale" value="2"/>'
                                      '<float name="albedo" value="1"/>', '<phase type="hg"><float name="g" value="0.7"/></phase>'),
}


def _assert_all_one(r, what):
    """Each view's mean per channel equals 1: a z-test with the pooled variance of the pixel
    means (Sidak over views and channels; per-pixel tests would trust variance estimates from
    a few heavy-tailed samples), with a standard error below 1 %."""
    n_tests = 3 * len(r.view_ids)
    z_crit = stats.norm.isf(0.005 / n_tests)
    for vid in r.view_ids:
        img, var = r.images[vid].astype(np.float64), r.variance[vid].astype(np.float64)
        assert np.all(np.isfinite(img))
        n = img.shape[0] * img.shape[1]
        mean, se = img.mean(axis=(0, 1)), np.sqrt(var.sum(axis=(0, 1))) / n
        z = (mean - 1.0) / se
        assert np.abs(z).max() < z_crit, f"{what}, view {vid}: mean {mean}, z {z}"
        assert se.max() < 0.01, f"{what}, view {vid}: standard error {se} (too noisy to see a 3 % bias)"


@pytest.mark.parametrize("inside", [False, True], ids=["outside", "sensor-inside"])
@pytest.mark.parametrize("name", list(FURNACES))
def test_furnace(name, inside):
    r = mvpt.render(mvpt.load_string(furnace_scene(FURNACES[name], inside)), spp=256, seed=2)
    _assert_all_one(r, name)


def test_furnace_heterogeneous(tmp_path):
    vol = write_vol(tmp_path / "g.vol", blob_grid(8, 3) * 0.5 + 0.5)
    medium = ("heterogeneous", f'<volume type="gridvolume" name="sigma_t"><string name="filename" value="{vol}"/>'
                               '<transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform>'
                               '</volume><float name="albedo" value="1"/><float name="scale" value="3"/>'
                               '<phase type="hg"><float name="g" value="-0.4"/></phase>')
    r = mvpt.render(mvpt.load_string(furnace_scene(medium)), spp=256, seed=2)
    _assert_all_one(r, "heterogeneous")


# ---------------------------------------------------------------- against Mitsuba 3

def _vol_cases(tmp):
    v1, v3 = write_vol(tmp / "blob1.vol", blob_grid(16, 1)), write_vol(tmp / "blob3.vol", blob_grid(16, 3))
    return {
        "heterogeneous": fog_scene(heterogeneous(v1, '<rgb name="albedo" value="0.9, 0.8, 0.6"/><float name="scale" value="4"/>'),
                                   shape="cube"),
        "heterogeneous-rgb-hg": fog_scene(heterogeneous(v3, '<rgb name="albedo" value="0.9, 0.8, 0.6"/><float name="scale" value="4"/>',
                                                        '<phase type="hg"><float name="g" value="-0.3"/></phase>'), shape="cube"),
    }


AIR = '<medium type="homogeneous" id="air"><float name="sigma_t" value="0.08"/><rgb name="albedo" value="0.9, 0.9, 0.95"/></medium>'
CASES = {
    "homogeneous": fog_scene(homogeneous('<rgb name="albedo" value="0.8, 0.8, 0.8"/><float name="sigma_t" value="2"/>')),
    "absorbing-glass": fog_scene(homogeneous('<rgb name="albedo" value="0, 0, 0"/><rgb name="sigma_t" value="0.5, 0.2, 0.4"/>'),
                                 boundary='<bsdf type="dielectric"/>'),
    "rough-glass-scattering": fog_scene(homogeneous('<float name="albedo" value="0.95"/><float name="sigma_t" value="1.5"/>'),
                                        boundary='<bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf>'),
    "no-emitter-sampling-depth-4": fog_scene(homogeneous('<float name="sigma_t" value="1"/><boolean name="sample_emitters" value="false"/>'),
                                             max_depth=4),
    # The cameras in thin air that fills a big ball, with the fog ball inside it (its exterior: the air).
    "sensor-in-medium": f"""<scene version="3.0.0">
  <integrator type="volpath"/>
  {AIR}
  {SENSORS.format(medium='<ref id="air"/>')}
  {LIGHTS}
  <shape type="sphere"><point name="center" x="0" y="0.2" z="0"/><float name="radius" value="0.9"/><bsdf type="null"/>
     <medium type="homogeneous" name="interior"><float name="sigma_t" value="2"/></medium><ref name="exterior" id="air"/></shape>
  <shape type="sphere"><float name="radius" value="12"/><bsdf type="null"/><ref name="interior" id="air"/></shape>
</scene>""",
}


@pytest.fixture(scope="module")
def mc_module():
    pytest.importorskip("mitsuba")
    import mitsuba_compare
    return mitsuba_compare


@pytest.mark.parametrize("name", list(CASES) + ["heterogeneous", "heterogeneous-rgb-hg"])
def test_volpath_vs_mitsuba(name, mc_module, tmp_path):
    xml = CASES[name] if name in CASES else _vol_cases(tmp_path)[name]
    res = mc_module.compare_scene(xml, {}, spp=512, seeds=8, name=name)
    print(res.summary())
    assert res.passed, res.summary()


def test_volpath_spectral_extinction_vs_mitsuba_per_channel(mc_module):
    """Extinction that differs per channel (0.9, 3, 6): each channel against Mitsuba rendering the
    medium with that channel's values in every channel. Mitsuba's own RGB estimate weights
    distances by the density of the one channel it drew them with, which is heavy-tailed here
    (its red channel comes out 2-3 % low at 512 spp, with a variance estimate that hides it);
    the grey references are exact per channel, and transport does not mix channels."""
    albedo, sigma_t = (0.9, 0.7, 0.5), (0.9, 3.0, 6.0)
    phase = '<phase type="hg"><float name="g" value="0.6"/></phase>'
    rgb = fog_scene(homogeneous(f'<rgb name="albedo" value="{", ".join(map(str, albedo))}"/>'
                                f'<rgb name="sigma_t" value="{", ".join(str(s / 6) for s in sigma_t)}"/>'
                                '<float name="scale" value="6"/>', phase))
    ours = mc_module.render_mvpt(mc_module.load_mvpt(rgb, {}), 512)
    refs = [mc_module.render_mitsuba(mc_module.load_mitsuba(fog_scene(homogeneous(
        f'<float name="albedo" value="{a}"/><float name="sigma_t" value="{s}"/>', phase)), {}), 512, 8)
        for a, s in zip(albedo, sigma_t)]
    pairs = []
    for k, (i, vid, ea) in enumerate(ours):
        eb = refs[0][k][2]
        for c in (1, 2):
            for field in ("mean", "var", "dof"):
                getattr(eb, field)[..., c] = getattr(refs[c][k][2], field)[..., c]
        pairs.append((i, vid, ea, eb))
    res = mc_module.compare_estimates("homogeneous-spectral", pairs)
    print(res.summary())
    assert res.passed, res.summary()


# ---------------------------------------------------------------- determinism and semantics

def test_volpath_is_bit_identical_for_any_thread_count(tmp_path):
    xml = _vol_cases(tmp_path)["heterogeneous-rgb-hg"]
    scene = mvpt.load_string(xml)
    runs = [mvpt.render(scene, spp=4, seed=9, threads=t) for t in (1, 2, 3)]
    for r in runs[1:]:
        for vid in runs[0].view_ids:
            assert np.array_equal(r.images[vid], runs[0].images[vid])


def test_sigma_a_sigma_s_equal_sigma_t_albedo():
    a = fog_scene(homogeneous('<float name="sigma_a" value="0.5"/><float name="sigma_s" value="1.5"/>'))
    b = fog_scene(homogeneous('<float name="sigma_t" value="2"/><float name="albedo" value="0.75"/>'))
    ra, rb = (mvpt.render(mvpt.load_string(x), spp=4, seed=1) for x in (a, b))
    for vid in ra.view_ids:
        assert np.array_equal(ra.images[vid], rb.images[vid])


@pytest.mark.parametrize("integrator", ["path", "mvpath"])
def test_surface_integrators_ignore_media_and_say_so(integrator):
    """`path` ignores media as Mitsuba's does, and `mvpath` (its multi-view form) likewise; both
    say so. `volpath` renders them with either method (test_mvpt_media.py)."""
    xml = fog_scene(homogeneous('<float name="sigma_t" value="2"/>'), integrator=integrator)
    s = mvpt.load_string(xml)
    assert any(f"'{integrator}' integrator ignores" in n and "volpath" in n for n in s.notes)
    no_medium = mvpt.load_string(xml.replace('<medium type="homogeneous" name="interior"><float name="sigma_t" value="2"/></medium>', ""))
    ra, rb = mvpt.render(s, spp=2, seed=1), mvpt.render(no_medium, spp=2, seed=1)
    assert np.array_equal(ra.images["0"], rb.images["0"])


# ---------------------------------------------------------------- bad input

def _error(xml, match):
    with pytest.raises(mvpt.SceneError, match=match):
        mvpt.load_string(xml)


def test_medium_name_must_be_interior_or_exterior():
    _error(fog_scene(homogeneous("")).replace('name="interior"', 'name="inside"'), "'interior' or 'exterior', got 'inside'")


def test_homogeneous_needs_constants(tmp_path):
    vol = write_vol(tmp_path / "g.vol", blob_grid(4))
    medium = ("homogeneous", f'<volume type="gridvolume" name="sigma_t"><string name="filename" value="{vol}"/></volume>')
    _error(fog_scene(medium), "constant sigma_t.*heterogeneous")


def test_sigma_a_and_sigma_t_together_is_an_error():
    _error(fog_scene(homogeneous('<float name="sigma_a" value="1"/><float name="sigma_t" value="2"/>')), "either sigma_t")


@pytest.mark.parametrize("params,match", [
    ('<float name="sigma_a" value="-0.5"/><float name="sigma_s" value="1"/>', r"sigma_a must lie in \[0, inf\]"),
    ('<float name="sigma_a" value="2"/><float name="sigma_s" value="-1"/>', r"sigma_s must lie in \[0, inf\]"),
    ('<float name="sigma_t" value="1"/><float name="albedo" value="-0.5"/>', r"albedo must lie in \[0, 1\]"),
    ('<float name="sigma_t" value="1"/><rgb name="albedo" value="0.5, 1.2, 0.5"/>', r"albedo must lie in \[0, 1\].*to 1.2")])
def test_coefficients_out_of_range(params, match):
    """An albedo outside [0, 1] or a negative absorption or scattering coefficient (which
    sigma_a + sigma_s >= 0 alone lets through) is refused, naming the parameter."""
    _error(fog_scene(homogeneous(params)), match)


@pytest.mark.parametrize("name,grid,match", [("sigma_t", -0.1, r"sigma_t must lie in \[0, inf\]"),
                                             ("albedo", 1.5, r"albedo must lie in \[0, 1\]")])
def test_grid_coefficients_out_of_range(tmp_path, name, grid, match):
    g = blob_grid(4)
    g.flat[5] = grid
    vol = write_vol(tmp_path / "g.vol", g)
    other = '<float name="albedo" value="0.5"/>' if name == "sigma_t" else '<float name="sigma_t" value="1"/>'
    medium = ("heterogeneous", f'<volume type="gridvolume" name="{name}"><string name="filename" value="{vol}"/>'
              f'</volume>{other}')
    _error(fog_scene(medium), match)


def test_hg_asymmetry_out_of_range():
    _error(fog_scene(homogeneous("", '<phase type="hg"><float name="g" value="1"/></phase>')), r"\(-1, 1\)")


@pytest.mark.parametrize("case,match", [
    ("truncated", r"bytes of data \(expected"), ("magic", "not a .vol file"), ("channels", "channels"),
    ("resolution", "resolution"), ("nan", "not finite"), ("wrapping_resolution", r"more than 2\^30 values")])
def test_bad_vol_files(tmp_path, case, match):
    path = write_vol(tmp_path / "g.vol", blob_grid(4))
    data = bytearray(path.read_bytes())
    if case == "truncated":
        data = data[:-7]
    elif case == "magic":
        data[0:3] = b"VOX"
    elif case == "channels":
        data[20:24] = (2).to_bytes(4, "little")
    elif case == "resolution":
        data[8:12] = (-4).to_bytes(4, "little", signed=True)
    elif case == "wrapping_resolution":  # 2^30 x 2^30 x 2^4 values wrap to 0: a header alone
        data = data[:48]
        data[8:20] = np.array([2**30, 2**30, 2**4], dtype="<i4").tobytes()
    elif case == "nan":
        data[48 + 8:48 + 12] = np.float32(np.nan).tobytes()
    path.write_bytes(bytes(data))
    _error(fog_scene(heterogeneous(path, "")), match)


def test_volpath_without_media_is_path():
    """A scene without media renders with `volpath` as with `path` (the wavefront path tracer,
    bit for bit), and multi-view path tracing accepts it (Bitterli's scenes name volpath)."""
    xml = fog_scene(homogeneous('<float name="sigma_t" value="2"/>'))
    xml = xml.replace('<medium type="homogeneous" name="interior"><float name="sigma_t" value="2"/></medium>', "")
    vol, path = mvpt.load_string(xml), mvpt.load_string(xml.replace('type="volpath"', 'type="path"'))
    ra, rb = mvpt.render(vol, spp=2, seed=4), mvpt.render(path, spp=2, seed=4)
    for vid in ra.view_ids:
        assert np.array_equal(ra.images[vid], rb.images[vid])
    rm = mvpt.render(vol, spp=2, seed=4, method="mvpt")
    assert rm.stats["method"] == "mvpt"
