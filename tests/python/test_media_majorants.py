"""Local majorants of heterogeneous media (docs/media.md, "Majorants"): the majorant grid bounds
every lookup of its volume, the pieces along a ray bound the extinction on them, free flights
and transmittance against them are unbiased (piecewise-constant and trilinear grids against
exp(-optical depth)), a grid with one voxel of 1e30 renders promptly, voxels of 1e3 and 1e8
that are both opaque give the same image, and flights that give up are reported."""
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from media_scenes import LIGHTS, write_vol  # noqa: E402

mvpt = pytest.importorskip("mvpt")
from mvpt import _probes  # noqa: E402

CUBE = '<transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform>'


def _volume(vol, name="", filt="trilinear", wrap="clamp"):
    name = f' name="{name}"' if name else ""
    return (f'<volume type="gridvolume"{name}><string name="filename" value="{vol}"/>{CUBE}'
            f'<string name="filter_type" value="{filt}"/><string name="wrap_mode" value="{wrap}"/></volume>')


def _hot_grid(hot, n=4, base=0.1):
    g = np.full((n, n, n, 1), base, np.float32)
    g[1, 2, 1, 0] = hot
    return g


# ---------------------------------------------------------------- the grid and the pieces

@pytest.mark.parametrize("filt", ["trilinear", "nearest"])
@pytest.mark.parametrize("wrap", ["clamp", "repeat", "mirror"])
def test_majorant_grid_bounds_every_lookup(tmp_path, filt, wrap):
    """Cells on the dual lattice of the voxel centres (5^3 for 4^3 voxels) bound each lookup in
    them, the border half cells with their wrapped neighbours, next to a voxel of 1e30."""
    rng = np.random.default_rng(1)
    g = rng.uniform(0, 2, (4, 4, 4, 1)).astype(np.float32)
    g[0, 3, 1, 0] = 1e30
    probe = _probes.VolumeProbe(_volume(write_vol(tmp_path / "g.vol", g), filt=filt, wrap=wrap))
    assert probe.resolution == [5, 5, 5]
    p = rng.uniform(-1.02, 1.02, (200_000, 3)).astype(np.float32)
    v, bound = probe.eval(p).max(1), probe.cell_bound(p)
    assert np.all(v <= bound * (1 + 1e-6))
    # Tight: a cell away from the hot voxel is not bounded by it.
    assert np.mean(bound < 10) > 0.5


def test_majorant_grid_coarsens_large_grids(tmp_path):
    """Past 64 cells an axis, cells span several dual cells; they still bound every lookup."""
    rng = np.random.default_rng(2)
    g = rng.uniform(0, 1, (150, 3, 2, 1)).astype(np.float32)
    g[70, 1, 0, 0] = 1e6
    probe = _probes.VolumeProbe(_volume(write_vol(tmp_path / "g.vol", g)))
    assert probe.resolution == [3, 4, 51]  # 151 dual cells in threes along z
    p = rng.uniform(-1, 1, (200_000, 3)).astype(np.float32)
    assert np.all(probe.eval(p).max(1) <= probe.cell_bound(p) * (1 + 1e-6))


@pytest.mark.parametrize("hot", [1e3, 1e30])
def test_pieces_bound_the_extinction_along_rays(tmp_path, hot):
    """The walk's pieces cover the ray in order and bound the extinction on them; near a voxel
    of 1e30 they follow its trilinear ramp in a bounded number of steps."""
    probe = _probes.VolumeProbe(_volume(write_vol(tmp_path / "g.vol", _hot_grid(hot))))
    rng = np.random.default_rng(3)
    for _ in range(200):
        o = rng.uniform(-1, 1, 3).astype(np.float32)
        d = rng.normal(size=3).astype(np.float32)
        d /= np.linalg.norm(d)
        t_exit = float(np.min((np.sign(d) - o) / d))  # (as the medium clips the ray to the cube)
        pieces = probe.pieces(*o, *d, 0.0, t_exit)
        assert len(pieces) < 2000
        t, length, bound, at = pieces.T
        np.testing.assert_allclose(t[1:], (t + length)[:-1], rtol=0, atol=1e-6)
        assert t[0] == 0.0 and abs(t[-1] + length[-1] - t_exit) < 1e-5
        # Points well inside the pieces (one at a cell's face may round into the next cell).
        free = np.isnan(at) & (length > 1e-4)
        s = rng.uniform(0.1, 0.9, (free.sum(), 8))
        pts = (t[free, None] + s * length[free, None]).astype(np.float32)
        p = (o[None, None, :] + pts[..., None] * d[None, None, :]).astype(np.float32).reshape(-1, 3)
        v = probe.eval(p).max(1).reshape(pts.shape)
        assert np.all(v <= bound[free, None] * (1 + 1e-5) + 1e-6)


# ---------------------------------------------------------------- unbiasedness

def _medium(vol_xml, albedo='<float name="albedo" value="0.8"/>'):
    return _probes.MediumProbe(f'<medium type="heterogeneous">{vol_xml}{albedo}</medium>')


def _axis_ray(y=0.25 - 1e-3, z=-0.25 + 2e-3):
    """A ray along +x through the cube [-1, 1]^3 from x = -2."""
    return np.array([[-2.0, y, z]], np.float32), np.array([[1.0, 0.0, 0.0]], np.float32)


def _z(mean, se):
    return np.abs(mean) / np.maximum(se, 1e-12)


def test_transmittance_piecewise_constant_is_exp_minus_depth(tmp_path):
    """Ratio tracking along a row of a nearest RGB grid (one voxel 200 times the rest) against
    exp(-sum of voxel depths), each channel."""
    rng = np.random.default_rng(4)
    g = rng.uniform(0, 1.5, (4, 4, 4, 3)).astype(np.float32)
    g[1, 2, 3, :] = [200.0, 0.3, 1.0]  # in the ray's row, x index 3
    g[1, 2, 1, :] = [0.0, 0.0, 0.0]
    m = _medium(_volume(write_vol(tmp_path / "g.vol", g), "sigma_t", filt="nearest"))
    o, d = _axis_ray()
    depth = np.cumsum(g[1, 2, :, :], axis=0)[-1] * 0.5
    for t, expected in [(3.0, np.exp(-depth)), (2.5, np.exp(-np.cumsum(g[1, 2, :, :], axis=0)[2] * 0.5))]:
        tr = m.transmittance(o, d, t, 40_000, seed=7)
        se = tr.std(0) / np.sqrt(len(tr)) + 1e-9
        assert np.all(_z(tr.mean(0) - expected, se) < 4.5), (t, tr.mean(0), expected, se)
    assert m.flights_given_up == 0


def test_free_flights_piecewise_constant_are_unbiased(tmp_path):
    """Spectral tracking along the same row: per channel, the weighted scatterings in each voxel
    equal the integral of sigma_s T there, and the weight of reaching the surface equals T."""
    rng = np.random.default_rng(5)
    g = rng.uniform(0, 1.5, (4, 4, 4, 3)).astype(np.float32)
    g[1, 2, 2, :] = [40.0, 0.2, 3.0]
    albedo = np.array([0.9, 0.6, 0.3])
    m = _medium(_volume(write_vol(tmp_path / "g.vol", g), "sigma_t", filt="nearest"),
                f'<rgb name="albedo" value="{", ".join(map(str, albedo))}"/>')
    o, d = _axis_ray()
    t_surface = 2.75  # the surface inside the last voxel (x = 0.75)
    rows = m.sample(o, d, t_surface, 200_000, seed=3)
    scattered, t, w = rows[:, 1] > 0, rows[:, 2], rows[:, 3:]
    sigma = g[1, 2, :, :].astype(np.float64)  # (4 voxels, 3 channels), each 0.5 long
    edges = np.array([1.0, 1.5, 2.0, 2.5, 3.0])  # the voxels' faces in ray parameter t
    before = np.vstack([np.zeros(3), np.cumsum(sigma * 0.5, axis=0)])[:-1]
    for k in range(4):
        a, b = edges[k], min(edges[k + 1], t_surface)
        inside = scattered & (t >= a) & (t < b)
        est = np.where(inside[:, None], w, 0.0)
        # integral of sigma_s exp(-(before + sigma (t - a))) over [a, b)
        expected = albedo * np.exp(-before[k]) * (1 - np.exp(-sigma[k] * (b - a)))
        se = est.std(0) / np.sqrt(len(est)) + 1e-9
        assert np.all(_z(est.mean(0) - expected, se) < 4.5), (k, est.mean(0), expected)
    through = np.where(~scattered[:, None], w, 0.0)
    expected = np.exp(-(before[3] + sigma[3] * (t_surface - 2.5)))
    se = through.std(0) / np.sqrt(len(through)) + 1e-9
    assert np.all(_z(through.mean(0) - expected, se) < 4.5), (through.mean(0), expected)


def _trilinear_rays(hot, rng):
    """Rays along x past the hot voxel (centre (-0.25, 0.25, -0.25), its hat 0.5 wide): for 1e3,
    where its weight is a few percent in y and z (the ramp gives an optical depth of about 1);
    for 1e30, on the faces of its cells (weight 0 exactly, extinction 0.1) and through it."""
    if hot < 1e6:
        return [(0.25 - 0.5 * (1 - wy), -0.25 - 0.5 * (1 - wz)) for wy, wz in rng.uniform(0.02, 0.08, (4, 2))]
    return [(0.25, -0.75), (0.1, -0.75), (-0.25, -0.25), (0.0, 0.25), (0.25, -0.25)]


@pytest.mark.parametrize("hot", [1e3, 1e30])
def test_transmittance_trilinear_near_extreme_voxel(tmp_path, hot):
    """Ratio tracking through the trilinear ramp of a hot voxel against exp(-depth), the depth
    integrated finely from the volume's own lookups along the ray."""
    vol = write_vol(tmp_path / "g.vol", _hot_grid(hot))
    probe = _probes.VolumeProbe(_volume(vol))
    m = _medium(_volume(vol, "sigma_t"))
    for k, (y, z) in enumerate(_trilinear_rays(hot, np.random.default_rng(6))):
        o, d = _axis_ray(y, z)
        ts = np.linspace(1.0, 3.0, 400_001)
        p = np.stack([o[0, 0] + ts, np.full_like(ts, y), np.full_like(ts, z)], 1).astype(np.float32)
        sigma = probe.eval(p)[:, 0].astype(np.float64)
        expected = np.exp(-np.sum(0.5 * (sigma[1:] + sigma[:-1]) * np.diff(ts)))  # the trapezoidal rule
        tr = m.transmittance(o, d, 4.0, 20_000, seed=k)[:, 0]
        assert _z(tr.mean() - expected, tr.std() / np.sqrt(len(tr)) + 1e-9) < 4.5, (y, z, tr.mean(), expected)
        assert 0.02 < expected < 0.98 or expected < 1e-30
    assert m.flights_given_up == 0


# ---------------------------------------------------------------- scenes

def _box_scene(sigma_t, albedo='<float name="albedo" value="0.8"/>', size=16, max_depth=16):
    """The 16^2 box scene: a null cube of heterogeneous medium under the test lights."""
    return f"""<scene version="3.0.0"><integrator type="volpath"><integer name="max_depth" value="{max_depth}"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0.5, 1.5, 5" target="0, 0.2, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>
    <rfilter type="box"/></film></sensor>
  {LIGHTS}
  <shape type="cube"><bsdf type="null"/><medium type="heterogeneous" name="interior">{sigma_t}{albedo}</medium></shape>
</scene>"""


def test_voxel_of_1e30_renders_promptly(tmp_path):
    """One voxel of 1e30 among 63 of 0.1 (a walk against its global majorant did not end): the
    render finishes (the timeout only guards against a hang), with nothing given up."""
    vol = write_vol(tmp_path / "hot.vol", _hot_grid(1e30))
    (tmp_path / "scene.xml").write_text(_box_scene(_volume(vol, "sigma_t")))
    script = textwrap.dedent(f"""
        import numpy as np, mvpt
        r = mvpt.render(mvpt.load_file({str(tmp_path / 'scene.xml')!r}), spp=16, seed=1)
        assert all(np.isfinite(im).all() for im in r.images.values())
        print("warnings", r.stats["warnings"])
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "warnings []" in out.stdout, out.stdout


def test_opaque_voxels_of_1e3_and_1e8_render_alike(tmp_path):
    """A nearest voxel of 1e3 or 1e8 (both opaque over its 0.5: optical depth 500 or more) that
    absorbs all it meets: the same image in expectation (the global majorant of 1e8 made flights
    give up with weight 0, 31 % darker). Means of independent renders per channel, z-tested
    with standard errors from the per-pixel variances."""
    a = np.full((4, 4, 4, 1), 0.8, np.float32)
    a[1, 2, 1, 0] = 0.0
    albedo = _volume(write_vol(tmp_path / "albedo.vol", a), "albedo", filt="nearest")
    means = []
    for seed, hot in [(1, 1e3), (2, 1e8)]:
        sigma = _volume(write_vol(tmp_path / f"s{seed}.vol", _hot_grid(hot)), "sigma_t", filt="nearest")
        r = mvpt.render(mvpt.load_string(_box_scene(sigma, albedo)), spp=256, seed=seed)
        assert r.stats["warnings"] == []
        im, var = r.images["0"].reshape(-1, 3), r.variance["0"].reshape(-1, 3)
        means.append((im.mean(0), np.sqrt(var.sum(0)) / len(im)))
    (m1, s1), (m2, s2) = means
    assert np.all(_z(m1 - m2, np.hypot(s1, s2)) < 4.0), (m1, m2, s1, s2)


def test_flights_that_give_up_are_reported(tmp_path):
    """Ratio tracking through extinction (1e7, 0, 0) keeps the green and blue channels whole, so
    a shadow ray across the medium (from the floor in its shadow) takes 1e7 tentative collisions:
    past 2^22 it gives up (weight 0), and the render says so."""
    m = _probes.MediumProbe('<medium type="heterogeneous"><rgb name="sigma_t" value="1e7, 0, 0"/></medium>')
    tr = m.transmittance(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32), 1.0, 1)
    assert m.flights_given_up == 1 and np.all(tr == 0)
    r = mvpt.render(mvpt.load_string(_box_scene('<rgb name="sigma_t" value="1e7, 0, 0"/>', size=8, max_depth=2)), spp=1, seed=1)
    assert any("gave up" in w and "darker" in w for w in r.stats["warnings"]), r.stats["warnings"]
    plain = mvpt.render(mvpt.load_string(_box_scene('<rgb name="sigma_t" value="1, 0.5, 0.2"/>', size=2)), spp=1)
    assert plain.stats["warnings"] == []
