"""The synthetic speaker's body: an upper-body humanoid, its arm poses, and keyframe tracks.

The skeleton is the first 16 joints of :func:`evalsuite.motion.synthetic.humanoid_skeleton` (``Hips``,
``Spine``..``Spine3``, ``Neck``, ``Neck1``, ``Head``, ``Right``/``Left`` ``Shoulder``, ``Arm``,
``ForeArm``, ``Hand``; centimetres, +y up, +z forward), so the GENEA 2020 presets apply. Arm poses are
four channel angles of the right arm (``Arm`` Z, X, Y rotation and ``ForeArm`` Y rotation = elbow
flexion, degrees, ZXY order); the left arm is the mirror image (Z and Y negated). The poses were solved
once for hand and elbow targets by least squares on forward kinematics (hand positions in the comments,
relative to the hips' floor projection).
"""
from __future__ import annotations

import numpy as np

from evalsuite.motion.skeleton import Skeleton
from evalsuite.motion.synthetic import humanoid_skeleton

__all__ = ["upper_body_skeleton", "POSES", "Track", "min_jerk", "ARM_CHANNELS", "channel_index"]

# (Arm Z, Arm X, Arm Y, ForeArm Y) of the right arm.
POSES: dict[str, tuple[float, float, float, float]] = {
    "rest": (86.7, 10.8, -5.4, 59.8),       # hand (-17, 100, 17): in front of the hip
    "ready": (79.6, 5.5, 16.3, 69.4),       # (-20, 114, 33): gesture space, before a beat
    "beat": (78.8, 10.6, 15.1, 47.4),       # (-20, 104, 29): end of a beat's downward stroke
    "up": (-19.4, -61.3, 37.4, 64.4),       # (-22, 183, 20): hand raised above the head
    "wide": (32.0, -29.9, 5.4, 30.0),       # (-63, 125, 15): arm out to the side
    "self": (77.9, 50.9, 1.4, 122.2),       # (-5, 126, 14): hand on the chest
    "point": (44.2, 4.7, 84.6, 15.3),       # (-14, 141, 52): pointing forward
}
ARM_CHANNELS = (("Arm", "Zrotation"), ("Arm", "Xrotation"), ("Arm", "Yrotation"), ("ForeArm", "Yrotation"))
_MIRROR = np.array([-1.0, 1.0, -1.0, -1.0])   # left arm = right arm with Z and Y rotations negated


def upper_body_skeleton() -> Skeleton:
    """The 16-joint upper body (root ``Hips`` with 6 channels, the rest ZXY rotations)."""
    full = humanoid_skeleton(24)
    keep = 16
    leaves = [j for j in range(keep) if j not in set(full.parents[:keep].tolist())]
    ends = [np.asarray(full.offsets[j]) * 0.5 for j in leaves]
    return Skeleton(full.names[:keep], full.parents[:keep], full.offsets[:keep], full.channels[:keep],
                    np.asarray(leaves, dtype=np.int64), np.asarray(ends).reshape(-1, 3))


def channel_index(skeleton: Skeleton, joint: str, channel: str) -> int:
    j = skeleton.index(joint)
    return int(skeleton.channel_starts[j]) + skeleton.channels[j].index(channel)


def arm_pose(name: str, side: str) -> np.ndarray:
    """The named pose's 4 channel angles for ``side`` ('Right' or 'Left')."""
    p = np.asarray(POSES[name], dtype=np.float64)
    return p if side == "Right" else p * _MIRROR


def min_jerk(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk profile ``10 s^3 - 15 s^4 + 6 s^5`` on [0, 1] (zero velocity and acceleration at both ends)."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)


class Track:
    """Keyframes ``(time, value vector)`` in time order; between consecutive keys the value follows a
    minimum-jerk transition, before the first and after the last it holds."""

    def __init__(self, start: np.ndarray):
        self.times: list[float] = [0.0]
        self.values: list[np.ndarray] = [np.asarray(start, dtype=np.float64)]

    @property
    def last(self) -> np.ndarray:
        return self.values[-1]

    def key(self, t: float, value: np.ndarray) -> None:
        """Add a key at ``t`` (clamped to be after the last one)."""
        t = max(float(t), self.times[-1] + 1e-3)
        self.times.append(t)
        self.values.append(np.asarray(value, dtype=np.float64))

    def hold(self, t: float) -> None:
        """Stay at the current value until ``t``."""
        if t > self.times[-1]:
            self.key(t, self.last)

    def sample(self, t: np.ndarray) -> np.ndarray:
        """``(len(t), D)`` values at times ``t``."""
        times = np.asarray(self.times)
        vals = np.stack(self.values)
        k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
        nxt = np.minimum(k + 1, len(times) - 1)
        span = np.where(nxt > k, times[nxt] - times[k], 1.0)
        s = min_jerk((t - times[k]) / span)
        s = np.where(nxt > k, s, 0.0)
        return vals[k] + s[:, None] * (vals[nxt] - vals[k])
