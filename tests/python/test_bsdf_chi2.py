"""Chi-square tests of every BSDF's sample() against its pdf(), for several
incident directions, roughnesses (isotropic / anisotropic), both microfacet
distributions, sample_visible on and off, and incidence from below for the
two-sided dielectrics. Delta lobes are excluded from the histograms (the
harness counts them as discrete); the pdf must then integrate to the
probability of a continuous sample."""
import pytest

from bsdf_cases import chi2_adapters, direction, probe
from chi2 import chi2_test


def _rough(kind, distr, alpha=None, au=None, av=None, visible=True, extra=""):
    a = (f'<float name="alpha" value="{alpha}"/>' if alpha is not None else
         f'<float name="alpha_u" value="{au}"/><float name="alpha_v" value="{av}"/>')
    return (f'<bsdf type="{kind}"><string name="distribution" value="{distr}"/>{a}'
            f'<boolean name="sample_visible" value="{str(visible).lower()}"/>{extra}</bsdf>')


ABOVE = [direction(10, 30), direction(50, 120), direction(80, -40)]
BELOW = [direction(20, 60, below=True), direction(70, 200, below=True)]

CASES = []
for distr in ("beckmann", "ggx"):
    for visible in (True, False):
        CASES += [(f"roughconductor-{distr}-iso-vis{int(visible)}", _rough("roughconductor", distr, 0.3, visible=visible), ABOVE),
                  (f"roughconductor-{distr}-aniso-vis{int(visible)}",
                   _rough("roughconductor", distr, au=0.15, av=0.5, visible=visible), ABOVE[1:]),
                  (f"roughdielectric-{distr}-iso-vis{int(visible)}",
                   _rough("roughdielectric", distr, 0.3, visible=visible), ABOVE[:2] + BELOW),
                  (f"roughplastic-{distr}-vis{int(visible)}", _rough("roughplastic", distr, 0.25, visible=visible),
                   ABOVE[:2])]
    CASES += [(f"roughdielectric-{distr}-aniso", _rough("roughdielectric", distr, au=0.2, av=0.45,
                                                        extra='<float name="int_ior" value="1.33"/>'),
               [direction(40, 70), direction(60, 10, below=True)])]
CASES += [
    ("roughconductor-ggx-sharp", _rough("roughconductor", "ggx", 0.08), [direction(40, 20)]),
    ("diffuse", '<bsdf type="diffuse"/>', ABOVE[:2]),
    ("plastic", '<bsdf type="plastic"/>', ABOVE[:2]),
    ("phong-30", '<bsdf type="phong"/>', ABOVE),
    ("phong-3", '<bsdf type="phong"><float name="exponent" value="3"/>'
                '<rgb name="diffuse_reflectance" value="0.1, 0.2, 0.3"/></bsdf>', ABOVE[:2]),
    ("twosided-roughconductor", '<bsdf type="twosided">' + _rough("roughconductor", "ggx", 0.3) + '</bsdf>',
     [direction(30, 10), direction(60, 100, below=True)]),
    ("twosided-two-brdfs", '<bsdf type="twosided"><bsdf type="diffuse"/>' + _rough("roughplastic", "ggx", 0.2) + '</bsdf>',
     [direction(30, 10), direction(60, 100, below=True)]),
    ("blendbsdf-smooth", '<bsdf type="blendbsdf"><float name="weight" value="0.3"/><bsdf type="diffuse"/>'
                         + _rough("roughconductor", "beckmann", 0.2) + '</bsdf>', ABOVE[:2]),
    ("blendbsdf-with-delta", '<bsdf type="blendbsdf"><float name="weight" value="0.6"/><bsdf type="diffuse"/>'
                             '<bsdf type="conductor"/></bsdf>', ABOVE[:1]),
    ("mask", '<bsdf type="mask"><float name="opacity" value="0.6"/>' + _rough("roughconductor", "ggx", 0.4) + '</bsdf>',
     ABOVE[:2]),
    ("normalmap", '<bsdf type="normalmap"><rgb name="normalmap" value="0.7, 0.4, 0.85"/>'
                  + _rough("roughconductor", "ggx", 0.3) + '</bsdf>', [direction(30, 10), direction(75, 160)]),
]

PARAMS = [(name, xml, wi) for name, xml, wis in CASES for wi in wis]
N_TESTS = len(PARAMS)


@pytest.mark.parametrize("name,xml,wi", PARAMS, ids=[f"{p[0]}-{i}" for i, p in enumerate(PARAMS)])
def test_chi2(name, xml, wi):
    sample_fn, pdf_fn = chi2_adapters(probe(xml), wi)
    ok, p, msg = chi2_test(sample_fn, pdf_fn, n_samples=100_000, n_tests=N_TESTS)
    assert ok, f"{name} wi={wi}: {msg}"
