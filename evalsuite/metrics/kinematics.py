"""Average speed, acceleration and jerk of joints from finite differences of world positions.

For world positions ``x[t, j]`` (``(T, J, 3)``) sampled at ``fps``, the n-th derivative norm
of joint ``j`` at step ``t`` is

    d_n[t, j] = || Δ^n x[t, j] ||_2 · s^n,         Δ^n = np.diff(x, n, axis=0)

with ``s = fps`` (default convention, units/s^n), a fixed rate (GENEA 2020: 20, GENEA 2022: 30,
as hard-coded in their scripts) or ``s = 1`` (Aud2Repr2Pose: units/frame^n). The per-joint
average is the mean over the ``T - n`` steps. No smoothing, no central differences: finite
differences are exact for polynomials of degree n, so ``x = v t`` gives speed ``|v|`` and zero
acceleration, ``x = c t^3`` gives jerk ``6|c|``.

Summaries follow GENEA (``calk_jerk_or_acceleration.py``): per sequence the mean over joints;
per condition the mean and the std of those per-sequence values across sequences.
"""
from __future__ import annotations

import numpy as np
import numpy.typing as npt

from evalsuite.metrics._validate import positions_array, positive

__all__ = ["derivative_norms", "average_derivative_norm", "average_speed", "average_acceleration",
           "average_jerk", "sequence_means", "across_sequences"]

ORDERS = {"speed": 1, "acceleration": 2, "jerk": 3}


def derivative_norms(positions: npt.ArrayLike, order: int, fps: float | None = None) -> np.ndarray:
    """Per-step norms ``||Δ^n x[t, j]||_2 · fps^n``, shape ``(T - n, J)``.

    Args:
        positions: world positions ``(T, J, 3)`` with ``T > order``.
        order: 1 (speed), 2 (acceleration), 3 (jerk).
        fps: frames per second used for scaling; ``None`` leaves units per frame^n.
    """
    if order not in (1, 2, 3):
        raise ValueError(f"order must be 1, 2 or 3, got {order}")
    x = positions_array(positions, min_frames=order + 1)
    d = np.diff(x, n=order, axis=0)
    norms = np.sqrt(np.einsum("tjk,tjk->tj", d, d))
    if fps is not None:
        norms *= positive(fps, "fps") ** order
    return np.asarray(norms)


def average_derivative_norm(positions: npt.ArrayLike, order: int, fps: float | None = None) -> np.ndarray:
    """Mean over steps of :func:`derivative_norms`, one value per joint ``(J,)``."""
    return np.asarray(derivative_norms(positions, order, fps).mean(axis=0))


def average_speed(positions: npt.ArrayLike, fps: float | None) -> np.ndarray:
    """Average speed per joint ``mean_t ||x[t+1] - x[t]|| · fps`` (units/s; per frame if fps is None)."""
    return average_derivative_norm(positions, 1, fps)


def average_acceleration(positions: npt.ArrayLike, fps: float | None) -> np.ndarray:
    """Average acceleration per joint ``mean_t ||Δ² x[t]|| · fps²`` (GENEA "AA"; units/s²)."""
    return average_derivative_norm(positions, 2, fps)


def average_jerk(positions: npt.ArrayLike, fps: float | None) -> np.ndarray:
    """Average jerk per joint ``mean_t ||Δ³ x[t]|| · fps³`` (GENEA "AJ"; units/s³)."""
    return average_derivative_norm(positions, 3, fps)


def sequence_means(per_joint: npt.ArrayLike) -> np.ndarray:
    """Per-sequence value: mean over joints of a ``(S, J)`` table -> ``(S,)``."""
    table = np.asarray(per_joint, dtype=np.float64)
    if table.ndim != 2 or table.size == 0:
        raise ValueError(f"expected a non-empty (sequences, joints) table, got shape {table.shape}")
    return np.asarray(table.mean(axis=1))


def across_sequences(values: npt.ArrayLike, ddof: int = 1) -> tuple[float, float]:
    """Mean and std across sequences (std with ``ddof``; NaN when there are too few values)."""
    v = np.asarray(values, dtype=np.float64).ravel()
    v = v[np.isfinite(v)]
    if v.size == 0:
        return float("nan"), float("nan")
    std = float(np.std(v, ddof=ddof)) if v.size > ddof else float("nan")
    return float(v.mean()), std
