"""Distribution distances and diversity without a learned extractor (GENEA Leaderboard family).

Poses are flattened to vectors ``p_t = x[t].ravel()`` (D = 3J).

* **FD_g** ("static FID", audio2photoreal): Fréchet distance between Gaussians fitted to all
  natural and all generated pose vectors (every frame of every sequence). Units²
* **FD_k** ("kinematic FID"): the same on frame differences ``p_{t+1} - p_t`` (no fps scaling,
  as the reference). Units²
* **L1div** (BEAT/EMAGE ``L1div``, leaderboard "Div_pose"): ``Σ_s Σ_t Σ_d |p_td - mean_t p_d|``
  over sequences, divided by the total number of frames. Units
* **Div_k** (leaderboard ``var_k``): per sequence the population variance over time of each
  dimension, averaged over dimensions and then over sequences. Units²

The Fréchet distance is :func:`evalsuite.metrics.frechet.frechet_distance` (symmetric eigen form).
For the scorer, which works file by file, sample sets are summarised by moments (count, mean,
scatter matrix) that combine exactly (Chan et al.'s pairwise update), so pooled covariances
never need all frames in memory.
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError
from evalsuite.metrics._validate import positions_array, samples_array
from evalsuite.metrics.frechet import FrechetWarning, frechet_distance, frechet_distance_samples

__all__ = ["fd_g", "fd_k", "l1div", "div_k", "moments", "combine_moments", "moments_covariance",
           "frechet_from_moments", "pose_vectors"]


# (count, mean (D,), scatter (D, D)) of a sample set
Moments = tuple[Any, np.ndarray, np.ndarray]


def pose_vectors(positions: npt.ArrayLike) -> np.ndarray:
    """``(T, J, 3)`` -> ``(T, 3J)`` pose vectors."""
    x = positions_array(positions)
    return x.reshape(len(x), -1)


def _sequences(seqs: Any, name: str) -> list[np.ndarray]:
    if isinstance(seqs, np.ndarray) and seqs.ndim == 3:
        seqs = [seqs]
    seqs = [pose_vectors(s) for s in seqs]
    if not seqs:
        raise InputError(f"{name}: no sequences", field=name)
    dims = {s.shape[1] for s in seqs}
    if len(dims) != 1:
        raise InputError(f"{name}: sequences have different joint counts ({sorted(d // 3 for d in dims)})",
                         field=name)
    return list(seqs)


def fd_g(natural: Any, generated: Any) -> float:
    """FD_g: Fréchet distance of raw pose vectors pooled over all frames (units²).

    ``natural``/``generated``: a ``(T, J, 3)`` array or a list of them (one per sequence).
    """
    a = np.concatenate(_sequences(natural, "natural"))
    b = np.concatenate(_sequences(generated, "generated"))
    if a.shape[1] != b.shape[1]:
        raise InputError(f"natural has {a.shape[1] // 3} joints, generated {b.shape[1] // 3}", field="joints")
    return frechet_distance_samples(a, b)


def fd_k(natural: Any, generated: Any) -> float:
    """FD_k: Fréchet distance of frame differences ``p_{t+1} - p_t`` pooled over sequences (units²)."""
    a = np.concatenate([np.diff(s, axis=0) for s in _sequences(natural, "natural")])
    b = np.concatenate([np.diff(s, axis=0) for s in _sequences(generated, "generated")])
    if a.shape[1] != b.shape[1]:
        raise InputError(f"natural has {a.shape[1] // 3} joints, generated {b.shape[1] // 3}", field="joints")
    return frechet_distance_samples(a, b)


def l1div_parts(positions: npt.ArrayLike) -> tuple[float, int]:
    """``(Σ_t Σ_d |p_td - mean_t p_d|, T)`` of one sequence (combine with :func:`l1div`)."""
    p = pose_vectors(positions)
    return float(np.abs(p - p.mean(axis=0)).sum()), len(p)


def l1div(sequences: Any) -> float:
    """L1 diversity: summed absolute deviation from each sequence's mean pose, per frame (units)."""
    parts = [l1div_parts(s) for s in _sequences_raw(sequences)]
    return sum(p[0] for p in parts) / sum(p[1] for p in parts)


def div_k_sequence(positions: npt.ArrayLike) -> float:
    """Mean over dimensions of the population variance over time of one sequence (units²)."""
    return float(np.var(pose_vectors(positions), axis=0).mean())


def div_k(sequences: Any) -> float:
    """Div_k (``var_k``): :func:`div_k_sequence` averaged over sequences (units²)."""
    return float(np.mean([div_k_sequence(s) for s in _sequences_raw(sequences)]))


def _sequences_raw(seqs: Any) -> list[Any]:
    if isinstance(seqs, np.ndarray) and seqs.ndim == 3:
        return [seqs]
    seqs = list(seqs)
    if not seqs:
        raise InputError("no sequences", field="sequences")
    return list(seqs)


# --- moments: exact, combinable summaries of sample sets ------------------------------------
def moments(samples: npt.ArrayLike) -> tuple[int, np.ndarray, np.ndarray]:
    """``(n, mean (D,), scatter (D, D))`` with scatter = Σ (x - mean)(x - mean)^T."""
    x = samples_array(samples, "samples")
    mean = x.mean(axis=0)
    c = x - mean
    return len(x), mean, c.T @ c


def combine_moments(parts: Iterable[Moments], weights: npt.ArrayLike | None = None) -> Moments:
    """Moments of the union of sample sets (``weights``: integer multiplicities, for bootstrap).

    Same as :func:`moments` of the concatenated samples, up to round-off; combining in a fixed
    order gives identical results however the parts were computed.
    """
    parts = list(parts)
    if not parts:
        raise ValueError("no moments to combine")
    w = np.ones(len(parts)) if weights is None else np.asarray(weights, dtype=np.float64)
    ns = np.array([p[0] for p in parts], dtype=np.float64) * w
    n = ns.sum()
    means = np.stack([p[1] for p in parts])
    mean = (ns[:, None] * means).sum(axis=0) / n
    dev = means - mean
    scatter = sum(wi * p[2] for wi, p in zip(w, parts) if wi) + (dev.T * ns) @ dev
    return n, mean, scatter


def moments_covariance(m: Moments) -> tuple[np.ndarray, np.ndarray]:
    """Mean and unbiased covariance (N - 1) from moments."""
    n, mean, scatter = m
    if n < 2:
        raise InputError(f"need at least 2 samples for a covariance, got {n}", field="samples")
    return mean, scatter / (n - 1)


def frechet_from_moments(m1: Moments, m2: Moments) -> float:
    """Fréchet distance between Gaussians given by two moment summaries (warns if N <= D)."""
    import warnings

    for m in (m1, m2):
        if m[0] <= len(m[1]):
            warnings.warn(f"{int(m[0])} samples for {len(m[1])} dimensions: the covariance is singular and the "
                          "Fréchet distance unreliable", FrechetWarning, stacklevel=2)
    mu1, s1 = moments_covariance(m1)
    mu2, s2 = moments_covariance(m2)
    return frechet_distance(mu1, s1, mu2, s2)
