"""The SMPL-X joint layout: the 55 joint names in SMPL-X order and the kinematic parent table (facts, not model data).

SMPL-X ``poses`` hold one axis-angle vector (3 numbers, radians) per joint in this order: 22 body joints
(joint 0, ``pelvis``, carries the global orientation), ``jaw``, the two eyes, then 15 left-hand and 15
right-hand joints (index, middle, pinky, ring, thumb; three joints each, from the knuckle out). This is the
layout of BEAT2 and the GENEA Leaderboard (PantoMatrix issue 133: 1-22 body, 23 jaw, 24-25 eyes, 26-55 hands,
counting from 1).

SMPL-H (AMASS) files use the same body and hand joints without jaw and eyes: 52 joints, 156 numbers per frame.
"""
from __future__ import annotations

_FINGERS = ("index", "middle", "pinky", "ring", "thumb")


def _hand(side: str) -> list[str]:
    return [f"{side}_{finger}{k}" for finger in _FINGERS for k in (1, 2, 3)]


BODY_JOINT_NAMES: tuple[str, ...] = (
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle", "right_ankle",
    "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head", "left_shoulder",
    "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist")
FACE_JOINT_NAMES: tuple[str, ...] = ("jaw", "left_eye_smplhf", "right_eye_smplhf")
LEFT_HAND_JOINT_NAMES: tuple[str, ...] = tuple(_hand("left"))
RIGHT_HAND_JOINT_NAMES: tuple[str, ...] = tuple(_hand("right"))

SMPLX_JOINT_NAMES: tuple[str, ...] = (BODY_JOINT_NAMES + FACE_JOINT_NAMES + LEFT_HAND_JOINT_NAMES
                                      + RIGHT_HAND_JOINT_NAMES)


def _hand_parents(wrist: int, first: int) -> list[int]:
    out = []
    for f in range(5):
        base = first + 3 * f
        out += [wrist, base, base + 1]
    return out


SMPLX_PARENTS: tuple[int, ...] = tuple(
    [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19]   # body
    + [15, 15, 15]                                                             # jaw, eyes on the head
    + _hand_parents(20, 25) + _hand_parents(21, 40))                           # hands on the wrists

N_JOINTS = 55
POSE_WIDTH = 3 * N_JOINTS                     # 165
JAW_EYES = (22, 23, 24)                        # the joints a 156-wide (SMPL-H) file lacks
SMPLH_JOINTS: tuple[int, ...] = tuple(j for j in range(N_JOINTS) if j not in JAW_EYES)   # 52 joints
SMPLH_POSE_WIDTH = 3 * len(SMPLH_JOINTS)      # 156

# The Leaderboard's 13 upper-body joints for beat alignment (spine1..3, neck, collars, head, arms).
UPPER_BODY_BA_JOINTS: tuple[int, ...] = (3, 6, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21)

__all__ = ["SMPLX_JOINT_NAMES", "SMPLX_PARENTS", "BODY_JOINT_NAMES", "FACE_JOINT_NAMES", "LEFT_HAND_JOINT_NAMES",
           "RIGHT_HAND_JOINT_NAMES", "N_JOINTS", "POSE_WIDTH", "JAW_EYES", "SMPLH_JOINTS", "SMPLH_POSE_WIDTH",
           "UPPER_BODY_BA_JOINTS"]
