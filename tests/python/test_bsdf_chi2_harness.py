"""Self-test of the chi-square harness (tests/python/chi2.py): it must accept
a correct sampler/pdf pair and reject subtly wrong ones."""
import numpy as np

from chi2 import chi2_test, integrate_pdf, sidak_level

N_TESTS = 4


def _cosine_power_sampler(e, rng):
    """Directions with density (e+1)/(2 pi) cos^e(theta) on the upper hemisphere."""
    def sample(n):
        u1, u2 = rng.random(n), rng.random(n)
        c = u1 ** (1.0 / (e + 1.0))
        s = np.sqrt(1.0 - c * c)
        phi = 2 * np.pi * u2
        return np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1), np.ones(n, bool)
    return sample


def _cosine_power_pdf(e):
    return lambda wo: np.where(wo[:, 2] > 0, (e + 1) / (2 * np.pi) * np.maximum(wo[:, 2], 0) ** e, 0.0)


def test_integration_of_uniform_density_is_exact():
    cells = integrate_pdf(lambda wo: np.full(len(wo), 1.0 / (4 * np.pi)), 10, 20)
    assert np.allclose(cells, 1.0 / 200, rtol=1e-6)


def test_accepts_correct_pdf():
    rng = np.random.default_rng(1)
    ok, p, msg = chi2_test(_cosine_power_sampler(3.0, rng), _cosine_power_pdf(3.0), n_tests=N_TESTS)
    assert ok, msg


def test_rejects_slightly_wrong_exponent():
    rng = np.random.default_rng(2)
    ok, p, msg = chi2_test(_cosine_power_sampler(3.0, rng), _cosine_power_pdf(3.3), n_tests=N_TESTS)
    assert not ok, msg


def test_rejects_missing_probability_mass():
    """Half of the samples are invalid (e.g. a discrete lobe) but the pdf claims all of them."""
    rng = np.random.default_rng(3)
    base = _cosine_power_sampler(1.0, rng)

    def sample(n):
        wo, valid = base(n)
        return wo, valid & (rng.random(n) < 0.95)
    ok, p, msg = chi2_test(sample, _cosine_power_pdf(1.0), n_tests=N_TESTS)
    assert not ok, msg


def test_rejects_samples_where_pdf_is_zero():
    rng = np.random.default_rng(4)
    base = _cosine_power_sampler(1.0, rng)

    def sample(n):
        wo, valid = base(n)
        wo[:10, 2] *= -1.0  # a few samples below the horizon
        return wo, valid
    ok, p, msg = chi2_test(sample, _cosine_power_pdf(1.0), n_tests=N_TESTS)
    assert not ok and "zero" in msg, msg


def test_sidak_level():
    assert abs(sidak_level(0.01, 1) - 0.01) < 1e-12
    assert sidak_level(0.01, 100) < 0.01 / 99
