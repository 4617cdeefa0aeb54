"""Forward kinematics: BVH channel values to world positions (and rotations).

Vectorised over frames: the only Python loops run over joints (and over the groups of
joints that share a rotation-channel order), never over frames.

Conventions (named, chosen by the caller; see ``docs/motion.md``):

``root_offset``
    ``"ignore"`` (default, the common convention of PyMO, pymotion, bvhio, bvh-toolbox and
    Blender): when the root has position channels they are its absolute position and the
    root OFFSET is not added. ``"add"``: OFFSET + channel values.
``joint_translation`` (position channels on non-root joints)
    ``"replace"`` (default): the channel values are the joint's local translation and replace
    the OFFSET on the axes they cover (what MotionBuilder/Blender exporters write);
    ``"add"``: OFFSET + channel values, as PyMO computes it (the convention the GENEA 2023
    FGD statistics were computed with); ``"ignore"``: the channels are ignored and the OFFSET
    is used (pymotion, bvh-toolbox).
"""
from __future__ import annotations

from typing import Any, Literal, overload

import numpy as np

from evalsuite.motion.rotations import euler_to_matrix_elements, multiply_elements
from evalsuite.motion.skeleton import POSITION_CHANNELS, Skeleton

ROOT_OFFSET_CONVENTIONS = ("ignore", "add")
JOINT_TRANSLATION_CONVENTIONS = ("replace", "add", "ignore")

# Named presets of the two conventions, for readers of other libraries' numbers.
CONVENTIONS = {
    "default": {"root_offset": "ignore", "joint_translation": "replace"},
    "pymo": {"root_offset": "ignore", "joint_translation": "add"},
    "pymotion": {"root_offset": "ignore", "joint_translation": "ignore"},
    "bvhtoolbox": {"root_offset": "ignore", "joint_translation": "ignore"},
}


def check_conventions(root_offset: str, joint_translation: str) -> None:
    if root_offset not in ROOT_OFFSET_CONVENTIONS:
        raise ValueError(f"root_offset must be one of {ROOT_OFFSET_CONVENTIONS}, got {root_offset!r}")
    if joint_translation not in JOINT_TRANSLATION_CONVENTIONS:
        raise ValueError(f"joint_translation must be one of {JOINT_TRANSLATION_CONVENTIONS}, "
                         f"got {joint_translation!r}")


def local_rotation_elements(skeleton: Skeleton, values: np.ndarray) -> list[Any]:
    """Local rotation of every joint as a list (per joint) of 9 element entries.

    Each entry is a float constant or an array of shape ``(T,)``. Joints that share a
    rotation-channel order are converted together in one vectorised call.
    """
    starts = skeleton.channel_starts
    groups: dict[str, list[tuple[int, list[int]]]] = {}
    for j, chans in enumerate(skeleton.channels):
        axes = "".join(c[0] for c in chans if c.endswith("rotation"))
        cols = [int(starts[j]) + i for i, c in enumerate(chans) if c.endswith("rotation")]
        groups.setdefault(axes, []).append((j, cols))
    result: list[Any] = [None] * skeleton.n_joints
    for axes, members in groups.items():
        if not axes:
            for j, _ in members:
                result[j] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
            continue
        col_table = np.array([c for _, c in members], dtype=np.int64)  # (Jg, len(axes))
        # (len(axes), Jg, T): one contiguous row per joint keeps the later per-joint work fast.
        angles = values[:, col_table.T.ravel()].T.reshape(len(axes), len(members), -1)
        elements = euler_to_matrix_elements(angles, axes, degrees=True)
        for g, (j, _) in enumerate(members):
            result[j] = [e if isinstance(e, float) else e[g] for e in elements]
    return result


def local_translations(skeleton: Skeleton, values: np.ndarray, root_offset: str = "ignore",
                       joint_translation: str = "replace") -> list[Any]:
    """Local translation of every joint: a list of 3 entries (float or ``(T,)`` array)."""
    check_conventions(root_offset, joint_translation)
    starts = skeleton.channel_starts
    out = []
    for j, chans in enumerate(skeleton.channels):
        t: list[Any] = [float(v) for v in skeleton.offsets[j]]
        is_root = skeleton.parents[j] < 0
        mode = ("replace" if root_offset == "ignore" else "add") if is_root else joint_translation
        if mode != "ignore":
            for i, c in enumerate(chans):
                if c in POSITION_CHANNELS:
                    axis = POSITION_CHANNELS.index(c)
                    col = values[:, int(starts[j]) + i]
                    t[axis] = col if mode == "replace" else t[axis] + col
        out.append(t)
    return out


def _apply(rot: list[Any], vec: list[Any]) -> list[Any]:
    """``rot @ vec`` for element lists (vec entries are floats or arrays)."""
    out = []
    for i in range(3):
        acc = None
        for k in range(3):
            r, v = rot[3 * i + k], vec[k]
            if isinstance(r, float) and r == 0.0:
                continue
            if isinstance(v, float) and v == 0.0:
                continue
            term = r * v
            acc = term if acc is None else acc + term
        out.append(0.0 if acc is None else acc)
    return out


# Frames are processed in blocks: the many temporaries of one block stay in cache and their
# memory is reused, which is several times faster than whole-clip temporaries on long files.
BLOCK_FRAMES = 2048


@overload
def forward_kinematics(skeleton: Skeleton, values: np.ndarray, *, root_offset: str = ..., joint_translation: str = ...,
                       end_sites: bool = ..., world_rotations: Literal[False] = ...,
                       block_frames: int = ...) -> np.ndarray: ...
@overload
def forward_kinematics(skeleton: Skeleton, values: np.ndarray, *, root_offset: str = ..., joint_translation: str = ...,
                       end_sites: bool = ..., world_rotations: Literal[True],
                       block_frames: int = ...) -> tuple[np.ndarray, np.ndarray]: ...
def forward_kinematics(skeleton: Skeleton, values: np.ndarray, *, root_offset: str = "ignore",
                       joint_translation: str = "replace", end_sites: bool = False,
                       world_rotations: bool = False,
                       block_frames: int = BLOCK_FRAMES) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """World positions of every joint (and optionally End Site) for every frame.

    Args:
        skeleton: the hierarchy.
        values: ``(T, C)`` channel values in file order (degrees for rotations).
        root_offset, joint_translation: conventions, see the module docstring.
        end_sites: append the End Sites after the joints (named by ``skeleton.end_site_names``).
        world_rotations: also return the world rotation matrices ``(T, J, 3, 3)``.
        block_frames: frames computed together (a speed setting; results do not depend on it).

    Returns:
        positions ``(T, J[+E], 3)``; with ``world_rotations`` a tuple ``(positions, rotations)``.
    """
    values = np.asarray(values, dtype=np.float64)
    check_conventions(root_offset, joint_translation)
    n_frames = values.shape[0]
    n_joints = skeleton.n_joints
    n_out = n_joints + (len(skeleton.end_site_parents) if end_sites else 0)
    positions = np.empty((n_frames, n_out, 3), dtype=np.float64)
    rotations = np.empty((n_frames, n_joints, 9), dtype=np.float64) if world_rotations else None
    for start in range(0, max(n_frames, 1), block_frames):
        block = values[start:start + block_frames]
        pos, rot = _fk_block(skeleton, block, root_offset, joint_translation, end_sites, world_rotations)
        positions[start:start + len(block)] = pos.transpose(2, 0, 1)
        if rotations is not None and rot is not None:
            for j, elements in enumerate(rot):
                for k, e in enumerate(elements):
                    rotations[start:start + len(block), j, k] = e
    if rotations is None:
        return positions
    return positions, rotations.reshape(n_frames, n_joints, 3, 3)


def _fk_block(skeleton: Skeleton, values: np.ndarray, root_offset: str, joint_translation: str, end_sites: bool,
              world_rotations: bool) -> tuple[np.ndarray, list[list[Any]] | None]:
    n_frames = values.shape[0]
    n_joints = skeleton.n_joints
    rot_local = local_rotation_elements(skeleton, values)
    trans_local = local_translations(skeleton, values, root_offset, joint_translation)

    has_children = np.zeros(n_joints, dtype=bool)
    has_children[skeleton.parents[skeleton.parents >= 0]] = True
    if end_sites:
        has_children[skeleton.end_site_parents] = True

    n_out = n_joints + (len(skeleton.end_site_parents) if end_sites else 0)
    positions = np.empty((n_out, 3, n_frames), dtype=np.float64)
    world_rot: list[Any] = [None] * n_joints
    for j in range(n_joints):
        p = skeleton.parents[j]
        if p < 0:
            pos = trans_local[j]
            rot = rot_local[j]
        else:
            pos = [a + b for a, b in zip(positions[p], _apply(world_rot[p], trans_local[j]))]
            # The world rotation is only needed below joints with children (or if asked for).
            rot = multiply_elements(world_rot[p], rot_local[j]) if (has_children[j] or world_rotations) else None
        for a in range(3):
            positions[j, a] = pos[a]  # float entries broadcast over frames
        world_rot[j] = rot
    if end_sites:
        for e, (p, off) in enumerate(zip(skeleton.end_site_parents, skeleton.end_site_offsets)):
            moved = _apply(world_rot[p], [float(v) for v in off])
            for a in range(3):
                positions[n_joints + e, a] = positions[p, a] + moved[a]
    return positions, world_rot
