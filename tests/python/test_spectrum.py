"""Wavelength-sampled <spectrum> values: mvpt's RGB conversion against the RGB that Mitsuba 3
(`scalar_rgb`) gives the same spectrum in the same role (read back with mi.traverse), and the
same through the XML loader (a diffuse BSDF probe, a directly seen area light, .spd files)."""
from __future__ import annotations

import numpy as np
import pytest

import mvpt
from mvpt import _probes

mi = pytest.importorskip("mitsuba")
mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)  # "clamping out-of-gamut color" warnings

SPECTRA = {
    # From /work/shared/scenes (Mitsuba's cbox, blendbsdf) and edge cases.
    "cbox_light": "400:0, 500:8, 600:15.6, 700:18.4",
    "cbox_white": "400:0.343, 404:0.445, 408:0.551, 412:0.624, 416:0.665, 420:0.687, 500:0.747, 600:0.74, 700:0.737",
    "cbox_red": "400:0.04, 500:0.058, 560:0.067, 580:0.099, 600:0.287, 620:0.513, 640:0.609, 700:0.642",
    "cbox_green": "400:0.092, 480:0.125, 500:0.285, 520:0.472, 540:0.441, 560:0.337, 600:0.16, 700:0.159",
    "flat": "400:0.78, 500:0.78, 600:0.78, 700:0.78",
    "eta": "300:1.8, 400:1.65, 500:0.9, 600:0.2, 700:0.16, 800:0.18",
    "k": "300:1.92, 400:1.95, 500:1.95, 600:2.97, 700:3.8, 800:5.12",
    "narrow_uneven": "365.5:0.2, 402.25:-0.1, 555:0.9, 700.1:0.3",
    "beyond_cie": "200:0.5, 1000:0.5",
    "constant": "0.35",
}
USES = ["reflectance", "unbounded", "emission"]


def _pairs(text):
    if ":" not in text:
        return [], [float(text)]
    w, v = zip(*[(float(a), float(b)) for a, b in (t.split(":") for t in text.split(","))])
    return list(w), list(v)


def _mitsuba_rgb(text, use):
    """What Mitsuba makes of `text` as a diffuse reflectance, a conductor's eta or an area radiance."""
    s = f'<spectrum name="{{}}" value="{text}"/>'
    if use == "reflectance":
        obj, key = f'<bsdf version="3.0.0" type="diffuse">{s.format("reflectance")}</bsdf>', "reflectance.value"
    elif use == "unbounded":
        obj, key = f'<bsdf version="3.0.0" type="conductor">{s.format("eta")}</bsdf>', "eta.value"
    else:
        obj, key = (f'<shape version="3.0.0" type="rectangle"><emitter type="area">{s.format("radiance")}'
                    '</emitter></shape>', "emitter.radiance.value")
    v = mi.traverse(mi.load_string(obj))[key]
    return np.broadcast_to(np.array(v, dtype=float).ravel(), 3)


@pytest.mark.parametrize("use", USES)
@pytest.mark.parametrize("name", list(SPECTRA))
def test_conversion_matches_mitsuba(name, use):
    got = np.array(_probes.spectrum_to_rgb(*_pairs(SPECTRA[name]), use))
    want = _mitsuba_rgb(SPECTRA[name], use)
    assert np.allclose(got, want, rtol=1e-4, atol=1e-6), f"{name} as {use}: mvpt {got}, Mitsuba {want}"


def test_roles_differ_as_in_mitsuba():
    # The cbox light as emission vs reflectance: no D65 weighting, no clamping at 1.
    w, v = _pairs(SPECTRA["cbox_light"])
    assert np.all(np.array(_probes.spectrum_to_rgb(w, v, "emission")) > 2.0)
    assert np.allclose(_probes.spectrum_to_rgb(w, v, "reflectance"), 1.0)
    with pytest.raises(ValueError, match="at least two"):
        _probes.spectrum_to_rgb([500.0], [1.0], "emission")
    with pytest.raises(ValueError, match="use must be"):
        _probes.spectrum_to_rgb([], [1.0], "albedo")


def test_diffuse_reflectance_through_the_loader():
    # f * cos at normal incidence and exit is reflectance / pi.
    text = SPECTRA["cbox_green"]
    probe = _probes.BsdfProbe(f'<bsdf type="diffuse"><spectrum name="reflectance" value="{text}"/></bsdf>')
    f = probe.eval(0.0, 0.0, 1.0, np.array([[0.0, 0.0, 1.0]], dtype=np.float32))[0]
    assert np.allclose(f * np.pi, _mitsuba_rgb(text, "reflectance"), rtol=1e-4)


AREA = """<shape type="rectangle">
        <transform name="to_world"><scale value="10"/><rotate y="1" angle="180"/><translate z="5"/></transform>
        <emitter type="area">{}</emitter>
    </shape>"""


def _seen_emitter(spectrum_xml, emitter=AREA):
    """A 4x4 view filled by one emitter (by default an area light): every pixel is its radiance."""
    xml = f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="20"/>
        <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/>
            <rfilter type="box"/></film>
    </sensor>
    {emitter.format(spectrum_xml)}
</scene>"""
    img = mvpt.render(mvpt.load_string(xml), spp=1).images
    return next(iter(img.values())).reshape(-1, 3)


@pytest.mark.parametrize("name", ["cbox_light", "constant"])
def test_area_radiance_through_the_loader(name):
    text = SPECTRA[name]
    px = _seen_emitter(f'<spectrum name="radiance" value="{text}"/>')
    assert np.allclose(px, _mitsuba_rgb(text, "emission")[None, :], rtol=1e-4)


def test_spd_file_equals_inline_values(tmp_path):
    w, v = _pairs(SPECTRA["cbox_light"])
    (tmp_path / "light.spd").write_text("# wavelength value\n\n" + "".join(f"{a} {b}\n" for a, b in zip(w, v)))
    px = _seen_emitter(f'<spectrum name="radiance" filename="{tmp_path / "light.spd"}"/>')
    mi_rgb = mi.traverse(mi.load_string(
        f'<shape version="3.0.0" type="rectangle"><emitter type="area"><spectrum name="radiance" '
        f'filename="{tmp_path / "light.spd"}"/></emitter></shape>'))["emitter.radiance.value"]
    assert np.allclose(px, np.array(mi_rgb)[None, :], rtol=1e-4)


def test_environment_radiance_through_the_loader():
    # A `constant` emitter's radiance is an emission spectrum too (Mitsuba's get_emissive_texture).
    text = SPECTRA["cbox_light"]
    px = _seen_emitter(f'<spectrum name="radiance" value="{text}"/>', '<emitter type="constant">{}</emitter>')
    assert np.allclose(px, _mitsuba_rgb(text, "emission")[None, :], rtol=1e-4)
