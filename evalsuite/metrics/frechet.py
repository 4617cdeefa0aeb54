"""Fréchet distance between Gaussians fitted to two sample sets (FD_g, FD_k, FGD).

    FD = ||mu_1 - mu_2||^2 + tr(S_1) + tr(S_2) - 2 tr( (S_1^{1/2} S_2 S_1^{1/2})^{1/2} )

The reference code (pytorch-fid / TTUR, copied into every gesture repository) computes the
last term with ``scipy.linalg.sqrtm(S_1 S_2, disp=False)``: the product is not symmetric,
the result can be complex, and ``disp`` is deprecated in SciPy 1.17 and removed in 1.18.
Here the trace comes from the *symmetric* form: ``S_1^{1/2}`` by an eigendecomposition of
the symmetric PSD ``S_1`` (negative round-off eigenvalues clipped to 0), then the
eigenvalues of the symmetric PSD ``S_1^{1/2} S_2 S_1^{1/2}`` (clipped likewise), whose square
roots sum to the trace. ``tr sqrt(S_1 S_2)`` equals this exactly in exact arithmetic (the two
products are similar matrices). The result is clipped at 0 (identical sets give tiny
negatives in the references, e.g. GENEA 2022's ``-0.012``); the unclipped value is
available from :func:`frechet_distance_details`.

Covariances are the unbiased sample covariances (``np.cov(rowvar=False)``, N-1), as in the
references. With no more samples than dimensions the covariance is singular and the
distance is unreliable: a :class:`FrechetWarning` says so. :func:`sample_size_warnings` is the
one rule, shared by ``evalsuite score`` and ``evalsuite fgd check``, for samples too small for a
trustworthy distance.

For many pairs (the bootstrap), :func:`trace_sqrt_product` takes the trace term from a Cholesky
factor ``S_1 = L L^T`` instead: ``L^T S_2 L = L^{-1} (S_1 S_2) L`` is similar to ``S_1 S_2``, so its
(symmetric) eigenvalues are the same, at a fraction of the cost of the eigendecomposition.
"""
from __future__ import annotations

import warnings

import numpy as np
import numpy.typing as npt

__all__ = ["FrechetWarning", "gaussian_stats", "frechet_distance", "frechet_distance_details",
           "frechet_distance_samples", "trace_sqrt_product", "sample_size_warnings", "min_samples",
           "MIN_SEQUENCES", "BIAS_FRACTION"]

# The small-sample rule (see sample_size_warnings)
BIAS_FRACTION = 0.05   # largest tolerated FD between two samples of one distribution, as a share of tr S
MIN_SEQUENCES = 10     # fewest sequences per side: the sequence is the sampling (and bootstrap) unit


class FrechetWarning(UserWarning):
    """The Fréchet distance is computed but may be unreliable (too few samples)."""


def gaussian_stats(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean ``(D,)`` and unbiased covariance ``(D, D)`` of samples ``(N, D)``."""
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim != 2:
        raise ValueError(f"samples must have shape (N, D), got {x.shape}")
    n, d = x.shape
    if n < 2:
        raise ValueError(f"need at least 2 samples to estimate a covariance, got {n}")
    if not np.isfinite(x).all():
        raise ValueError("samples contain NaN or infinite values")
    if n <= d:
        warnings.warn(f"{n} samples for {d} dimensions: the covariance is singular and the Fréchet "
                      "distance unreliable; use more samples or fewer dimensions", FrechetWarning, stacklevel=2)
    return x.mean(axis=0), np.atleast_2d(np.cov(x, rowvar=False))


def _psd_sqrt(s: np.ndarray) -> np.ndarray:
    s = (s + s.T) / 2
    w, v = np.linalg.eigh(s)
    return np.asarray((v * np.sqrt(np.clip(w, 0.0, None))) @ v.T)


def frechet_distance_details(mu1: npt.ArrayLike, sigma1: npt.ArrayLike, mu2: npt.ArrayLike, sigma2: npt.ArrayLike) -> dict[str, float]:
    """The distance and its parts: ``mean_term``, ``trace_term``, ``raw`` (unclipped), ``value``."""
    mu1, mu2 = np.atleast_1d(np.asarray(mu1, float)), np.atleast_1d(np.asarray(mu2, float))
    s1, s2 = np.atleast_2d(np.asarray(sigma1, float)), np.atleast_2d(np.asarray(sigma2, float))
    d = mu1.shape[0]
    if mu2.shape != (d,) or s1.shape != (d, d) or s2.shape != (d, d):
        raise ValueError(f"shapes do not match: mu1 {mu1.shape}, sigma1 {s1.shape}, mu2 {mu2.shape}, "
                         f"sigma2 {s2.shape}")
    root1 = _psd_sqrt(s1)
    inner = root1 @ s2 @ root1
    eig = np.linalg.eigvalsh((inner + inner.T) / 2)
    tr_covmean = float(np.sum(np.sqrt(np.clip(eig, 0.0, None))))
    diff = mu1 - mu2
    mean_term = float(diff @ diff)
    trace_term = float(np.trace(s1) + np.trace(s2) - 2.0 * tr_covmean)
    raw = mean_term + trace_term
    return {"mean_term": mean_term, "trace_term": trace_term, "raw": raw, "value": max(raw, 0.0)}


def frechet_distance(mu1: npt.ArrayLike, sigma1: npt.ArrayLike, mu2: npt.ArrayLike, sigma2: npt.ArrayLike) -> float:
    """Fréchet distance between ``N(mu1, sigma1)`` and ``N(mu2, sigma2)`` (>= 0)."""
    return frechet_distance_details(mu1, sigma1, mu2, sigma2)["value"]


def frechet_distance_samples(x: np.ndarray, y: np.ndarray) -> float:
    """Fréchet distance between Gaussians fitted to samples ``x (N, D)`` and ``y (M, D)``."""
    return frechet_distance(*gaussian_stats(x), *gaussian_stats(y))


def trace_sqrt_product(s1: np.ndarray, s2: np.ndarray) -> float:
    """``tr (S_1 S_2)^{1/2}`` (``S (D, D)`` PSD) from the eigenvalues of ``L^T S_2 L`` (``S_1 = L L^T``, similar to
    ``S_1 S_2``); with the PSD square root of :func:`frechet_distance_details` when ``S_1`` is not positive
    definite (Cholesky fails). Negative round-off eigenvalues are clipped to 0."""
    s1 = (s1 + s1.T) / 2
    try:
        low = np.linalg.cholesky(s1)
        inner = low.T @ s2 @ low
    except np.linalg.LinAlgError:
        root = _psd_sqrt(s1)
        inner = root @ s2 @ root
    eig = np.linalg.eigvalsh((inner + inner.T) / 2)
    return float(np.sum(np.sqrt(np.clip(eig, 0.0, None))))


def min_samples(dim: int) -> int:
    """Fewest samples per side for :func:`sample_size_warnings`'s bias limit: ``10 (D + 5)``."""
    return int(np.ceil((dim + 5) / (2 * BIAS_FRACTION)))


def sample_size_warnings(n_samples: tuple[float, float], dim: int, n_sequences: tuple[int, int] | None = None,
                         what: str = "samples") -> list[str]:
    """Why a Fréchet distance between samples of these sizes is not to be trusted ([] when it is).

    ``n_samples``: samples (frames, windows) of the reference and of the condition; ``dim``: ``D``;
    ``n_sequences``: the sequences they come from. Three rules:

    * ``N <= D`` on a side: its covariance is singular;
    * two independent samples of sizes ``N_1``, ``N_2`` of one and the same Gaussian ``N(mu, s^2 I)`` are
      expected to lie ``E[FD] ~ (1/N_1 + 1/N_2) (D + 5) / 4 * tr S`` apart (mean term ``tr S (1/N_1 +
      1/N_2)``, covariance term ``~ ||S_1 - S_2||_F^2 / 4``): warn when that exceeds
      ``BIAS_FRACTION`` (5 %) of ``tr S``, i.e. below ``10 (D + 5)`` samples per side for equal sizes
      (:func:`min_samples`). Correlated samples (frames of one take) make it worse, never better;
    * fewer than ``MIN_SEQUENCES`` (10) sequences on a side: frames and windows of one sequence are
      correlated, so the effective sample is nearer the number of sequences; a bootstrap resample of
      ``n`` sequences holds on average ``n (1 - (1 - 1/n)^n)`` distinct ones (3.4 of 5), so resampled
      distances carry a larger small-sample bias than the estimate.
    """
    out = []
    n1, n2 = (float(n) for n in n_samples)
    singular = [f"{n:g}" for n in (n1, n2) if n <= dim]
    if singular:
        out.append(f"{' and '.join(singular)} {what} for {dim} dimensions: the covariance is singular and the "
                   "Fréchet distance unreliable")
    expected = (1.0 / n1 + 1.0 / n2) * (dim + 5) / 4.0
    if expected > BIAS_FRACTION:
        out.append(f"{n1:g} reference and {n2:g} condition {what} for {dim} dimensions: two samples this small of "
                   f"one and the same distribution lie about {expected:.0%} of its total variance apart (the "
                   f"Fréchet distance's small-sample bias, (1/N1 + 1/N2)(D + 5)/4); use at least "
                   f"{min_samples(dim)} {what} per side for under {BIAS_FRACTION:.0%}")
    if n_sequences is not None and min(n_sequences) < MIN_SEQUENCES:
        n = min(n_sequences)
        distinct = n * (1 - (1 - 1 / n) ** n)
        out.append(f"{n} sequence(s) on a side (fewer than {MIN_SEQUENCES}): frames of one sequence are correlated, "
                   f"so the sample is effectively nearer {n} than its {what}, and a bootstrap resample holds on "
                   f"average only {distinct:.1f} distinct sequences (its distance is biased upwards more than the "
                   "estimate)")
    return out
