"""What the encoder sees: a motion turned into pose vectors ``(T, D)`` and cut into windows.

Two representations:

``positions`` (GENEA 2020/2022/2023)
    world positions of the named joints, flattened joint-major as PyMO's ``Numpyfier`` does
    (``j0.x, j0.y, j0.z, j1.x, ...``), in file units; ``D = 3 J``.
``bone_directions`` (Yoon et al. 2020)
    unit vectors ``(child - parent) / ||child - parent||`` for named (parent, child) joint
    pairs; ``D = 3 B``; scale-invariant by construction.

Before the representation is taken, the motion is brought to the model's frame rate
(:func:`evalsuite.motion.ops.resample`) and, for BVH motion, to the model's translation
convention (GENEA 2023 used PyMO's, see :mod:`evalsuite.motion.fk`).
"""
from __future__ import annotations

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion import Motion
from evalsuite.motion.fk import CONVENTIONS
from evalsuite.motion.ops import resample

REPRESENTATIONS = ("positions", "bone_directions")
WINDOW_RULES = ("complete", "genea")


def with_convention(motion: Motion, convention: str | None) -> Motion:
    """The motion under a named BVH translation convention (positions files are unchanged)."""
    if convention is None or not motion.is_hierarchical:
        return motion
    if convention not in CONVENTIONS:
        raise InputError(f"unknown convention {convention!r}; expected one of {', '.join(CONVENTIONS)}")
    conv = CONVENTIONS[convention]
    if motion.root_offset == conv["root_offset"] and motion.joint_translation == conv["joint_translation"]:
        return motion
    return Motion(motion.skeleton, motion.values, motion.fps, name=motion.name, source=motion.source,
                  root_offset=conv["root_offset"], joint_translation=conv["joint_translation"])


def needs_resampling(source_fps: float, fps: float) -> bool:
    """True when motion at ``source_fps`` is resampled (interpolated) to ``fps`` before encoding."""
    return abs(source_fps - fps) > 1e-9 * fps


def resampled_files(motions: dict, fps: float, label: str = "") -> list[dict]:
    """``[{"file", "from_fps", "to_fps"}]`` for every motion of ``{name: Motion}`` that the model
    resamples to its ``fps`` (provenance for every output that encodes them)."""
    out = []
    for name, m in motions.items():
        if needs_resampling(m.fps, fps):
            where = m.source or (f"{label}/{name}" if label else str(name))
            out.append({"file": str(where), "from_fps": float(m.fps), "to_fps": float(fps)})
    return out


def describe_resampling(records: list[dict], why: str) -> list[str]:
    """One warning line per (from, to) rate pair: how many files, one example, why."""
    groups: dict[tuple[float, float], list[str]] = {}
    for r in records:
        groups.setdefault((r["from_fps"], r["to_fps"]), []).append(r["file"])
    return [f"{len(files)} file(s) resampled by interpolation from {a:g} to {b:g} fps {why} (e.g. {files[0]})"
            for (a, b), files in sorted(groups.items())]


def joint_positions(motion: Motion, joints: list[str], fps: float, convention: str | None = None) -> np.ndarray:
    """Positions ``(T, J, 3)`` of ``joints`` (in that order) at ``fps`` under ``convention``."""
    missing = [j for j in joints if j not in motion.joint_names]
    if missing:
        shown = ", ".join(missing[:10]) + (f" and {len(missing) - 10} more" if len(missing) > 10 else "")
        raise InputError(f"the model needs joints the motion does not have: {shown} "
                         f"(the motion has {motion.n_joints} joints: {', '.join(motion.joint_names[:8])}...)",
                         path=motion.source or motion.name)
    motion = with_convention(motion, convention)
    if needs_resampling(motion.fps, fps):
        motion = resample(motion, fps)
    names = motion.joint_names
    index = [names.index(j) for j in joints]
    pos = motion.positions()
    if index == list(range(pos.shape[1])):
        return pos  # already the model's joints in its order: no copy
    return pos[:, index]


def bone_directions(positions: np.ndarray, bones: list[tuple[int, int]]) -> np.ndarray:
    """Unit bone vectors ``(T, B, 3)`` for (parent index, child index) pairs of ``positions (T, J, 3)``.

    A zero-length bone gives a zero vector (as sklearn's ``normalize`` in the reference).
    """
    parent = np.array([p for p, _ in bones], dtype=np.int64)
    child = np.array([c for _, c in bones], dtype=np.int64)
    vec = positions[:, child] - positions[:, parent]
    norm = np.linalg.norm(vec, axis=-1, keepdims=True)
    return np.divide(vec, norm, out=np.zeros_like(vec), where=norm > 0)


def pose_vectors(motion: Motion, representation: dict, fps: float) -> np.ndarray:
    """The motion as pose vectors ``(T, D)`` under a model's representation description.

    ``representation`` holds ``kind``, ``joints`` and (bone directions) ``bones`` as
    ``[parent_name, child_name]`` pairs, plus the optional ``convention``.
    """
    kind = representation["kind"]
    joints = list(representation["joints"])
    pos = joint_positions(motion, joints, fps, representation.get("convention"))
    if kind == "positions":
        return pos.reshape(len(pos), -1)
    if kind == "bone_directions":
        index = {n: i for i, n in enumerate(joints)}
        bones = [(index[p], index[c]) for p, c in representation["bones"]]
        return bone_directions(pos, bones).reshape(len(pos), -1)
    raise InputError(f"unknown representation {kind!r}; expected one of {', '.join(REPRESENTATIONS)}")


def window_starts(n_frames: int, window: int, stride: int, rule: str = "complete") -> np.ndarray:
    """First frame of every window.

    ``complete``: every complete window, ``range(0, T - window + 1, stride)``. ``genea``: the
    reference scripts' ``range(0, T - window, stride)``, which never uses the last complete
    window (a clip of exactly ``window`` frames gives none); kept to reproduce their numbers.
    """
    if rule not in WINDOW_RULES:
        raise InputError(f"unknown window rule {rule!r}; expected one of {', '.join(WINDOW_RULES)}")
    stop = n_frames - window + (1 if rule == "complete" else 0)
    return np.arange(0, max(stop, 0), stride, dtype=np.int64)


def cut_windows(vectors: np.ndarray, window: int, stride: int, rule: str = "complete") -> np.ndarray:
    """Windows ``(N, window, D)`` of pose vectors ``(T, D)`` (a contiguous copy)."""
    starts = window_starts(len(vectors), window, stride, rule)
    # A row gather (each frame's D values are contiguous) is several times faster than
    # copying a transposed sliding_window_view.
    return np.take(vectors, starts[:, None] + np.arange(window), axis=0)


def default_bones(motion: Motion, joints: list[str]) -> list[list[str]]:
    """(parent, child) pairs linking each selected joint to its nearest selected ancestor."""
    names = motion.joint_names
    parents = motion.parents
    chosen = set(joints)
    bones = []
    for j in joints:
        p = parents[names.index(j)]
        while p >= 0 and names[p] not in chosen:
            p = parents[p]
        if p >= 0:
            bones.append([names[p], j])
    if not bones:
        raise InputError("no bones: none of the selected joints has a selected ancestor")
    return bones
