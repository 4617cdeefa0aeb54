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
distance is unreliable: a :class:`FrechetWarning` says so.
"""
from __future__ import annotations

import warnings

import numpy as np
import numpy.typing as npt

__all__ = ["FrechetWarning", "gaussian_stats", "frechet_distance", "frechet_distance_details",
           "frechet_distance_samples"]


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
