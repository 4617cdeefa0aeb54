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
