"""Errors against time-aligned ground truth: APE and MAE (Aud2Repr2Pose ``calc_errors.py``).

Generated and natural sequences are paired by name and truncated to the common length (as
every reference does); :func:`align_lengths` warns when the lengths differ by more than a
tolerance (1 s by default), since then the "time-aligned" assumption is doubtful.

    APE_j = mean_t || x̂[t, j] - x[t, j] ||_2                       (units)
    MAE_j = mean_t mean_{k in xyz} | x̂[t, j, k] - x[t, j, k] |     (units)

The per-sequence value is the mean over joints; the per-condition value is the mean (± std)
across sequences.
"""
from __future__ import annotations

import warnings

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError
from evalsuite.metrics._validate import positions_array

__all__ = ["LengthMismatchWarning", "align_lengths", "average_position_error", "mean_absolute_error"]


class LengthMismatchWarning(UserWarning):
    """Paired sequences differ in length by more than the tolerance; they were truncated."""


def align_lengths(generated: npt.ArrayLike, natural: npt.ArrayLike, fps: float, tolerance_s: float = 1.0,
                  name: str = "") -> tuple[np.ndarray, np.ndarray, float]:
    """Truncate two ``(T, J, 3)`` arrays to their common length; warn if they differ by > tolerance.

    Returns ``(generated[:T], natural[:T], difference_in_seconds)``.
    """
    a = positions_array(generated, "generated")
    b = positions_array(natural, "natural")
    if a.shape[1] != b.shape[1]:
        raise InputError(f"generated has {a.shape[1]} joints but natural has {b.shape[1]}", field="joints")
    diff_s = abs(len(a) - len(b)) / float(fps)
    if diff_s > tolerance_s:
        warnings.warn(f"{name + ': ' if name else ''}generated has {len(a)} frames and natural {len(b)} "
                      f"({diff_s:.2f} s apart, more than {tolerance_s:g} s); both truncated to "
                      f"{min(len(a), len(b))} frames", LengthMismatchWarning, stacklevel=2)
    n = min(len(a), len(b))
    return a[:n], b[:n], diff_s


def _pair(generated: npt.ArrayLike, natural: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    a = positions_array(generated, "generated")
    b = positions_array(natural, "natural")
    if a.shape != b.shape:
        raise InputError(f"generated {a.shape} and natural {b.shape} differ; truncate with align_lengths first",
                         field="shape")
    return a, b


def average_position_error(generated: npt.ArrayLike, natural: npt.ArrayLike) -> np.ndarray:
    """APE per joint ``(J,)``: mean over frames of the Euclidean distance to the natural joint."""
    a, b = _pair(generated, natural)
    d = a - b
    return np.asarray(np.sqrt(np.einsum("tjk,tjk->tj", d, d)).mean(axis=0))


def mean_absolute_error(generated: npt.ArrayLike, natural: npt.ArrayLike) -> np.ndarray:
    """MAE per joint ``(J,)``: mean over frames and the 3 coordinates of the absolute difference."""
    a, b = _pair(generated, natural)
    return np.asarray(np.abs(a - b).mean(axis=(0, 2)))
