"""Image metrics against hand-computed values on tiny arrays (RMSE, relMSE, pooling), and FLIP's
basic properties through the flip-evaluator package."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mvpt import metrics


def _px(*rgb) -> np.ndarray:
    """A 1 x n image from n RGB triples."""
    return np.array([list(rgb)], dtype=np.float32)


def test_rmse_and_relmse_by_hand():
    x = _px([1, 2, 3])
    r = _px([1, 1, 1])
    # squared errors 0, 1, 4 over 3 channel values
    assert metrics.mse(x, r) == pytest.approx(5 / 3)
    assert metrics.rmse(x, r) == pytest.approx(math.sqrt(5 / 3))
    # (x-r)^2 / (r^2 + 0.01): 0, 1/1.01, 4/1.01
    assert metrics.relmse(x, r) == pytest.approx(5 / (3 * 1.01))
    assert metrics.RELMSE_EPS == 0.01


def test_relmse_dark_reference_is_bounded_by_eps():
    x = _px([0.1, 0.0, 0.2], [2.0, 2.0, 2.0])
    r = _px([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    # pixel 0: 0.01/0.01, 0, 0.04/0.01 ; pixel 1: three times 1/1.01
    expected = (1 + 0 + 4 + 3 / 1.01) / 6
    assert metrics.relmse(x, r) == pytest.approx(expected)
    assert metrics.relmse(x, r, eps=1.0) == pytest.approx((0.01 + 0.04 + 3 * 1 / 2) / 6)


def test_identical_images_have_zero_error():
    rng = np.random.default_rng(1)
    img = rng.uniform(0, 4, size=(24, 24, 3)).astype(np.float32)
    e = metrics.view_errors(img, img)
    assert e.rmse == 0 and e.relmse == 0 and e.flip == 0
    assert e.pixels == 24 * 24


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="shape"):
        metrics.rmse(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))


def test_overall_pools_pixels_of_all_views():
    ref = {"a": _px([1, 1, 1]), "b": _px([1, 1, 1], [1, 1, 1], [1, 1, 1])}
    test = {"a": _px([2, 2, 2]), "b": _px([1, 1, 1], [1, 1, 1], [3, 3, 3])}
    e = metrics.errors(test, ref, with_flip=False)
    assert e.views["a"].rmse == pytest.approx(1.0)
    assert e.views["b"].rmse == pytest.approx(math.sqrt(4 / 3))
    # all 4 pixels x 3 channels together: squared errors 1,1,1, 0*6, 4,4,4 -> 15/12
    assert e.overall.rmse == pytest.approx(math.sqrt(15 / 12))
    assert e.overall.relmse == pytest.approx((3 / 1.01 + 12 / 1.01) / 12)
    assert e.overall.pixels == 4
    assert math.isnan(e.overall.flip)


def test_missing_reference_view_is_named():
    with pytest.raises(ValueError, match="'c'"):
        metrics.errors({"c": _px([1, 1, 1])}, {"a": _px([1, 1, 1])}, with_flip=False)


def test_flip_matches_flip_evaluator_and_grows_with_the_error():
    flip_evaluator = pytest.importorskip("flip_evaluator", reason="FLIP needs the flip-evaluator package")
    rng = np.random.default_rng(2)
    ref = rng.uniform(0.2, 0.8, size=(32, 32, 3)).astype(np.float32)
    small = np.clip(ref + rng.normal(0, 0.02, ref.shape), 0, None).astype(np.float32)
    large = np.clip(ref + rng.normal(0, 0.3, ref.shape), 0, None).astype(np.float32)
    direct = flip_evaluator.evaluate(ref, small, "HDR")[1]
    assert metrics.flip(small, ref) == pytest.approx(direct, rel=1e-6)
    assert 0 < metrics.flip(small, ref) < metrics.flip(large, ref) <= 1
    error_map, mean = metrics.flip_map(large, ref)
    assert error_map.shape == (32, 32)
    assert float(error_map.mean()) == pytest.approx(mean, rel=1e-4)


def test_reference_noise_is_what_a_noisy_reference_adds():
    """relMSE against a noisy reference = the estimate's own relMSE + the reference's noise term,
    in expectation: subtracting metrics.reference_noise recovers the former."""
    rng = np.random.default_rng(4)
    shape = (96, 128, 3)
    truth = np.full(shape, 0.5) + 0.3 * rng.random(shape)
    var_r = (0.08 * truth) ** 2
    ref = truth + rng.normal(size=shape) * np.sqrt(var_r)
    x = truth + rng.normal(size=shape) * 0.1
    raw = metrics.relmse(x, ref)
    noise = metrics.reference_noise({"v": ref}, {"v": var_r})
    assert set(noise) == {"v", "overall"} and noise["v"] == noise["overall"] > 0
    own = metrics.relmse(x, truth)
    assert abs((raw - noise["overall"]) - own) < 0.05 * own, (raw, noise, own)
    assert raw - own > 0.5 * noise["overall"]  # the noise term is real and large here
    assert metrics.reference_noise({"v": ref}, {}) == {}  # variance unknown


def test_display_rows_of_grids_and_rows():
    assert metrics.display_rows(["r1c0", "r0c1", "r0c0", "r1c1"]) == [["r0c0", "r0c1"], ["r1c0", "r1c1"]]
    assert metrics.display_rows(["view002", "view000"]) == [["view002", "view000"]]
    assert metrics.display_rows(["left", "r0c0"]) == [["left", "r0c0"]]


def test_display_weights_blend_neighbours_with_clamped_ends():
    np.testing.assert_allclose(metrics.display_weights(1), [[1.0]])
    np.testing.assert_allclose(metrics.display_weights(3), [[0.75, 0.25, 0], [0.25, 0.5, 0.25], [0, 0.25, 0.75]])
    np.testing.assert_allclose(metrics.display_weights(7).sum(axis=1), 1.0)


def test_display_relmse_by_hand():
    # Two views of one pixel: 0 and 2 against 1 and 1; blended, each shows 0.75*x + 0.25*y.
    test = {"a": np.zeros((1, 1, 3)), "b": np.full((1, 1, 3), 2.0)}
    ref = {"a": np.ones((1, 1, 3)), "b": np.ones((1, 1, 3))}
    shown_a, shown_b = 0.5, 1.5  # 0.75*0 + 0.25*2, 0.75*2 + 0.25*0
    want = ((shown_a - 1) ** 2 + (shown_b - 1) ** 2) / 2 / 1.01
    assert metrics.display_relmse(test, ref)[0] == pytest.approx(want)


def test_display_reference_noise_is_what_independent_noise_adds():
    # Views of independent noise of variance s2 around a flat truth: the blended relMSE's
    # expectation is the noise term (sum of squared weights times s2, over r^2 + eps).
    rng = np.random.default_rng(4)
    views = [f"view{i:03d}" for i in range(9)]
    truth = {v: np.full((64, 64, 3), 0.5) for v in views}
    s2 = 0.01
    noisy = {v: truth[v] + rng.normal(0.0, np.sqrt(s2), truth[v].shape) for v in views}
    measured = metrics.display_relmse(noisy, truth)[0]
    predicted = metrics.display_relmse(truth, truth, {v: np.full((64, 64, 3), s2) for v in views})[1]
    # 110592 values: the mean's relative standard deviation is about 0.5 %
    assert measured == pytest.approx(predicted, rel=0.03)
    # and blending averages independent noise: 0.375 of a view's for interior views
    assert predicted < 0.45 * s2 / (0.25 + 0.01)
