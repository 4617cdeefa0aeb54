"""Synthetic humanoid motion for benchmarks and tests (no licence questions, any size).

The skeleton is a plausible humanoid (spine chain, neck, head, arms with fingers, legs)
whose joint count is adjustable; the motion is a smooth sum of sinusoids per channel,
seeded, so two calls with the same arguments give identical data.
"""
from __future__ import annotations

import numpy as np

from evalsuite.motion.motion import Motion
from evalsuite.motion.skeleton import Skeleton

_ROT = ("Zrotation", "Xrotation", "Yrotation")
_ROOT = ("Xposition", "Yposition", "Zposition") + _ROT


def humanoid_skeleton(n_joints: int = 60, rotation_order: str = "ZXY") -> Skeleton:
    """A humanoid with exactly ``n_joints`` joints (>= 20); fingers take the remainder.

    Joint names follow the GENEA/Trinity naming (``Hips``, ``Spine``..``Spine3``, ``Neck``,
    ``Neck1``, ``Head``, ``RightShoulder``, ``RightArm``, ``RightForeArm``, ``RightHand``, ...),
    so the named presets apply.
    """
    if n_joints < 20:
        raise ValueError("n_joints must be at least 20")
    rot = tuple(f"{a}rotation" for a in rotation_order.upper())
    names, parents, offsets = [], [], []

    def add(name: str, parent: str | None, offset: tuple[float, float, float]) -> None:
        names.append(name)
        parents.append(parent if parent is None else names.index(parent))
        offsets.append(offset)

    add("Hips", None, (0.0, 95.0, 0.0))
    add("Spine", "Hips", (0.0, 8.0, 0.0))
    add("Spine1", "Spine", (0.0, 10.0, 0.0))
    add("Spine2", "Spine1", (0.0, 10.0, 0.0))
    add("Spine3", "Spine2", (0.0, 10.0, 0.0))
    add("Neck", "Spine3", (0.0, 12.0, 0.0))
    add("Neck1", "Neck", (0.0, 5.0, 0.0))
    add("Head", "Neck1", (0.0, 8.0, 0.0))
    for side, sx in (("Right", -1.0), ("Left", 1.0)):
        add(f"{side}Shoulder", "Spine3", (sx * 4.0, 10.0, 0.0))
        add(f"{side}Arm", f"{side}Shoulder", (sx * 14.0, 0.0, 0.0))
        add(f"{side}ForeArm", f"{side}Arm", (sx * 28.0, 0.0, 0.0))
        add(f"{side}Hand", f"{side}ForeArm", (sx * 25.0, 0.0, 0.0))
    for side, sx in (("Right", -1.0), ("Left", 1.0)):
        add(f"{side}UpLeg", "Hips", (sx * 9.0, -4.0, 0.0))
        add(f"{side}Leg", f"{side}UpLeg", (0.0, -42.0, 0.0))
        add(f"{side}Foot", f"{side}Leg", (0.0, -40.0, 0.0))
        add(f"{side}ToeBase", f"{side}Foot", (0.0, -6.0, 12.0))
    # Fingers: chains of up to 3 phalanges, alternating hands, until the count is reached.
    finger_names = ("Thumb", "Index", "Middle", "Ring", "Pinky")
    hands = [("Right", -1.0), ("Left", 1.0)]
    remaining = n_joints - len(names)
    k = 0
    while remaining > 0:
        side, sx = hands[k % 2]
        finger = finger_names[(k // 2) % 5] + ("" if k < 10 else str(k // 10))
        parent = f"{side}Hand"
        for phalanx in range(1, 4):
            if remaining == 0:
                break
            add(f"{side}Hand{finger}{phalanx}", parent, (sx * 3.0, 0.0, ((k // 2) % 5 - 2) * 1.5))
            parent = names[-1]
            remaining -= 1
        k += 1
    channels = [_ROOT if p is None else rot for p in parents]
    parents = [-1 if p is None else p for p in parents]
    leaf = [j for j in range(len(names)) if j not in parents]
    end_offsets = [np.asarray(offsets[j]) * 0.5 for j in leaf]
    return Skeleton(names, np.asarray(parents, dtype=np.int64), np.asarray(offsets, dtype=np.float64), channels,
                    np.asarray(leaf, dtype=np.int64), np.asarray(end_offsets, dtype=np.float64).reshape(-1, 3))


def synthetic_motion(n_joints: int = 60, fps: float = 60.0, seconds: float = 60.0, seed: int = 0,
                     rotation_order: str = "ZXY") -> Motion:
    """Smooth random motion (sinusoids of 0.2-3 Hz, +-30 degrees) on :func:`humanoid_skeleton`."""
    skeleton = humanoid_skeleton(n_joints, rotation_order)
    rng = np.random.default_rng(seed)
    n_frames = int(round(seconds * fps))
    t = np.arange(n_frames) / fps
    n_ch = skeleton.n_channels
    freq = rng.uniform(0.2, 3.0, size=(2, n_ch))
    phase = rng.uniform(0, 2 * np.pi, size=(2, n_ch))
    amp = rng.uniform(2.0, 30.0, size=(2, n_ch))
    values = (amp[0] * np.sin(2 * np.pi * freq[0] * t[:, None] + phase[0])
              + 0.3 * amp[1] * np.sin(2 * np.pi * freq[1] * t[:, None] + phase[1]))
    values[:, 0:3] = values[:, 0:3] * 0.3 + np.array([0.0, 95.0, 0.0])  # root position
    return Motion(skeleton, values, fps, name=f"synthetic_{n_joints}j_{seed}")
