"""What each joint and bone of any skeleton is (spine, upper arm, finger, thigh...), from joint names and
topology, with a fallback by bone length: the mannequin's radii and the above-knees framing use it.

Joint kinds come from the name with any namespace (``mixamorig:``) dropped, first match wins::

    finger       thumb, index, middle, ring, pinky, little, finger      (LeftHandIndex1, b_l_ring2, left_thumb1)
    forearm_mid  wrist/forearm/lowerarm twist or roll joints            (b_l_wrist_twist)
    arm_mid      arm/upperarm twist or roll joints                      (b_l_arm_twist)
    wrist        hand, wrist                                            (LeftHand, b_l_wrist, left_wrist)
    elbow        forearm, elbow, lowerarm                               (LeftForeArm, left_elbow)
    clavicle     collar, clavicle
    shoulder     shoulder, arm, upperarm                                (LeftArm, b_l_arm, left_shoulder)
    hip          upleg, upperleg, thigh, left/right hip                 (LeftUpLeg, left_hip)
    toe          toe                                                    (LeftToeBase)
    ankle        ankle, foot, heel                                      (LeftFoot, left_ankle)
    knee         knee, leg, lowerleg, shin, calf                        (LeftLeg, b_l_leg, left_knee)
    head_end     head top / head end                                    (HeadTop_End)
    head, neck, spine (spine, chest, torso, back), pelvis (hips, pelvis, root), other

then topology settles the ambiguous names: a ``shoulder`` whose child is also a ``shoulder`` is the clavicle
(Mixamo ``LeftShoulder`` -> ``LeftArm``; GENEA ``b_l_shoulder`` -> ``b_l_arm``), and a ``foot`` under an ankle is
the toe joint (SMPL-X ``left_ankle`` -> ``left_foot``). A bone is classed by its child joint (the segment that
ends there): child elbow -> ``upperarm``, wrist -> ``forearm``, finger -> ``finger`` (``palm`` from the wrist),
knee -> ``thigh``, ankle -> ``shin``, toe -> ``foot``, hip -> ``pelvis``, head -> ``neck``, spine/neck ->
``spine``; a bone whose child has no recognisable name is classed by its length ``l`` relative to the figure
size ``s``: ``l < 0.06 s`` finger, ``l < 0.18 s`` forearm, else upperarm.
"""
from __future__ import annotations

import re

import numpy as np

from renderers.figure import LEFT, RIGHT, joint_sides

_KINDS = [
    ("finger", r"thumb|index|middle|ring|pinky|little|finger"),
    ("forearm_mid", r"wrist_?twist|(forearm|lowerarm)_?(twist|roll)"),
    ("arm_mid", r"arm_?(twist|roll)"),
    ("wrist", r"hand|wrist"),
    ("elbow", r"forearm|elbow|lowerarm|fore_arm"),
    ("clavicle", r"collar|clavicle"),
    ("shoulder", r"shoulder|arm"),
    ("hip", r"upleg|up_leg|upperleg|thigh|(^|[^a-z])(left|right|l|r)_?hip"),
    ("toe", r"toe"),
    ("ankle", r"ankle|foot|heel"),
    ("knee", r"knee|leg|shin|calf"),
    ("head_end", r"head_?(top|end)|headtop|head_nub"),
    ("head", r"head"),
    ("neck", r"neck"),
    ("spine", r"spine|chest|torso|back|abdomen"),
    ("pelvis", r"hips|pelvis|root"),
]
_KIND_RES = [(k, re.compile(p)) for k, p in _KINDS]

BONE_OF_CHILD = {"elbow": "upperarm", "arm_mid": "upperarm", "forearm_mid": "forearm", "wrist": "forearm",
                 "shoulder": "clavicle", "clavicle": "clavicle", "hip": "pelvis", "knee": "thigh", "ankle": "shin",
                 "toe": "foot", "head": "neck", "neck": "spine", "spine": "spine", "pelvis": "spine"}
BELOW_KNEE = ("ankle", "toe")


def _name_kind(name: str) -> str:
    tail = name.rsplit(":", 1)[-1].lower()
    for kind, rx in _KIND_RES:
        if rx.search(tail):
            return kind
    return "other"


def joint_kinds(names, parents) -> list[str]:
    """The kind of every joint (see the module doc), names first, then topology."""
    kinds = [_name_kind(n) for n in names]
    parents = [int(p) for p in parents]
    for j, p in enumerate(parents):
        if p < 0:
            continue
        if kinds[j] == "shoulder" and kinds[p] == "shoulder":
            kinds[p] = "clavicle"
        if kinds[j] == "ankle" and kinds[p] == "ankle" and "foot" in names[j].lower():
            kinds[j] = "toe"
    return kinds


def descendants(parents, root: int) -> np.ndarray:
    """Boolean mask of the joints below ``root`` (not ``root`` itself); parents come before children."""
    out = np.zeros(len(parents), dtype=bool)
    for j, p in enumerate(parents):
        if p >= 0 and (p == root or out[p]):
            out[j] = True
    return out


def bone_classes(names, parents, lengths, size: float) -> list[str]:
    """Class of the bone ending at each joint (``""`` for a root), see the module doc. ``lengths`` ``(J,)``:
    each joint's distance to its parent in the rest pose (used only for joints of no known kind)."""
    kinds = joint_kinds(names, parents)
    out = []
    for j, p in enumerate(parents):
        if p < 0:
            out.append("")
            continue
        kind = kinds[j]
        if kind == "finger":
            out.append("palm" if kinds[p] == "wrist" else "finger")
        elif kind == "wrist" and kinds[p] == "wrist":
            out.append("hand")
        elif kind == "neck" and kinds[p] == "neck":
            out.append("neck")
        elif kind in BONE_OF_CHILD:
            out.append(BONE_OF_CHILD[kind])
        elif kind == "head_end":
            out.append("head_end")
        else:
            length = float(lengths[j]) / size
            out.append("finger" if length < 0.06 else "forearm" if length < 0.18 else "upperarm")
    return out


# Stature fractions (Drillis and Contini's segment proportions, as tabulated in Winter's "Biomechanics and Motor
# Control of Human Movement"): the hip joint at 0.530 and the shoulder at 0.818 of stature (torso 0.288); the
# shoulder joints' centres about 0.2 of stature apart.
TORSO_PER_STATURE, SHOULDERS_PER_STATURE = 0.288, 0.20


def has_legs(kinds) -> bool:
    """Whether a skeleton of these joint kinds has legs (a knee, ankle or toe joint)."""
    return any(k in ("knee", "ankle", "toe") for k in kinds)


def body_scale(names, parents, positions, size: float) -> float:
    """The length a body's part sizes are fractions of: ``size`` (the figure's largest extent, about its stature)
    for a skeleton with legs; for an upper body, whose extent is far below its stature, at least the stature its
    torso (pelvis to neck, 0.288 of stature) and shoulder span (0.20) suggest (their median), so an upper body is
    as thick as the whole body of the same person would be. ``positions`` ``(T, J, 3)``."""
    kinds = joint_kinds(names, parents)
    if has_legs(kinds) or not len(positions):
        return float(size)
    med = np.nan_to_num(np.nanmedian(np.asarray(positions, float), axis=0))
    estimates = []
    pelvis = next((j for j, k in enumerate(kinds) if k == "pelvis"), None)
    neck = next((j for j, k in enumerate(kinds) if k == "neck"), None)
    if pelvis is not None and neck is not None:
        estimates.append(np.linalg.norm(med[neck] - med[pelvis]) / TORSO_PER_STATURE)
    sides = joint_sides(names)
    left = [j for j, k in enumerate(kinds) if k == "shoulder" and sides[j] == LEFT]
    right = [j for j, k in enumerate(kinds) if k == "shoulder" and sides[j] == RIGHT]
    if left and right:
        estimates.append(np.linalg.norm(med[left[0]] - med[right[0]]) / SHOULDERS_PER_STATURE)
    return float(max(size, np.median(estimates))) if estimates else float(size)
