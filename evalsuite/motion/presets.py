"""Named joint sets, selected by name (never by column index).

``genea2020_upper``: the 15-joint upper body of the Trinity / GENEA 2020 data used by
Gesticulator and Gesture2Vec (``JointSelector`` lists of their data scripts).
``genea2023``: the 56 joints of the GENEA 2023 (Talking With Hands skeleton) FGD scripts
(``extract_joint_positions.py``: PyMO positions of these joints, root excluded).
``genea2023_upper``: the same without legs, ``body_world`` and ``b_root``.
``wrists``, ``forearms``, ``hands``: the groups whose speed histograms "Moving fast and slow"
reports; they name Trinity joints and, where present, the GENEA 2023 ones.
"""
from __future__ import annotations

from collections.abc import Sequence

GENEA2020_UPPER = [
    "Spine", "Spine1", "Spine2", "Spine3", "Neck", "Neck1", "Head",
    "RightShoulder", "RightArm", "RightForeArm", "RightHand",
    "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
]

GENEA2023 = [
    "body_world", "b_root", "b_l_upleg", "b_l_leg", "b_r_upleg", "b_r_leg", "b_spine0", "b_spine1",
    "b_spine2", "b_spine3", "b_l_shoulder", "b_l_arm", "b_l_arm_twist", "b_l_forearm", "b_l_wrist_twist",
    "b_l_wrist", "b_l_pinky1", "b_l_pinky2", "b_l_pinky3", "b_l_ring1", "b_l_ring2", "b_l_ring3",
    "b_l_middle1", "b_l_middle2", "b_l_middle3", "b_l_index1", "b_l_index2", "b_l_index3", "b_l_thumb0",
    "b_l_thumb1", "b_l_thumb2", "b_l_thumb3", "b_r_shoulder", "b_r_arm", "b_r_arm_twist", "b_r_forearm",
    "b_r_wrist_twist", "b_r_wrist", "b_r_thumb0", "b_r_thumb1", "b_r_thumb2", "b_r_thumb3", "b_r_pinky1",
    "b_r_pinky2", "b_r_pinky3", "b_r_middle1", "b_r_middle2", "b_r_middle3", "b_r_ring1", "b_r_ring2",
    "b_r_ring3", "b_r_index1", "b_r_index2", "b_r_index3", "b_neck0", "b_head",
]

GENEA2023_UPPER = [j for j in GENEA2023
                   if j not in ("body_world", "b_root", "b_l_upleg", "b_l_leg", "b_r_upleg", "b_r_leg")]

PRESETS: dict[str, list[str]] = {
    "genea2020_upper": GENEA2020_UPPER,
    "trinity_upper": GENEA2020_UPPER,
    "genea2023": GENEA2023,
    "genea2023_upper": GENEA2023_UPPER,
    "wrists": ["RightHand", "LeftHand", "b_r_wrist", "b_l_wrist"],
    "forearms": ["RightForeArm", "LeftForeArm", "b_r_forearm", "b_l_forearm"],
    "hands": ["RightHand", "LeftHand", "b_r_wrist", "b_l_wrist"],
}

# Groups whose members are alternatives across skeletons: only the present ones are used.
OPTIONAL_MEMBER_PRESETS = {"wrists", "forearms", "hands"}


def resolve_joints(spec: str | Sequence[str], available: list[str]) -> list[str]:
    """Joint names from a preset name, a comma-separated string or a list of names.

    Raises ``KeyError`` listing the missing names (callers turn it into a MotionError).
    """
    if isinstance(spec, str):
        if spec in PRESETS:
            names = PRESETS[spec]
            if spec in OPTIONAL_MEMBER_PRESETS:
                names = [n for n in names if n in available]
                if not names:
                    raise KeyError(f"none of the joints of preset {spec!r} ({', '.join(PRESETS[spec])})")
                return names
        else:
            names = [n.strip() for n in spec.split(",") if n.strip()]
    else:
        names = [str(n) for n in spec]
    missing = [n for n in names if n not in available]
    if missing:
        raise KeyError(", ".join(repr(n) for n in missing))
    return names
