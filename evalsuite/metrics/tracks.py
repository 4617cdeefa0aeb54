"""Per-sequence data for figures (not metrics): where the wrists are over time."""
from __future__ import annotations

from typing import Any

import numpy as np

from evalsuite.metrics.planning import find_group

__all__ = ["wrist_track"]


def wrist_track(motion: Any) -> tuple[np.ndarray, float] | None:
    """Wrist positions ``(T', W, 3)`` relative to the root's ground-plane position, about 10 per second,
    and their rate; None when the skeleton has no wrist-like joints. (Y-up: the height is kept.)"""
    wrists = find_group("wrists", motion.joint_names)
    if not wrists:
        return None
    fps = motion.fps
    pos = motion.positions()
    roots = np.flatnonzero(motion.parents < 0)
    root = pos[:, roots[0] if roots.size else 0].copy()
    root[:, 1] = 0.0  # keep height; remove travel on the ground plane
    idx = [motion.joint_names.index(w) for w in wrists]
    step = max(1, int(round(fps / 10.0)))
    return (pos[::step, idx] - root[::step, None, :]).astype(np.float32), fps / step
