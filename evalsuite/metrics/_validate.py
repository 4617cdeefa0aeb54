"""Input checks shared by the metric functions (the API boundary)."""
from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError


def positions_array(positions: npt.ArrayLike, name: str = "positions", min_frames: int = 1) -> np.ndarray:
    """A finite float64 array ``(T, J, 3)`` with at least ``min_frames`` frames."""
    try:
        arr = np.asarray(positions, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a numeric array of shape (T, J, 3)", field=name) from None
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise InputError(f"{name} must have shape (T, J, 3), got {arr.shape}", field=name)
    if arr.shape[0] < min_frames:
        raise InputError(f"{name} needs at least {min_frames} frames, got {arr.shape[0]}", field=name)
    if not np.isfinite(arr).all():
        raise InputError(f"{name} contains NaN or infinite values", field=name)
    return arr


def samples_array(x: npt.ArrayLike, name: str, min_rows: int = 1) -> np.ndarray:
    """A finite float64 array ``(N, D)``."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a numeric array of shape (N, D)", field=name) from None
    if arr.ndim != 2:
        raise InputError(f"{name} must have shape (N, D), got {arr.shape}", field=name)
    if arr.shape[0] < min_rows:
        raise InputError(f"{name} needs at least {min_rows} rows, got {arr.shape[0]}", field=name)
    if not np.isfinite(arr).all():
        raise InputError(f"{name} contains NaN or infinite values", field=name)
    return arr


def positive(value: object, name: str) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]  # anything float() takes; the rest is reported below
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a positive number, got {value!r}", field=name) from None
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name} must be a positive number, got {value!r}", field=name)
    return v
