"""Per-dimension pose scaling with a relative floor, shared by the re-implementations.

Each seed paper normalises every pose dimension to itself: Gesticulator and Ferstl et al. to unit variance,
"Moving fast and slow" and Gesture2Vec to a maximum absolute value of 1. On a skeleton where some channels
hardly move (a spine's idle sway of 0.01 rad, breathing, rounding in a held joint) that stretches their
noise to the size of an arm's gestures, and the mean squared error, summed over dimensions, then spends most
of its weight on motion that is neither visible nor predictable from speech. Measured on the synthetic
speaker (docs/generators.md): Aud2Pose's held-out pose error fell from 1.03 to 0.64 x the mean pose's when
the sway stopped dominating its loss.

:func:`floored_spread` keeps each dimension's own spread (std or max |x - mean|) but never lets it fall
below ``floor`` x the widest dimension's, so every dimension that moves like a limb is scaled as the paper
scales it, and a nearly still one keeps its small size. ``floor = 0`` is the papers' normalisation.
"""
from __future__ import annotations

import numpy as np

__all__ = ["floored_spread", "DEFAULT_FLOOR", "FLOOR_OPTION", "FLOOR_DEVIATION"]

DEFAULT_FLOOR = 0.1
FLOOR_OPTION = ("a pose dimension's scale is at least this fraction of the widest dimension's (default 0.1), so "
                "channels that hardly move (idle sway) are not stretched to the size of an arm's gestures; 0: "
                "every dimension scaled to itself, the paper's")
FLOOR_DEVIATION = ("Pose dimensions are scaled with a floor of scale_floor (0.1) x the widest dimension's spread, so "
                   "that channels which hardly move (idle sway) do not weigh as much as the arms in the loss; the "
                   "paper scales every dimension to itself (scale_floor=0).")


def floored_spread(spread: np.ndarray, floor: float) -> np.ndarray:
    """``(D,)`` spread -> ``max(spread, floor * max(spread), 1e-6)``.

    ``spread``: per-dimension standard deviation or maximum absolute deviation; ``floor`` in [0, 1)."""
    s = np.asarray(spread, dtype=np.float64)
    if not 0.0 <= float(floor) < 1.0:
        raise ValueError(f"scale_floor must be in [0, 1), got {floor}")
    top = float(s.max()) if s.size else 0.0
    return np.maximum(s, max(float(floor) * top, 1e-6))


