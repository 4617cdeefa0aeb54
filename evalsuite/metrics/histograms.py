"""Histograms of joint speed/acceleration and the Hellinger distance between them.

Values are the per-step derivative norms of :mod:`evalsuite.metrics.kinematics`
(speed ``||Δx||·s``, acceleration ``||Δ²x||·s²``). A histogram per joint counts them in bins
``[e_k, e_{k+1})`` (the last bin closed, as ``np.histogram``); group histograms (e.g. wrists,
forearms, all joints pooled) are sums of joint histograms.

The reference scripts (GENEA ``calc_histogram.py``, Aud2Repr2Pose ``calc_distance.py``) silently
drop values above the last edge, and normalise over the kept ones only. Here every histogram
carries one extra column: the count above the last edge. With ``overflow=True`` (the default
convention) it is an ordinary bin in the normalisation; with ``overflow=False`` it is left out
(the references' numbers) and reported as the clipped fraction.

Hellinger distance (range [0, 1]):

    H(p, q) = sqrt(1 - Σ_i sqrt(p_i q_i)),   p = h1 / Σ h1,  q = h2 / Σ h2
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError

__all__ = ["joint_histograms", "histogram_counts", "clipped_fraction", "hellinger_distance",
           "hellinger_rows", "automatic_edges"]


def _check_edges(edges: npt.ArrayLike) -> np.ndarray:
    e = np.asarray(edges, dtype=np.float64)
    if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0) or not np.isfinite(e).all():
        raise InputError("histogram edges must be a 1-D increasing array of at least 2 values", field="bins")
    if e[0] > 0:
        raise InputError(f"histogram edges must start at 0 or below (norms are >= 0), got {e[0]}", field="bins")
    return e


def joint_histograms(values: npt.ArrayLike, edges: npt.ArrayLike) -> np.ndarray:
    """Counts per joint ``(J, B + 1)``: B bins of ``edges`` plus the count above the last edge.

    Args:
        values: non-negative values ``(N, J)`` (e.g. per-step speeds of J joints).
        edges: ``B + 1`` increasing edges starting at 0 or below.

    Bin k holds ``e_k <= v < e_{k+1}``, the last bin also ``v == e_B`` (``np.histogram``'s rule);
    column B holds ``v > e_B``. Vectorised with one ``searchsorted`` and one ``bincount``.
    """
    e = _check_edges(edges)
    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2:
        raise InputError(f"values must have shape (N, J), got {v.shape}", field="values")
    if not np.isfinite(v).all():
        raise InputError("values contain NaN or infinite values", field="values")
    n_bins = e.size - 1
    idx = np.searchsorted(e, v, side="right") - 1
    idx[v == e[-1]] = n_bins - 1
    if (idx < 0).any():
        raise InputError(f"values below the first edge {e[0]}", field="values")
    n_joints = v.shape[1]
    flat = idx + (n_bins + 1) * np.arange(n_joints)[None, :]
    return np.bincount(flat.ravel(), minlength=n_joints * (n_bins + 1)).reshape(n_joints, n_bins + 1)


def histogram_counts(counts: npt.ArrayLike, overflow: bool) -> np.ndarray:
    """The bins that take part in normalisation: all ``B + 1`` columns, or the first B."""
    c = np.asarray(counts)
    return c if overflow else c[..., :-1]


def clipped_fraction(counts: npt.ArrayLike) -> np.ndarray:
    """Fraction of values above the last edge (last column over the total), NaN if empty."""
    c = np.asarray(counts, dtype=np.float64)
    total = c.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total > 0, c[..., -1] / np.where(total > 0, total, 1), np.nan)


def hellinger_distance(h1: npt.ArrayLike, h2: npt.ArrayLike) -> float:
    """Hellinger distance ``sqrt(1 - Σ sqrt(p q))`` between two histograms (counts or masses).

    Each histogram is normalised to sum 1 first; the distance is computed as the equal
    ``sqrt(½ Σ (sqrt p_i - sqrt q_i)²)``, which has no round-off residue for identical
    histograms. Identical histograms give 0, histograms with disjoint support 1. NaN if
    either histogram is empty (sums to 0).
    """
    return float(hellinger_rows(np.atleast_2d(h1), np.atleast_2d(h2))[0])


def hellinger_rows(h1: npt.ArrayLike, h2: npt.ArrayLike) -> np.ndarray:
    """Row-wise Hellinger distance of two stacks of histograms ``(..., B)`` (broadcasting)."""
    a = np.asarray(h1, dtype=np.float64)
    b = np.asarray(h2, dtype=np.float64)
    if a.shape[-1] != b.shape[-1]:
        raise InputError(f"histograms have different numbers of bins: {a.shape[-1]} and {b.shape[-1]}",
                         field="bins")
    if (a < 0).any() or (b < 0).any():
        raise InputError("histograms must not have negative counts", field="bins")
    sa = a.sum(axis=-1, keepdims=True)
    sb = b.sum(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        # 1 - Σ sqrt(p q) = ½ Σ (sqrt p - sqrt q)²: the same number, but exactly 0 for identical
        # histograms (the first form leaves ~1e-8 after the square root of round-off).
        diff = np.sqrt(a / sa) - np.sqrt(b / sb)
        out = np.sqrt(np.clip(0.5 * np.sum(diff * diff, axis=-1), 0.0, 1.0))
    empty = (sa[..., 0] == 0) | (sb[..., 0] == 0)
    return np.where(empty, np.nan, out)


def automatic_edges(high_value: float, n_bins: int = 100) -> np.ndarray:
    """``n_bins`` equal bins from 0 to ``nice_ceil(high_value)`` (the default convention)."""
    from evalsuite.metrics.conventions import nice_ceil

    top = nice_ceil(high_value)
    return np.linspace(0.0, top, n_bins + 1)
