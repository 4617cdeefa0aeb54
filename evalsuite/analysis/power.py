"""Sample-size planning for the tests ``evalsuite analyze`` runs (``evalsuite study power``).

Every comparison is planned at Holm's strictest step, level ``alpha / K`` for ``K`` comparisons in the
family: a comparison that reaches the stated power there reaches it at every Holm step.

- **Pairwise preference** (:func:`binomial_power`, exact): judgements ``n`` (ties left out, as
  ``--tie-policy exclude`` does), ``k`` of them for A. The two-sided exact binomial test of
  ``H0: P(A) = 0.5`` has p-value ``min(1, 2 * min(F(k), F(n - k)))`` with ``F`` the Binomial(n, 0.5) CDF
  (what ``scipy.stats.binomtest`` gives for ``p = 0.5``); it rejects when that is ``<= level``.
  Power = ``sum over rejecting k of C(n, k) p^k (1 - p)^(n - k)`` for the true preference ``p``.
  The exact power is not monotone in ``n`` (a saw-tooth); :func:`pairwise_judgements` returns the
  smallest ``n`` reaching the target.
- **MUSHRA / 0-100 ratings** (:func:`mushra_power`, simulated): pages showing both conditions; ratings
  ``clip(round(50 +- d/2 + e), 0, 100)`` with ``e ~ Normal(0, sd)`` independent per rating (a participant's
  own offset cancels in the paired difference); two-sided Wilcoxon signed-rank test
  (``scipy.stats.wilcoxon``, zero differences dropped, as ``analyze`` does by default; its normal
  approximation with tie correction, since rounded ratings tie and the exact null is then unavailable).
- **Likert** (:func:`likert_power`, simulated): each statement ``clip(round(m +- d/2 + u + e), 1, points)``
  with ``m`` the scale's middle, ``u ~ Normal(0, sd)`` the participant's offset and ``e ~ Normal(0, sd)``
  per answer; the scale score is the mean over ``statements``. Participants rating both conditions: paired
  t-test (``scipy.stats.ttest_rel``); else one group per condition: Welch's t-test
  (``scipy.stats.ttest_ind(equal_var=False)``), as ``analyze``'s post-hoc tests.

Simulations are seeded (the same answer on every run) and use common random numbers across ``n``, so the
search for the smallest ``n`` (:func:`smallest_n`) sees a smooth curve.
"""
from __future__ import annotations

import math
import warnings
from collections.abc import Callable

import numpy as np
from scipy import stats

__all__ = ["binomial_power", "pairwise_judgements", "mushra_power", "likert_power", "smallest_n", "MAX_N"]

MAX_N = 100_000     # judgements per comparison: no plan needs more
MAX_SIMULATED = 5_000   # pages or participants searched by simulation


def _check(alpha: float, comparisons: int, power: float | None = None) -> float:
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be between 0 and 1, got {alpha}")
    if comparisons < 1:
        raise ValueError(f"comparisons must be at least 1, got {comparisons}")
    if power is not None and not 0 < power < 1:
        raise ValueError(f"power must be between 0 and 1, got {power}")
    return alpha / comparisons


def binomial_power(n: int, preference: float, level: float) -> float:
    """Power of the exact two-sided binomial test of ``P(A) = 0.5`` at ``level`` with ``n`` judgements whose
    true share for A is ``preference`` (module docstring)."""
    if n < 1:
        return 0.0
    k = np.arange(n + 1)
    tail = stats.binom.cdf(np.minimum(k, n - k), n, 0.5)
    pvalue = np.minimum(1.0, 2.0 * tail)
    reject = pvalue <= level * (1 + 1e-12)
    return float(stats.binom.pmf(k[reject], n, preference).sum())


def pairwise_judgements(preference: float, *, alpha: float = 0.05, power: float = 0.8,
                        comparisons: int = 1) -> tuple[int, float]:
    """``(n, achieved power)``: the fewest judgements (ties excluded) per comparison for which the exact
    binomial test at ``alpha / comparisons`` reaches ``power`` when A's true share is ``preference``."""
    level = _check(alpha, comparisons, power)
    if not 0 <= preference <= 1 or preference == 0.5:
        raise ValueError(f"preference must be a share of A other than 0.5 (no effect), got {preference}")
    # Start below the normal approximation's answer and walk up (the exact power is a saw-tooth).
    effect = abs(preference - 0.5)
    z = stats.norm.ppf(1 - level / 2) * 0.5 + stats.norm.ppf(power) * math.sqrt(preference * (1 - preference))
    start = max(1, int((z / effect) ** 2 * 0.7))
    for n in range(start, MAX_N + 1):
        achieved = binomial_power(n, preference, level)
        if achieved >= power:
            return n, achieved
    raise ValueError(f"more than {MAX_N:,} judgements per comparison; a preference of {preference} is too "
                     "close to 0.5 to plan for")


def mushra_power(n_pages: int, difference: float, sd: float, level: float, *, sims: int = 1000,
                 seed: int = 0) -> float:
    """Simulated power of the two-sided Wilcoxon signed-rank test at ``level`` on ``n_pages`` pages rating two
    conditions ``difference`` points apart (0-100 scale, rating noise ``sd``)."""
    if n_pages < 2:
        return 0.0
    noise = _columns(seed, n_pages, (2, sims)) * sd
    x = np.clip(np.round(50 + difference / 2 + noise[0]), 0, 100)
    y = np.clip(np.round(50 - difference / 2 + noise[1]), 0, 100)
    d = x - y
    usable = (d != 0).sum(axis=1) >= 1
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        p = stats.wilcoxon(x, y, axis=1, zero_method="wilcox", alternative="two-sided", method="asymptotic").pvalue
    return float(np.mean(usable & (np.nan_to_num(p, nan=1.0) <= level)))


def likert_power(n_participants: int, difference: float, sd: float, level: float, *, points: int = 7,
                 statements: int = 1, paired: bool = True, sims: int = 1000, seed: int = 0) -> float:
    """Simulated power at ``level`` for two conditions ``difference`` scale points apart (``points``-point
    items, ``statements`` per scale): the paired t-test on ``n_participants`` participants rating both
    (``paired``), else Welch's t-test on ``n_participants`` different participants per condition."""
    if n_participants < 2:
        return 0.0
    draws = _columns(seed, n_participants, (2 + 2 * statements, sims)) * sd
    offset_a, offset_b = draws[0], draws[0] if paired else draws[1]
    noise = draws[2:].reshape(2, statements, sims, n_participants)
    middle = (1 + points) / 2
    a = np.clip(np.round(middle + difference / 2 + offset_a + noise[0]), 1, points).mean(axis=0)
    b = np.clip(np.round(middle - difference / 2 + offset_b + noise[1]), 1, points).mean(axis=0)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)     # identical scores in a tiny simulated study
        p = (stats.ttest_rel(a, b, axis=1) if paired else stats.ttest_ind(a, b, axis=1, equal_var=False)).pvalue
    return float(np.mean(np.nan_to_num(p, nan=1.0) <= level))


def _columns(seed: int, n: int, shape: tuple[int, ...]) -> np.ndarray:
    """Standard normal draws of ``shape + (n,)``, column ``j`` from its own generator (seed, j): ``n`` and
    ``n + 1`` share their first ``n`` columns (common random numbers), so the simulated power curve over
    ``n`` is smooth and the search of :func:`smallest_n` is stable."""
    return np.stack([np.random.default_rng([seed, j]).standard_normal(shape) for j in range(n)], axis=-1)


def smallest_n(power_at: Callable[[int], float], target: float, *, low: int = 2,
               high: int = MAX_SIMULATED) -> tuple[int, float]:
    """``(n, power_at(n))`` for the smallest ``n`` in ``low..high`` with ``power_at(n) >= target``, by doubling
    then bisection (assumes power grows with ``n``, as the seeded simulations above do)."""
    n = low
    while power_at(n) < target:
        if n >= high:
            raise ValueError(f"more than {high:,} needed to reach power {target}; the effect is too small to plan "
                             "for with this design")
        n = min(high, n * 2)
    lo, hi = max(low, n // 2), n
    while lo < hi:
        mid = (lo + hi) // 2
        if power_at(mid) >= target:
            hi = mid
        else:
            lo = mid + 1
    return hi, power_at(hi)
