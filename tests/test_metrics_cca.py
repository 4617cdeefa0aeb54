"""CCA: in-sample value against an independent generalized eigenproblem, a population oracle, cross-fitting."""
import numpy as np
import pytest
import scipy.linalg

from evalsuite.errors import InputError
from evalsuite.metrics import canonical_correlation, cca_fit, cca_score


def _independent_first_canonical_correlation(x, y):
    """rho^2 is the largest eigenvalue of Cxy Cyy^-1 Cyx a = rho^2 Cxx a."""
    c = np.cov(np.hstack([x, y]), rowvar=False)
    dx = x.shape[1]
    cxx, cyy, cxy = c[:dx, :dx], c[dx:, dx:], c[:dx, dx:]
    m = cxy @ np.linalg.solve(cyy, cxy.T)
    return float(np.sqrt(scipy.linalg.eigh(m, cxx, eigvals_only=True)[-1]))


def test_in_sample_matches_generalized_eigenproblem():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(2000, 1))
    x = np.hstack([z + rng.normal(size=(2000, 1)), rng.normal(size=(2000, 4))]) @ rng.normal(size=(5, 5))
    y = np.hstack([z + 0.5 * rng.normal(size=(2000, 1)), rng.normal(size=(2000, 3))])
    assert canonical_correlation(x, y) == pytest.approx(_independent_first_canonical_correlation(x, y), abs=1e-9)


def test_population_oracle_and_cross_fitted_score():
    # x1 = z + e1, y1 = z + e2 with unit variances: corr(x1, y1) = 1/2; other dims independent.
    rng = np.random.default_rng(1)
    n = 40_000
    z = rng.normal(size=n)
    x = np.column_stack([z + rng.normal(size=n), rng.normal(size=(n, 3))])
    y = np.column_stack([z + rng.normal(size=n), rng.normal(size=(n, 2))])
    half = n // 2
    model = cca_fit(x[:half], y[:half])
    assert model.correlation == pytest.approx(0.5, abs=0.02)
    assert cca_score(model, x[half:], y[half:]) == pytest.approx(0.5, abs=0.02)


def test_in_sample_is_optimistic_on_noise_but_cross_fitting_is_not():
    rng = np.random.default_rng(2)
    x, y = rng.normal(size=(2, 200, 40))
    assert canonical_correlation(x[:100], y[:100]) > 0.8        # 40+40 dims, 100 frames: spurious
    model = cca_fit(x[:100], y[:100])
    assert abs(cca_score(model, x[100:], y[100:])) < 0.35


def test_constant_dimensions_are_dropped_and_static_motion_is_an_error():
    rng = np.random.default_rng(3)
    x = np.column_stack([rng.normal(size=300), np.full(300, 7.0)])
    y = np.column_stack([x[:, 0] * 2 + 1, rng.normal(size=300)])
    assert canonical_correlation(x, y) == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(InputError, match="static"):
        canonical_correlation(np.ones((50, 3)), y[:50])
    with pytest.raises(InputError):
        cca_fit(x[:10], y[:9])
