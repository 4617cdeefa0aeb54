"""Smoothing filters of the seed papers, on arrays ``(T, ...)`` and on motions.

``moving_average`` (window 5), ``savgol`` (Savitzky-Golay, 9 frames, order 3 as in the GENEA
2023 baseline) and ``one_euro`` (Casiez et al. 2012). Filters run along axis 0 (frames).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.ndimage import uniform_filter1d
from scipy.signal import savgol_filter

from evalsuite.errors import MotionError

__all__ = ["moving_average", "savgol", "one_euro", "smooth", "FILTERS"]

if TYPE_CHECKING:
    from evalsuite.motion.motion import Motion


def moving_average(x: np.ndarray, window: int = 5) -> np.ndarray:
    """Centred moving average over ``window`` frames; edges repeat the first/last frame."""
    if window < 1:
        raise MotionError(f"window must be >= 1, got {window}")
    return np.asarray(uniform_filter1d(np.asarray(x, dtype=np.float64), size=window, axis=0, mode="nearest"))


def savgol(x: np.ndarray, window: int = 9, order: int = 3) -> np.ndarray:
    """Savitzky-Golay filter (least-squares polynomial of ``order`` over ``window`` frames)."""
    x = np.asarray(x, dtype=np.float64)
    if window % 2 == 0 or window <= order:
        raise MotionError(f"savgol needs an odd window larger than the order, got window={window}, order={order}")
    if len(x) < window:
        raise MotionError(f"savgol window {window} is longer than the motion ({len(x)} frames)")
    return np.asarray(savgol_filter(x, window, order, axis=0, mode="interp"))


def _alpha(cutoff: Any, fps: float) -> Any:
    tau = 1.0 / (2 * np.pi * cutoff)
    return 1.0 / (1.0 + tau * fps)


def one_euro(x: np.ndarray, fps: float, min_cutoff: float = 1.0, beta: float = 0.0,
             d_cutoff: float = 1.0) -> np.ndarray:
    """One-Euro filter: a low-pass whose cutoff rises with speed (``min_cutoff + beta*|dx|``).

    The filter is recursive with a data-dependent coefficient, so it steps through frames;
    each step is vectorised over all joints and coordinates.
    """
    x = np.asarray(x, dtype=np.float64)
    if len(x) == 0:
        return np.asarray(x.copy())
    out = np.empty_like(x)
    out[0] = x[0]
    dx_prev = np.zeros_like(x[0])
    a_d = _alpha(d_cutoff, fps)
    for t in range(1, len(x)):  # inherent recursion over time; vectorised over joints
        dx = (x[t] - out[t - 1]) * fps
        dx_hat = a_d * dx + (1 - a_d) * dx_prev
        cutoff = min_cutoff + beta * np.abs(dx_hat)
        a = _alpha(cutoff, fps)
        out[t] = a * x[t] + (1 - a) * out[t - 1]
        dx_prev = dx_hat
    return out


FILTERS: dict[str, Callable[..., np.ndarray]] = {"moving_average": moving_average, "savgol": savgol,
                                                  "one_euro": one_euro}


def smooth(motion: Motion, method: str = "moving_average", **params: Any) -> Motion:
    """Smooth a motion with one of :data:`FILTERS`.

    A BVH motion is smoothed on its channels (rotation angles unwrapped first, so a jump
    from 179 to -179 degrees is not averaged through 0) and stays a BVH motion; a
    positions motion is smoothed on its positions.
    """
    if method not in FILTERS:
        raise MotionError(f"unknown smoothing method {method!r}; expected one of {', '.join(FILTERS)}")
    func = FILTERS[method]
    if method == "one_euro":
        params.setdefault("fps", motion.fps)
    if motion.is_hierarchical:
        values = motion.values.copy()
        rot_cols = [i for i, name in enumerate(motion.skeleton.channel_names()) if name.endswith("rotation")]
        if rot_cols:
            values[:, rot_cols] = np.unwrap(values[:, rot_cols], period=360.0, axis=0)
        return motion.with_values(func(values, **params))
    return motion.with_positions(func(motion.positions(), **params))
