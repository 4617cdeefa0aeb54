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


# --- the bootstrap of FD_g / FD_k: fast resampled distances, the small-sample rule ----------
def _sequence_moments(seqs):
    return [moments(s) for s in seqs]


def _one_by_one(ref, cond, weights):
    """The scorer's former bootstrap: moments combined and a Fréchet distance computed per resample."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FrechetWarning)
        return np.array([frechet_from_moments(combine_moments(ref, w), combine_moments(cond, w)) for w in weights])


def test_fast_bootstrap_equals_the_resample_by_resample_computation():
    from evalsuite.metrics.distribution import bootstrap_frechet
    from evalsuite.metrics.families import bootstrap_weights

    rng = np.random.default_rng(5)
    mix = rng.normal(size=(12, 12))
    ref = _sequence_moments([rng.normal(size=(60, 12)) @ mix + 50.0 for _ in range(9)])
    cond = _sequence_moments([rng.normal(size=(45, 12)) @ mix * 1.3 + 52.0 for _ in range(9)])
    weights = bootstrap_weights(9, 70, seed=3, cond_index=1)
    done = []
    fast = bootstrap_frechet(ref, cond, weights, threads=1, chunk=16, progress=done.append)
    np.testing.assert_allclose(fast, _one_by_one(ref, cond, weights), rtol=1e-8)
    assert sum(done) == 70 and len(done) == 5  # progress per chunk
    # the numbers do not depend on the number of threads
    np.testing.assert_array_equal(bootstrap_frechet(ref, cond, weights, threads=2, chunk=16), fast)
    # all weights 1: the point estimate
    assert bootstrap_frechet(ref, cond, np.ones((1, 9)))[0] == pytest.approx(
        frechet_from_moments(combine_moments(ref), combine_moments(cond)), rel=1e-9)


def test_fast_bootstrap_is_exact_on_rank_deficient_pose_covariances():
    """Poses of a skeleton have directions of zero variance (joints at fixed offsets). The fast bootstrap works
    in the range of the reference covariance, so it gives the distance of the same data without those
    directions (the exact value, by rotation invariance); the resample-by-resample form adds the square
    roots of round-off eigenvalues there."""
    from evalsuite.metrics.distribution import bootstrap_frechet
    from evalsuite.metrics.families import bootstrap_weights

    rng = np.random.default_rng(6)
    r, d = 10, 30
    basis = np.linalg.qr(rng.normal(size=(d, r)))[0]          # r varying directions in d dimensions
    mix = rng.normal(size=(r, r))
    low_ref = [rng.normal(size=(50, r)) @ mix * 20 for _ in range(8)]
    low_cond = [rng.normal(size=(50, r)) @ mix * 25 + 3.0 for _ in range(8)]
    offset = rng.normal(size=d) * 100
    embed = lambda seqs: [s @ basis.T + offset for s in seqs]  # noqa: E731
    weights = bootstrap_weights(8, 40, seed=0, cond_index=2)
    fast = bootstrap_frechet(_sequence_moments(embed(low_ref)), _sequence_moments(embed(low_cond)), weights)
    exact = _one_by_one(_sequence_moments(low_ref), _sequence_moments(low_cond), weights)
    np.testing.assert_allclose(fast, exact, rtol=1e-8)


def test_fast_bootstrap_falls_back_when_a_resample_is_singular():
    from evalsuite.metrics.distribution import bootstrap_frechet

    rng = np.random.default_rng(7)
    ref = _sequence_moments([rng.normal(size=(40, 6)) for _ in range(3)] + [rng.normal(size=(4, 6))])
    cond = _sequence_moments([rng.normal(size=(40, 6)) + 1 for _ in range(3)] + [rng.normal(size=(4, 6))])
    weights = np.array([[0.0, 0.0, 0.0, 4.0], [1.0, 1.0, 1.0, 1.0]])  # only the 4-frame sequence: rank 3 of 6
    fast = bootstrap_frechet(ref, cond, weights)
    np.testing.assert_allclose(fast, _one_by_one(ref, cond, weights), rtol=1e-6)


def test_two_samples_of_one_gaussian_at_the_stated_size_lie_five_percent_apart():
    """The small-sample rule's number: E[FD] ~ (1/N1 + 1/N2)(D + 5)/4 tr S, 5 % at 10 (D + 5) per side."""
    from evalsuite.metrics.frechet import min_samples

    rng = np.random.default_rng(8)
    d = 20
    n = min_samples(d)
    assert n == 250
    fds = [frechet_distance_samples(rng.normal(size=(n, d)) * 3, rng.normal(size=(n, d)) * 3) for _ in range(40)]
    assert np.mean(fds) / (9 * d) == pytest.approx(0.05, rel=0.08)


def test_sample_size_warnings_name_the_rule_that_is_broken():
    from evalsuite.metrics.frechet import sample_size_warnings

    assert sample_size_warnings((250, 250), 20, (10, 10), "frames") == []
    (bias,) = sample_size_warnings((249, 250), 20, (10, 10), "frames")
    assert "use at least 250 frames per side" in bias
    (few,) = sample_size_warnings((5000, 5000), 20, (10, 9), "frames")
    assert "9 sequence(s)" in few and "fewer than 10" in few
    singular, _, _ = sample_size_warnings((20, 400), 20, (5, 5), "windows")
    assert "20 windows for 20 dimensions: the covariance is singular" in singular
