"""Joint rotations of a BVH motion as rotation vectors (axis-angle, radians), and back; blending two poses.

Operators that are defined on axis-angle poses (the GENEA Leaderboard's synthetic degradations) or that
cross-fade two clips (slerp) work through these: :func:`rotation_vectors` reads every joint that has three
distinct rotation channels, :func:`with_rotation_vectors` writes them back as Euler angles in each joint's
own channel order, leaving position channels untouched.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from evalsuite.errors import MotionError
from evalsuite.motion.motion import Motion

__all__ = ["rotation_joints", "rotation_vectors", "with_rotation_vectors", "blend_values"]


def rotation_joints(motion: Motion) -> list[tuple[int, list[int], str]]:
    """``(joint, value columns, axes)`` of every joint with three distinct rotation channels, in file order."""
    if not motion.is_hierarchical:
        raise MotionError("this motion holds positions only; it has no joint rotations")
    sk = motion.skeleton
    out = []
    for j, chans in enumerate(sk.channels):
        idx = [i for i, c in enumerate(chans) if c.endswith("rotation")]
        axes = "".join(chans[i][0] for i in idx)
        if len(axes) == 3 and len(set(axes)) == 3:
            out.append((j, [int(sk.channel_starts[j]) + i for i in idx], axes))
    return out


def rotation_vectors(motion: Motion) -> np.ndarray:
    """``(T, R, 3)`` rotation vectors (radians) of the :func:`rotation_joints`, from the intrinsic Euler
    channels (BVH's convention: upper-case axes in scipy)."""
    joints = rotation_joints(motion)
    out = np.empty((motion.n_frames, len(joints), 3))
    for r, (_, cols, axes) in enumerate(joints):
        out[:, r] = Rotation.from_euler(axes.upper(), motion.values[:, cols], degrees=True).as_rotvec()
    return out


def with_rotation_vectors(motion: Motion, rotvecs: np.ndarray, values: np.ndarray | None = None) -> Motion:
    """``motion`` with its rotation channels set from ``rotvecs`` ``(T, R, 3)``; other channels from
    ``values`` (default: the motion's own)."""
    joints = rotation_joints(motion)
    rv = np.asarray(rotvecs, dtype=np.float64)
    base = motion.values if values is None else np.asarray(values, dtype=np.float64)
    if rv.shape[1:] != (len(joints), 3) or len(rv) != len(base):
        raise MotionError(f"rotation vectors of shape {rv.shape} do not fit {len(base)} frames x {len(joints)} joints")
    out = base.copy()
    for r, (_, cols, axes) in enumerate(joints):
        out[:, cols] = Rotation.from_rotvec(rv[:, r]).as_euler(axes.upper(), degrees=True)
    return motion.with_values(out)


def blend_values(motion: Motion, a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Channel values ``(T, C)`` blending frames ``a`` into ``b`` with weights ``w`` ``(T,)`` in [0, 1]:
    spherical linear interpolation (slerp) per joint rotation, linear for position channels."""
    joints = rotation_joints(motion)
    w = np.clip(np.asarray(w, dtype=np.float64), 0.0, 1.0)
    out: np.ndarray = a * (1 - w)[:, None] + b * w[:, None]
    for _, cols, axes in joints:
        ra = Rotation.from_euler(axes.upper(), a[:, cols], degrees=True)
        rb = Rotation.from_euler(axes.upper(), b[:, cols], degrees=True)
        # slerp(a, b, w) = a * exp(w * log(a^-1 b)), frame by frame
        delta = (ra.inv() * rb).as_rotvec()
        out[:, cols] = (ra * Rotation.from_rotvec(delta * w[:, None])).as_euler(axes.upper(), degrees=True)
    return out
