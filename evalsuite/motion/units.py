"""A guess of a motion's length unit from the figure's height (BVH files do not say)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

# Plausible adult figure heights (full body) in each unit; upper-body skeletons are shorter,
# so the ranges are wide and the answer is only a guess.
_RANGES = [
    ("metres", 0.4, 2.6),
    ("inches", 25.0, 90.0),
    ("centimetres", 90.0, 260.0),
    ("millimetres", 400.0, 2600.0),
]

if TYPE_CHECKING:
    from evalsuite.motion.motion import Motion


def figure_height(positions: np.ndarray, up_axis: int = 1) -> float:
    """Median over frames of the vertical extent of all joints."""
    if positions.size == 0:
        return 0.0
    extent = positions[..., up_axis].max(axis=1) - positions[..., up_axis].min(axis=1)
    return float(np.median(extent))


def guess_units(motion: Motion, up_axis: int = 1) -> str:
    """E.g. ``"centimetres (figure height 172.3 units, Y up)"``."""
    pos = motion.positions()[:: max(1, motion.n_frames // 200)]
    height = figure_height(pos, up_axis)
    axis = "XYZ"[up_axis]
    for unit, low, high in _RANGES:
        if low <= height < high:
            return f"{unit} (figure height {height:.4g} units, {axis} up)"
    return f"unknown (figure height {height:.4g} units, {axis} up)"
