"""The joints a re-implemented generator models: named presets for the skeletons researchers train on, declared
once here, and ``evalsuite train --joints PRESET|names``.

=========================  =====================================================================================
preset                     joints
=========================  =====================================================================================
``genea2020-upper``        the 15 upper-body joints of the Trinity / GENEA 2020 data (Gesticulator, Gesture2Vec,
                           the GENEA 2020 baseline): ``Spine``..``Spine3``, ``Neck``, ``Neck1``, ``Head``,
                           shoulders, arms, forearms, hands
``genea2023-upper``        the GENEA 2022/2023 (Talking With Hands) upper body without fingers (18):
                           ``b_spine0``..``b_spine3``, ``b_neck0``, ``b_head`` and per side ``shoulder``, ``arm``,
                           ``arm_twist``, ``forearm``, ``wrist_twist``, ``wrist``
``genea2023-upper-fingers``  the same with the 15 finger joints of each hand (50: the GENEA 2023 FGD joints
                           without legs, ``body_world`` and ``b_root``)
``beat-upper``             BEAT's Mixamo-style upper body (``Spine``..``Spine3``, ``Neck``, ``Neck1``,
                           ``Head``, ``RightShoulder``, ``RightArm``, ``RightForeArm``, ``RightHand``, …):
                           the same 15 names as ``genea2020-upper``, on BEAT's skeleton
``smplx-body-hands``       the SMPL-X body above the pelvis (spine, neck, head, collars, shoulders, elbows,
                           wrists) and the 30 hand joints
=========================  =====================================================================================

Without ``--joints`` a re-implementation models the first preset of this table of which at least three joints
with rotation channels are in the corpus's skeleton (so a GENEA 2020 corpus keeps its 15 joints and a GENEA 2023
one gets ``genea2023-upper``). Names (comma-separated) model exactly those joints.
"""
from __future__ import annotations

from collections.abc import Sequence

from evalsuite.errors import InputError
from evalsuite.motion.presets import GENEA2020_UPPER, GENEA2023_UPPER
from evalsuite.motion.smplx_layout import LEFT_HAND_JOINT_NAMES, RIGHT_HAND_JOINT_NAMES

__all__ = ["JOINT_PRESETS", "resolve_joint_option", "default_joints", "WRIST_JOINTS", "ARM_JOINTS"]

_FINGER_WORDS = ("pinky", "ring", "middle", "index", "thumb")
_GENEA2023_UPPER_BODY = [j for j in GENEA2023_UPPER if not any(w in j for w in _FINGER_WORDS)]
_SMPLX_UPPER = ["spine1", "spine2", "spine3", "neck", "head", "left_collar", "right_collar", "left_shoulder",
                "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist"]

JOINT_PRESETS: dict[str, list[str]] = {
    "genea2020-upper": list(GENEA2020_UPPER),
    "genea2023-upper": _GENEA2023_UPPER_BODY,
    "genea2023-upper-fingers": list(GENEA2023_UPPER),
    "beat-upper": list(GENEA2020_UPPER),
    "smplx-body-hands": _SMPLX_UPPER + list(LEFT_HAND_JOINT_NAMES) + list(RIGHT_HAND_JOINT_NAMES),
}

# Wrists and arm chains under each skeleton's names (GENEA 2020 / BEAT first, so their order is unchanged).
WRIST_JOINTS = ("RightHand", "LeftHand", "b_r_wrist", "b_l_wrist", "right_wrist", "left_wrist")
ARM_JOINTS = ("RightShoulder", "RightArm", "RightForeArm", "RightHand", "LeftShoulder", "LeftArm", "LeftForeArm",
              "LeftHand", "b_r_shoulder", "b_r_arm", "b_r_forearm", "b_r_wrist", "b_l_shoulder", "b_l_arm",
              "b_l_forearm", "b_l_wrist", "right_collar", "right_shoulder", "right_elbow", "right_wrist",
              "left_collar", "left_shoulder", "left_elbow", "left_wrist")


def resolve_joint_option(value: str | Sequence[str] | None) -> list[str] | None:
    """``--joints``: a preset name, comma-separated joint names, or a list of names; None stays None."""
    if value is None:
        return None
    if isinstance(value, str):
        if value in JOINT_PRESETS:
            return list(JOINT_PRESETS[value])
        names = [n.strip() for n in value.split(",") if n.strip()]
    else:
        names = [str(n) for n in value]
    if not names:
        raise InputError(f"--joints takes a preset ({', '.join(JOINT_PRESETS)}) or comma-separated joint names",
                         field="--joints")
    if len(names) == 1 and "," not in str(value):
        known = ", ".join(JOINT_PRESETS)
        raise InputError(f"unknown joint preset {names[0]!r} (presets: {known}); give two or more comma-separated "
                         f"joint names to model those joints", field="--joints")
    return names


def default_joints(available: Sequence[str]) -> list[str]:
    """The first preset with at least three joints in ``available`` (the corpus's rotating joints)."""
    have = set(available)
    for names in JOINT_PRESETS.values():
        if sum(j in have for j in names) >= 3:
            return list(names)
    return list(GENEA2020_UPPER)
