"""FD_g / FD_k / L1div / Div_k, and the moment summaries the scorer combines."""
import warnings

import numpy as np
import pytest

from evalsuite.metrics import FrechetWarning, div_k, fd_g, fd_k, frechet_distance_samples, l1div
from evalsuite.metrics.distribution import combine_moments, frechet_from_moments, moments, moments_covariance


def test_fd_between_unit_gaussians_approaches_squared_mean_distance():
    rng = np.random.default_rng(0)
    d = 6
    mu = np.array([1.0, -2.0, 0.5, 0.0, 3.0, 1.0])
    x = rng.normal(size=(200_000, d))
    y = rng.normal(size=(200_000, d)) + mu
    assert frechet_distance_samples(x, y) == pytest.approx(mu @ mu, rel=5e-3)


def test_fd_between_isotropic_gaussians_of_different_scale():
    rng = np.random.default_rng(1)
    d, s1, s2 = 4, 1.0, 3.0
    x = rng.normal(size=(200_000, d)) * s1
    y = rng.normal(size=(200_000, d)) * s2
    assert frechet_distance_samples(x, y) == pytest.approx(d * (s1 - s2) ** 2, rel=1e-2)


def test_fd_g_and_fd_k_pool_frames_of_all_sequences():
    rng = np.random.default_rng(2)
    nat = [rng.normal(size=(300, 2, 3)) for _ in range(3)]
    gen = [rng.normal(size=(250, 2, 3)) + 1.0 for _ in range(3)]
    flat = lambda seqs: np.concatenate([s.reshape(len(s), -1) for s in seqs])  # noqa: E731
    assert fd_g(nat, gen) == pytest.approx(frechet_distance_samples(flat(nat), flat(gen)), rel=1e-12)
    diffs = lambda seqs: np.concatenate([np.diff(s.reshape(len(s), -1), axis=0) for s in seqs])  # noqa: E731
    assert fd_k(nat, gen) == pytest.approx(frechet_distance_samples(diffs(nat), diffs(gen)), rel=1e-12)
    assert fd_g(nat, nat) == pytest.approx(0.0, abs=1e-10)


def test_moments_combine_exactly_like_concatenation_and_multiplicities():
    rng = np.random.default_rng(3)
    parts = [rng.normal(loc=k, size=(50 + 10 * k, 4)) for k in range(4)]
    n, mean, scatter = combine_moments([moments(p) for p in parts])
    all_x = np.concatenate(parts)
    assert n == len(all_x)
    np.testing.assert_allclose(mean, all_x.mean(0), rtol=1e-12)
    np.testing.assert_allclose(moments_covariance((n, mean, scatter))[1], np.cov(all_x, rowvar=False), rtol=1e-10)
    weights = [2, 0, 1, 3]  # a bootstrap draw: part 0 twice, part 3 three times
    rep = np.concatenate([p for p, w in zip(parts, weights) for _ in range(w)])
    nw, meanw, scw = combine_moments([moments(p) for p in parts], weights)
    assert nw == len(rep)
    np.testing.assert_allclose(scw / (nw - 1), np.cov(rep, rowvar=False), rtol=1e-10)
    y = rng.normal(size=(400, 4)) * 2
    assert frechet_from_moments(moments(all_x), moments(y)) == pytest.approx(frechet_distance_samples(all_x, y),
                                                                          rel=1e-9)


def test_too_few_samples_warn():
    x = np.random.default_rng(4).normal(size=(5, 8))
    with pytest.warns(FrechetWarning):
        frechet_from_moments(moments(x), moments(x + 1))


def test_l1div_and_div_k_match_their_reference_formulas():
    rng = np.random.default_rng(5)
    seqs = [rng.normal(size=(40 + 5 * k, 3, 3)) for k in range(3)]
    # EMAGE L1div: per sequence sum |x - mean_t x| accumulated, divided by the total frame count
    total, count = 0.0, 0
    for s in seqs:
        flat = s.reshape(len(s), -1).copy()
        mean = flat.mean(axis=0)
        for i in range(len(flat)):
            flat[i] = np.abs(flat[i] - mean)
        total += flat.sum()
        count += len(flat)
    assert l1div(seqs) == pytest.approx(total / count, rel=1e-12)
    # leaderboard var_k: np.var over time per dim, concatenated, averaged
    expected = np.concatenate([np.var(s.reshape(len(s), -1), axis=0) for s in seqs]).mean()
    assert div_k(seqs) == pytest.approx(expected, rel=1e-12)


def test_static_motion_has_zero_diversity():
    still = np.repeat(np.random.default_rng(6).normal(size=(1, 4, 3)), 30, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert l1div([still]) == pytest.approx(0.0, abs=1e-12)
        assert div_k([still]) == pytest.approx(0.0, abs=1e-12)
