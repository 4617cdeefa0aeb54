"""The synthetic speaker on another skeleton: ``evalsuite corpus synth --skeleton genea2020|genea2023|beat|smplx``.

The speaker's model (:mod:`evalsuite.synth.model`) animates its 16-joint GENEA 2020 upper body
(:func:`evalsuite.synth.body.upper_body_skeleton`: T-pose, centimetres, +y up, +z forward, left at +x, ZXY Euler
channels). Another skeleton gets the same performance by copying each joint's local rotation to its counterpart
(both skeletons rest in a T-pose with the same axes, so equal local rotations give the same bone directions);
joints without a counterpart (twist joints, fingers, legs, ``body_world``) stay at rest (zero rotation).

* ``genea2020``: the speaker's own skeleton (the default; files identical to those before the option existed).
* ``genea2023``: the GENEA 2022/2023 (Talking With Hands) hierarchy and joint names, fingers included
  (:data:`evalsuite.motion.presets.GENEA2023`, 56 joints, the order of the FGD scripts): ``body_world`` (a root at
  the floor) -> ``b_root`` (the pelvis, with the speaker's hip channels) -> legs, ``b_spine0..3``, ``b_neck0``,
  ``b_head`` and per side ``shoulder``, ``arm``, ``arm_twist``, ``forearm``, ``wrist_twist``, ``wrist`` and 15
  finger joints. ``Neck1``'s rotation is composed into ``b_head`` (``R_head' = R_neck1 R_head``).
* ``beat``: BEAT's Mixamo-style names (``Hips``, ``Spine``..``Spine3``, ``Neck``, ``Neck1``, ``Head``,
  ``HeadEnd``, ``RightShoulder``, ``RightArm``, ``RightForeArm``, ``RightHand``, ``RightHandThumb1..4``,
  ``RightHandIndex``/``Index1..4`` (and ``Middle``, ``Ring``, ``Pinky``), legs with ``ForeFoot`` and ``ToeBase``).
* ``smplx``: SMPL-X ``.npz`` files (:func:`evalsuite.motion.smplx.write_smplx`) holding **rotations only**:
  ``poses`` (T, 165) axis-angle in SMPL-X joint order (pelvis = the speaker's hip rotation, spine1..3 =
  ``Spine``, ``Spine1``, ``Spine2``·``Spine3``, neck = ``Neck``·``Neck1``, head, collars, shoulders = ``Arm``,
  elbows = ``ForeArm``, wrists = ``Hand``), ``trans`` (T, 3) in metres, no ``betas``. Joint positions need an
  SMPL-X body model, which evalsuite does not ship; a re-implementation trains on the rotations.

Offsets are the speaker's bone lengths where a bone has a counterpart (the upper arm split in two at the twist
joint, the forearm likewise), and plausible lengths (centimetres) elsewhere.
"""
from __future__ import annotations

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion.motion import Motion
from evalsuite.motion.presets import GENEA2023
from evalsuite.motion.skeleton import Skeleton

__all__ = ["SKELETONS", "skeleton_for", "retarget", "smplx_rotations"]

SKELETONS = ("genea2020", "genea2023", "beat", "smplx")
_ROT = ("Zrotation", "Xrotation", "Yrotation")
_ROOT = ("Xposition", "Yposition", "Zposition") + _ROT
_FINGERS = ("thumb", "index", "middle", "ring", "pinky")
_FINGER_X = {"thumb": (2.0, 3.0), "index": (9.0, 2.0), "middle": (9.0, 0.5), "ring": (8.5, -1.0),
             "pinky": (8.0, -2.5)}   # knuckle offset from the wrist (along the arm, forward) in cm


def _genea2023() -> tuple[list[str], dict[str, tuple[str | None, tuple[float, float, float]]], dict[str, str]]:
    j: dict[str, tuple[str | None, tuple[float, float, float]]] = {
        "body_world": (None, (0.0, 0.0, 0.0)), "b_root": ("body_world", (0.0, 0.0, 0.0))}
    for s, x in (("l", 1.0), ("r", -1.0)):
        j[f"b_{s}_upleg"] = ("b_root", (9.0 * x, -4.0, 0.0))
        j[f"b_{s}_leg"] = (f"b_{s}_upleg", (0.0, -42.0, 0.0))
    j["b_spine0"] = ("b_root", (0.0, 8.0, 0.0))
    for k in (1, 2, 3):
        j[f"b_spine{k}"] = (f"b_spine{k - 1}", (0.0, 10.0, 0.0))
    for s, x in (("l", 1.0), ("r", -1.0)):
        chain = [("shoulder", "b_spine3", (4.0, 10.0, 0.0)), ("arm", "shoulder", (14.0, 0.0, 0.0)),
                 ("arm_twist", "arm", (14.0, 0.0, 0.0)), ("forearm", "arm_twist", (14.0, 0.0, 0.0)),
                 ("wrist_twist", "forearm", (12.5, 0.0, 0.0)), ("wrist", "wrist_twist", (12.5, 0.0, 0.0))]
        for name, parent, off in chain:
            j[f"b_{s}_{name}"] = (parent if parent.startswith("b_") else f"b_{s}_{parent}", (off[0] * x, off[1], off[2]))
        for finger in _FINGERS:
            first = 0 if finger == "thumb" else 1
            for k in range(first, 4):
                parent = f"b_{s}_wrist" if k == first else f"b_{s}_{finger}{k - 1}"
                dx, dz = _FINGER_X[finger] if k == first else (2.5, 0.0)
                j[f"b_{s}_{finger}{k}"] = (parent, (dx * x, 0.0, dz))
    j["b_neck0"] = ("b_spine3", (0.0, 12.0, 0.0))
    j["b_head"] = ("b_neck0", (0.0, 13.0, 0.0))
    mapping = {"Hips": "b_root", "Spine": "b_spine0", "Spine1": "b_spine1", "Spine2": "b_spine2",
               "Spine3": "b_spine3", "Neck": "b_neck0", "Head": "b_head"}
    for side, s in (("Right", "r"), ("Left", "l")):
        mapping.update({f"{side}Shoulder": f"b_{s}_shoulder", f"{side}Arm": f"b_{s}_arm",
                        f"{side}ForeArm": f"b_{s}_forearm", f"{side}Hand": f"b_{s}_wrist"})
    return list(GENEA2023), j, mapping


def _beat() -> tuple[list[str], dict[str, tuple[str | None, tuple[float, float, float]]], dict[str, str]]:
    j: dict[str, tuple[str | None, tuple[float, float, float]]] = {"Hips": (None, (0.0, 95.0, 0.0))}
    order = ["Hips"]

    def add(name: str, parent: str, off: tuple[float, float, float]) -> None:
        j[name] = (parent, off)
        order.append(name)

    add("Spine", "Hips", (0.0, 8.0, 0.0))
    for k in (1, 2, 3):
        add(f"Spine{k}", "Spine" if k == 1 else f"Spine{k - 1}", (0.0, 10.0, 0.0))
    add("Neck", "Spine3", (0.0, 12.0, 0.0))
    add("Neck1", "Neck", (0.0, 5.0, 0.0))
    add("Head", "Neck1", (0.0, 8.0, 0.0))
    add("HeadEnd", "Head", (0.0, 12.0, 0.0))
    for side, x in (("Right", -1.0), ("Left", 1.0)):
        add(f"{side}Shoulder", "Spine3", (4.0 * x, 10.0, 0.0))
        add(f"{side}Arm", f"{side}Shoulder", (14.0 * x, 0.0, 0.0))
        add(f"{side}ForeArm", f"{side}Arm", (28.0 * x, 0.0, 0.0))
        add(f"{side}Hand", f"{side}ForeArm", (25.0 * x, 0.0, 0.0))
        for finger in ("Thumb", "Index", "Middle", "Ring", "Pinky"):
            dx, dz = _FINGER_X[finger.lower()]
            parent = f"{side}Hand"
            if finger != "Thumb":             # BEAT's metacarpal joints: RightHandIndex, then Index1..4
                add(f"{side}Hand{finger}", parent, (2.0 * x, 0.0, dz))
                parent, dx = f"{side}Hand{finger}", dx - 2.0
            for k in (1, 2, 3, 4):
                add(f"{side}Hand{finger}{k}", parent, ((dx if k == 1 else 2.5) * x, 0.0, dz if k == 1 and finger == "Thumb" else 0.0))
                parent = f"{side}Hand{finger}{k}"
    for side, x in (("Right", -1.0), ("Left", 1.0)):
        add(f"{side}UpLeg", "Hips", (9.0 * x, -4.0, 0.0))
        add(f"{side}Leg", f"{side}UpLeg", (0.0, -42.0, 0.0))
        add(f"{side}Foot", f"{side}Leg", (0.0, -40.0, 0.0))
        add(f"{side}ForeFoot", f"{side}Foot", (0.0, -6.0, 8.0))
        add(f"{side}ToeBase", f"{side}ForeFoot", (0.0, 0.0, 5.0))
    names = ["Hips", "Spine", "Spine1", "Spine2", "Spine3", "Neck", "Neck1", "Head"]
    names += [f"{s}{p}" for s in ("Right", "Left") for p in ("Shoulder", "Arm", "ForeArm", "Hand")]
    return order, j, {n: n for n in names}


def skeleton_for(name: str) -> tuple[Skeleton, dict[str, str]]:
    """The skeleton called ``name`` (BVH ones) and the map speaker joint -> its joint."""
    if name == "genea2020":
        from evalsuite.synth.body import upper_body_skeleton

        sk = upper_body_skeleton()
        return sk, {n: n for n in sk.names}
    if name not in ("genea2023", "beat"):
        raise InputError(f"unknown skeleton {name!r}; expected one of {', '.join(SKELETONS)} (smplx is written as "
                         f"SMPL-X .npz, not BVH)", field="--skeleton")
    order, joints, mapping = _genea2023() if name == "genea2023" else _beat()
    parents = [order.index(p) if p is not None else -1 for p, _ in (joints[n] for n in order)]
    offsets = [joints[n][1] for n in order]
    roots = {"body_world", "b_root", "Hips"}
    channels: list[tuple[str, ...]] = [_ROOT if n in roots else _ROT for n in order]
    children = {p for p in parents if p >= 0}
    leaves = [k for k in range(len(order)) if k not in children]
    ends = [np.asarray(offsets[k], dtype=np.float64) * 0.5 if np.any(offsets[k]) else np.array([0.0, 5.0, 0.0])
            for k in leaves]
    return Skeleton(order, np.asarray(parents), np.asarray(offsets, dtype=np.float64), channels,
                    np.asarray(leaves, dtype=np.int64), np.asarray(ends).reshape(-1, 3)), mapping


def _euler(motion: Motion, joint: str) -> np.ndarray:
    sk = motion.skeleton
    j = sk.index(joint)
    cols = [int(sk.channel_starts[j]) + sk.channels[j].index(c) for c in _ROT]
    return np.asarray(motion.values[:, cols], dtype=np.float64)


def _compose(motion: Motion, first: str, second: str) -> np.ndarray:
    """ZXY Euler degrees of ``R_first R_second`` (a parent's and its child's local rotations in one)."""
    from scipy.spatial.transform import Rotation

    a = Rotation.from_euler("ZXY", _euler(motion, first), degrees=True)
    b = Rotation.from_euler("ZXY", _euler(motion, second), degrees=True)
    return np.asarray((a * b).as_euler("ZXY", degrees=True))


def retarget(motion: Motion, name: str) -> Motion:
    """The speaker's motion (its own skeleton) on the skeleton ``name`` (module doc)."""
    if name == "genea2020":
        return motion
    target, mapping = skeleton_for(name)
    values = np.zeros((motion.n_frames, target.n_channels))
    src = motion.skeleton
    for s_name, t_name in mapping.items():
        t = target.index(t_name)
        start = int(target.channel_starts[t])
        if t_name in ("b_root", "Hips"):
            s = src.index(s_name)
            values[:, start:start + 6] = motion.values[:, int(src.channel_starts[s]):int(src.channel_starts[s]) + 6]
            continue
        rot = _compose(motion, "Neck1", "Head") if (name == "genea2023" and s_name == "Head") else _euler(motion, s_name)
        values[:, start:start + 3] = rot
    return Motion(target, values, motion.fps, name=motion.name) if hasattr(motion, "name") else Motion(
        target, values, motion.fps)


# speaker joint(s) whose composed rotation drives each SMPL-X joint
_SMPLX_MAP = {"spine1": ("Spine",), "spine2": ("Spine1",), "spine3": ("Spine2", "Spine3"), "neck": ("Neck", "Neck1"),
              "head": ("Head",), "right_collar": ("RightShoulder",), "left_collar": ("LeftShoulder",),
              "right_shoulder": ("RightArm",), "left_shoulder": ("LeftArm",), "right_elbow": ("RightForeArm",),
              "left_elbow": ("LeftForeArm",), "right_wrist": ("RightHand",), "left_wrist": ("LeftHand",)}


def smplx_rotations(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """``(poses (T, 165) axis-angle radians, trans (T, 3) metres)`` of the speaker's motion for SMPL-X."""
    from scipy.spatial.transform import Rotation

    from evalsuite.motion.smplx_layout import SMPLX_JOINT_NAMES

    n = motion.n_frames
    poses = np.zeros((n, 55, 3))
    sk = motion.skeleton
    h = int(sk.channel_starts[sk.index("Hips")])
    poses[:, 0] = Rotation.from_euler("ZXY", motion.values[:, h + 3:h + 6], degrees=True).as_rotvec()
    for joint, sources in _SMPLX_MAP.items():
        r = Rotation.from_euler("ZXY", _euler(motion, sources[0]), degrees=True)
        for extra in sources[1:]:
            r = r * Rotation.from_euler("ZXY", _euler(motion, extra), degrees=True)
        poses[:, SMPLX_JOINT_NAMES.index(joint)] = r.as_rotvec()
    trans = np.asarray(motion.values[:, h:h + 3], dtype=np.float64) / 100.0
    return poses.reshape(n, 165), trans
