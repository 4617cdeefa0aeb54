"""Rank correlations of two vectors and of many resamples at once, with exact small-sample p-values.

- Spearman's rho and Kendall's tau-b: exactly ``scipy.stats.spearmanr(x, y)`` and
  ``scipy.stats.kendalltau(x, y, variant="b")`` (tau-b corrects for ties);
- two-sided p-values, exact (every ordering of the conditions) for n <= :data:`EXACT_MAX_N`
  (:func:`rank_p_values`), scipy's approximations above;
- :func:`spearman_rows` / :func:`kendall_b_rows`: the same statistics for a batch ``(B, n)`` of row pairs
  (bootstrap resamples), equal to scipy's row by row.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

__all__ = ["EXACT_MAX_N", "EXACT", "T_APPROX", "NORMAL_APPROX", "rank_correlations", "rank_p_values",
           "spearman_rows", "kendall_b_rows", "replicates", "percentile"]

EXACT_MAX_N = 8  # every one of the n! orderings is enumerated up to here (8! = 40,320; 9! takes seconds a row)
EXACT, T_APPROX, NORMAL_APPROX = "exact", "t approximation", "normal approximation"
_CHUNK = 256


def rank_correlations(x, y) -> tuple[float, float, float, float]:
    """``(rho, p_rho, tau_b, p_tau)``: ``scipy.stats.spearmanr`` and ``kendalltau(variant="b")`` of two
    equally long vectors, with the p-values of :func:`rank_p_values`; all NaN when either is constant (no
    rank correlation exists)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.size < 2 or np.all(x == x[0]) or np.all(y == y[0]):
        return (math.nan,) * 4
    p_rho, _, p_tau, _ = rank_p_values(x, y)
    return float(stats.spearmanr(x, y).statistic), p_rho, float(stats.kendalltau(x, y, variant="b").statistic), p_tau


def rank_p_values(x, y) -> tuple[float, str, float, str]:
    """Two-sided p-values of Spearman's rho and Kendall's tau-b and how each was computed:
    ``(p_rho, method, p_tau, method)``, ``x``, ``y`` of shape ``(n,)``, neither constant.

    - ``"exact"``, n <= :data:`EXACT_MAX_N`: the permutation distribution over all n! orderings of y
      against x, ``p = min(1, 2 min(P(T* >= T), P(T* <= T)))`` (``scipy.stats.permutation_test((y,), ...,
      permutation_type="pairings", n_resamples=inf)``; for rho, ``scipy.stats.pearsonr`` of the average ranks with
      ``method=PermutationMethod(n_resamples=inf)``). Ties are kept, so this is exact with ties too;
    - tau-b without ties up to n = 33 is also ``"exact"``: scipy's exact null distribution
      (``kendalltau(method="exact")``);
    - otherwise ``"t approximation"`` for rho (``t = rho sqrt((n - 2) / (1 - rho^2))``, n - 2 degrees of
      freedom: ``spearmanr``) and ``"normal approximation"`` for tau-b (tie-corrected variance: ``kendalltau``).
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n = x.size
    ties = np.unique(x).size < n or np.unique(y).size < n
    if n <= EXACT_MAX_N:
        exhaustive = stats.PermutationMethod(n_resamples=np.inf)
        p_rho = stats.pearsonr(stats.rankdata(x), stats.rankdata(y), method=exhaustive).pvalue
        rho_method = EXACT
    else:
        p_rho, rho_method = stats.spearmanr(x, y).pvalue, T_APPROX
    if not ties and n <= 33:
        p_tau, tau_method = stats.kendalltau(x, y, variant="b", method="exact").pvalue, EXACT
    elif n <= EXACT_MAX_N:
        def tau_b(y_perm, axis=-1):  # y_perm: (..., n) orderings of y against the fixed x
            rows = np.reshape(y_perm, (-1, n))
            return kendall_b_rows(np.broadcast_to(x, rows.shape), rows).reshape(np.shape(y_perm)[:-1])

        p_tau = stats.permutation_test((y,), tau_b, permutation_type="pairings", n_resamples=np.inf,
                                       vectorized=True).pvalue
        tau_method = EXACT
    else:
        p_tau, tau_method = stats.kendalltau(x, y, variant="b", method="asymptotic").pvalue, NORMAL_APPROX
    return float(p_rho), rho_method, float(p_tau), tau_method


def spearman_rows(X, Y) -> np.ndarray:
    """Spearman's rho of each row pair of ``X``, ``Y`` (``(B, n)``; average ranks for ties, as scipy):
    the Pearson correlation of the ranks. NaN for a constant row."""
    rx = stats.rankdata(X, axis=1)
    ry = stats.rankdata(Y, axis=1)
    rx -= rx.mean(axis=1, keepdims=True)
    ry -= ry.mean(axis=1, keepdims=True)
    den = np.sqrt((rx * rx).sum(axis=1) * (ry * ry).sum(axis=1))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(den > 0, (rx * ry).sum(axis=1) / den, np.nan)
    return np.clip(r, -1.0, 1.0)


def kendall_b_rows(X, Y) -> np.ndarray:
    """Kendall's tau-b of each row pair: ``(n_c - n_d) / sqrt((n0 - n_x) (n0 - n_y))`` over all pairs
    ``i < j``, with ``n_x``, ``n_y`` the pairs tied in X, in Y. NaN for a constant row."""
    X, Y = np.asarray(X, dtype=float), np.asarray(Y, dtype=float)
    i, j = np.triu_indices(X.shape[1], 1)
    sx = np.sign(X[:, i] - X[:, j])
    sy = np.sign(Y[:, i] - Y[:, j])
    den = np.sqrt((sx != 0).sum(axis=1).astype(float) * (sy != 0).sum(axis=1))
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(den > 0, (sx * sy).sum(axis=1) / den, np.nan)
    return np.clip(t, -1.0, 1.0)


def replicates(X, Y) -> tuple[np.ndarray, np.ndarray]:
    """``(rho, tau_b)`` of every row pair of ``X``, ``Y`` (``(B, n)`` -> two ``(B,)``), in chunks of rows."""
    rho, tau = [], []
    for s in range(0, X.shape[0], _CHUNK):
        rho.append(spearman_rows(X[s:s + _CHUNK], Y[s:s + _CHUNK]))
        tau.append(kendall_b_rows(X[s:s + _CHUNK], Y[s:s + _CHUNK]))
    return np.concatenate(rho), np.concatenate(tau)


def percentile(values, alpha: float) -> tuple[float, float]:
    """The ``alpha / 2`` and ``1 - alpha / 2`` percentiles (``numpy.percentile``, linear) of the finite
    ``values``; NaN when there are none."""
    v = values[np.isfinite(values)]
    if v.size == 0:
        return (math.nan, math.nan)
    lo, hi = np.percentile(v, [100 * alpha / 2, 100 * (1 - alpha / 2)])
    return float(lo), float(hi)

