"""FGD and the number of windows it is computed from (Chong & Forsyth, "Effectively Unbiased FID and
Inception Score and where to find them", CVPR 2020).

The Fréchet distance of Gaussians fitted to ``N`` samples is biased upwards, and the bias shrinks like
``1/N``: for two samples of sizes ``N_1 = N_2 = N``, ``E[FD_N] = FD_∞ + c / N + o(1/N)`` (the mean term
alone adds ``tr(S_1 + S_2) / N``). FGDs computed from different numbers of windows are therefore not
comparable. Two remedies:

* :func:`fgd_at_n`: FGD at a fixed ``N`` — ``N`` windows drawn from each side, ``draws`` times (an
  m-out-of-n bootstrap: without replacement when the side has at least ``N`` windows, so each draw is a
  sample of ``N`` windows of the same distribution), the mean over draws and the 2.5-97.5 percentiles;
* :func:`fgd_infinity`: ``FGD_∞`` — FGD at several ``N`` (``points`` sizes evenly spaced from
  ``N_max / 5`` to ``N_max`` = the smaller side, each the mean of ``draws`` draws without replacement),
  fitted by least squares to ``FGD_N = FGD_∞ + b / N``; the intercept is the estimate, with the 95 %
  interval of the fit (t distribution, ``points - 2`` degrees of freedom).

Windows of one sequence are correlated; draws are of windows, as in the references' FGD.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from scipy import stats

from evalsuite.errors import InputError
from evalsuite.learned.fgd import batched_frechet_distance

__all__ = ["draw_fds", "fgd_at_n", "fgd_infinity", "n_grid"]

_CHUNK = 8_000_000   # largest draws x N x D block held at once (floats)


def _batched_stats(x: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Means ``(B, D)`` and unbiased covariances ``(B, D, D)`` of ``x[idx[b]]`` (``idx (B, N)``)."""
    sub = x[idx]                                        # (B, N, D)
    mu = sub.mean(axis=1)
    c = sub - mu[:, None]
    return mu, np.einsum("bnd,bne->bde", c, c) / (idx.shape[1] - 1)


def draw_fds(reference: np.ndarray, condition: np.ndarray, n: int, draws: int,
             rng: np.random.Generator) -> tuple[np.ndarray, bool]:
    """FDs ``(draws,)`` between Gaussians of ``n`` rows drawn from ``reference (N_r, D)`` and from
    ``condition (N_c, D)``; without replacement where a side has at least ``n`` rows. Also returns
    whether a side had to be drawn with replacement."""
    ref, cond = np.asarray(reference, dtype=np.float64), np.asarray(condition, dtype=np.float64)
    if n < 2:
        raise InputError(f"FGD at N needs N >= 2 windows, got {n}", field="fgd-n")
    replace = n > len(ref) or n > len(cond)
    step = max(1, _CHUNK // max(1, n * ref.shape[1]))
    out = []
    for start in range(0, draws, step):
        b = min(step, draws - start)
        sides = []
        for x in (ref, cond):
            if n > len(x):
                idx = rng.integers(0, len(x), size=(b, n))
            else:
                idx = np.argsort(rng.random((b, len(x))), axis=1)[:, :n]
            sides.append(_batched_stats(x, idx))
        out.append(batched_frechet_distance(sides[0][0], sides[0][1], sides[1][0], sides[1][1]))
    return np.concatenate(out), replace


def fgd_at_n(reference: np.ndarray, condition: np.ndarray, n: int, *, draws: int = 200,
             seed: int = 0) -> dict[str, float]:
    """FGD at ``n`` windows per side: ``value`` (mean over draws), ``ci_low``/``ci_high`` (2.5 and 97.5
    percentiles of the draws), ``std``, ``n``, ``draws`` and ``with_replacement`` (1 when a side has fewer
    than ``n`` windows: those draws repeat windows, and the value is biased up further)."""
    fds, replace = draw_fds(reference, condition, int(n), int(draws), np.random.default_rng(seed))
    lo, hi = np.percentile(fds, [2.5, 97.5])
    return {"value": float(fds.mean()), "ci_low": float(lo), "ci_high": float(hi), "std": float(fds.std(ddof=1)),
            "n": int(n), "draws": int(draws), "with_replacement": float(replace)}


def n_grid(n_max: int, dim: int, points: int = 10) -> np.ndarray:
    """``points`` sizes evenly spaced from ``max(N_max / 5, 2 (D + 1))`` to ``N_max`` (distinct integers).
    Below about ``2 D`` windows the covariance is near singular and the bias is no longer linear in ``1/N``."""
    low = max(n_max // 5, 2 * (dim + 1))
    if n_max < low + points:
        raise InputError(f"FGD∞ needs more windows: {n_max} on the smaller side for {dim} feature dimensions "
                         f"(at least {low + points}); use longer or more sequences", field="fgd")
    return np.unique(np.round(np.linspace(low, n_max, points)).astype(int))


def fgd_infinity(reference: np.ndarray, condition: np.ndarray, *, points: int = 10, draws: int = 20,
                 seed: int = 0, ns: np.ndarray | None = None) -> dict[str, Any]:
    """``FGD_∞``: intercept of the least-squares line ``FGD_N = a + b / N`` over the sizes ``ns`` (default
    :func:`n_grid`), each ``FGD_N`` the mean of ``draws`` draws without replacement. Returns ``value`` (a),
    ``slope`` (b), ``ci_low``/``ci_high`` (95 % interval of a from the fit), ``ns``, ``fgd_n`` (the means)
    and ``draws`` (``(len(ns), draws)``)."""
    ref, cond = np.asarray(reference, dtype=np.float64), np.asarray(condition, dtype=np.float64)
    sizes = n_grid(min(len(ref), len(cond)), ref.shape[1], points) if ns is None else np.asarray(ns, dtype=int)
    rng = np.random.default_rng(seed)
    per_n = np.stack([draw_fds(ref, cond, int(n), draws, rng)[0] for n in sizes])   # (P, draws)
    means = per_n.mean(axis=1)
    x = 1.0 / sizes
    design = np.stack([np.ones_like(x), x], axis=1)
    coef, *_ = np.linalg.lstsq(design, means, rcond=None)
    dof = len(sizes) - 2
    if dof > 0:
        resid = means - design @ coef
        cov = np.linalg.inv(design.T @ design) * float(resid @ resid) / dof
        half = float(stats.t.ppf(0.975, dof) * np.sqrt(cov[0, 0]))
    else:
        half = float("nan")
    return {"value": float(coef[0]), "slope": float(coef[1]), "ci_low": float(coef[0] - half),
            "ci_high": float(coef[0] + half), "ns": sizes, "fgd_n": means, "draws": per_n}
