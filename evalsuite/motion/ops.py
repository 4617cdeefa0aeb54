"""Operations on a :class:`~evalsuite.motion.Motion`: select joints, resample, cut, center.

All of them return a new Motion and leave the input unchanged.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evalsuite.errors import MotionError
from evalsuite.motion.motion import Motion
from evalsuite.motion.presets import resolve_joints
from evalsuite.motion.rotations import elements_to_array, quaternion_slerp
from evalsuite.motion.skeleton import POSITION_CHANNELS, Skeleton

__all__ = ["select_joints", "drop_joints", "resample", "cut", "center"]


def _resolve(motion: Motion, joints: str | Sequence[str]) -> list[str]:
    try:
        return resolve_joints(joints, motion.joint_names)
    except KeyError as exc:
        raise MotionError(f"joints not in the motion: {exc.args[0]}; it has: {', '.join(motion.joint_names)}",
                          path=motion.source) from None


def select_joints(motion: Motion, joints: str | Sequence[str]) -> Motion:
    """Keep the named joints (a preset name, ``"A,B,C"`` or a list), in the motion's order.

    If every kept joint's parent is kept too (e.g. dropping fingers or legs), a BVH motion
    stays a BVH motion: the skeleton is pruned and a kept joint that loses all its children
    gets an End Site at its first removed child's offset, so its bone is still drawn.
    Otherwise (e.g. the GENEA 2020 upper body, which leaves out the root) the result holds
    world positions, with each joint's parent mapped to its nearest kept ancestor.
    """
    wanted = set(_resolve(motion, joints))
    keep = [j for j, n in enumerate(motion.joint_names) if n in wanted]
    parents = motion.parents
    closed = all(parents[j] < 0 or parents[j] in keep for j in keep)
    if motion.is_hierarchical and closed:
        return _prune(motion, keep)
    index = {j: i for i, j in enumerate(keep)}
    new_parents = []
    for j in keep:
        p = parents[j]
        while p >= 0 and p not in index:
            p = parents[p]
        new_parents.append(index[p] if p >= 0 else -1)
    pos = motion.positions()[:, keep]
    return motion.with_positions(pos, joint_names=[motion.joint_names[j] for j in keep], parents=new_parents)


def drop_joints(motion: Motion, joints: str | Sequence[str]) -> Motion:
    """Remove the named joints; see :func:`select_joints` for what the result holds."""
    drop = set(_resolve(motion, joints))
    return select_joints(motion, [n for n in motion.joint_names if n not in drop])


def _prune(motion: Motion, keep: list[int]) -> Motion:
    sk = motion.skeleton
    index = {j: i for i, j in enumerate(keep)}
    starts = sk.channel_starts
    cols = [int(starts[j]) + c for j in keep for c in range(len(sk.channels[j]))]
    end_parents, end_offsets = [], []
    for p, off in zip(sk.end_site_parents, sk.end_site_offsets):
        if p in index:
            end_parents.append(index[p])
            end_offsets.append(off)
    for j in keep:
        lost = [c for c in sk.children(j) if c not in index]
        if lost and not any(c in index for c in sk.children(j)) and index[j] not in end_parents:
            end_parents.append(index[j])
            end_offsets.append(sk.offsets[lost[0]])
    order = np.argsort(end_parents, kind="stable")
    new = Skeleton([sk.names[j] for j in keep],
                   np.asarray([index[sk.parents[j]] if sk.parents[j] >= 0 else -1 for j in keep], dtype=np.int64),
                   sk.offsets[keep], [sk.channels[j] for j in keep],
                   np.asarray(end_parents, dtype=np.int64)[order], np.asarray(end_offsets).reshape(-1, 3)[order])
    return motion.with_values(motion.values[:, cols], skeleton=new)


def _new_times(n_frames: int, fps: float, new_fps: float) -> np.ndarray:
    last = (n_frames - 1) / fps
    n_new = int(np.floor(last * new_fps + 1e-9)) + 1 if n_frames else 0
    return np.arange(n_new) / new_fps


def resample(motion: Motion, fps: float) -> Motion:
    """Resample to ``fps``: slerp for rotations, linear interpolation for positions.

    New frames sit at ``k / fps`` seconds for every ``k`` up to the last original frame's
    time. At an integer ratio (60 -> 30 fps) the kept frames are exactly the original ones,
    as PyMO's ``DownSampler`` keeps every n-th frame.
    """
    if not (np.isfinite(fps) and fps > 0):
        raise MotionError(f"fps must be a positive number, got {fps!r}")
    if abs(fps - motion.fps) < 1e-9 * fps:
        return motion
    times = _new_times(motion.n_frames, motion.fps, float(fps))
    src = times * motion.fps
    i0 = np.minimum(np.floor(src + 1e-9).astype(np.int64), max(motion.n_frames - 1, 0))
    i1 = np.minimum(i0 + 1, max(motion.n_frames - 1, 0))
    w = np.clip(src - i0, 0.0, 1.0)
    w[np.abs(w) < 1e-9] = 0.0
    if not motion.is_hierarchical:
        pos = motion.positions()
        new = pos[i0] * (1 - w)[:, None, None] + pos[i1] * w[:, None, None]
        return motion.with_positions(new, fps=fps)
    sk = motion.skeleton
    values = motion.values
    out = values[i0] * (1 - w)[:, None] + values[i1] * w[:, None]  # exact for position channels
    starts = sk.channel_starts
    from scipy.spatial.transform import Rotation  # here, not at the top: rendering imports ops (1 s of scipy)

    from evalsuite.motion.fk import local_rotation_elements

    local = local_rotation_elements(sk, values)
    for j, chans in enumerate(sk.channels):
        rot_idx = [i for i, c in enumerate(chans) if c.endswith("rotation")]
        axes = "".join(chans[i][0] for i in rot_idx)
        cols = [int(starts[j]) + i for i in rot_idx]
        if len(axes) == 3 and len(set(axes)) == 3:
            quats = Rotation.from_matrix(elements_to_array(local[j], (motion.n_frames,))).as_quat()
            q = quaternion_slerp(quats[i0], quats[i1], w)
            out[:, cols] = Rotation.from_quat(q).as_euler(axes, degrees=True)
        elif cols:
            unwrapped = np.unwrap(values[:, cols], period=360.0, axis=0)
            out[:, cols] = unwrapped[i0] * (1 - w)[:, None] + unwrapped[i1] * w[:, None]
    exact = w == 0.0
    out[exact] = values[i0[exact]]  # frames that coincide keep their exact original values
    return motion.with_values(out, fps=fps)


def cut(motion: Motion, start: float = 0.0, end: float | None = None, *, past_end: bool = True) -> Motion:
    """Frames from ``start`` to ``end`` seconds: frame ``round(start*fps)`` up to, not incl., ``round(end*fps)``.

    ``end=None`` keeps everything after ``start``. With ``past_end=False`` an ``end`` after the
    last frame (``round(end*fps) > n_frames``, i.e. past ``duration`` by half a frame or more) is an
    error instead of being clipped to the end of the motion.
    """
    where = f"{motion.duration:g} s ({motion.n_frames} frames @ {motion.fps:g} fps)"
    span = f"cut {start:g} s to {'the end' if end is None else f'{end:g} s'}"
    if not np.isfinite(start) or (end is not None and not np.isfinite(end)):
        raise MotionError(f"{span}: start and end must be finite numbers of seconds", path=motion.source)
    if end is not None and end <= start:
        raise MotionError(f"{span} is empty: the end must come after the start", path=motion.source)
    first = int(round(start * motion.fps))
    last = motion.n_frames if end is None else int(round(end * motion.fps))
    if start < 0:
        raise MotionError(f"{span}: the start must be 0 s or later", path=motion.source)
    if first >= motion.n_frames:
        raise MotionError(f"{span} starts outside the motion, which lasts {where}", path=motion.source)
    if last <= first:
        raise MotionError(f"{span} holds no frame at {motion.fps:g} fps", path=motion.source)
    if not past_end and last > motion.n_frames:
        raise MotionError(f"{span} ends outside the motion, which lasts {where}", path=motion.source)
    if motion.is_hierarchical:
        return motion.with_values(motion.values[first:last])
    return motion.with_positions(motion.positions()[first:last])


def center(motion: Motion, joint: str | None = None, axes: str = "xz") -> Motion:
    """Subtract a joint's trajectory (default: the root) on ``axes`` from the whole body.

    ``axes="xz"`` (default) is hip-centering on the ground plane of a Y-up BVH; ``"xyz"``
    puts the joint at the origin in every frame. A BVH motion centred on its root keeps its
    hierarchy (only the root's position channels change); otherwise positions are returned.
    """
    ax = ["xyz".index(a) for a in axes.lower() if a in "xyz"]
    if not ax or len(ax) != len(axes):
        raise MotionError(f"axes must be letters from 'xyz', got {axes!r}")
    sk = motion.skeleton
    j = sk.roots[0] if joint is None else motion.joint_index(joint)
    root_channels = {c: i for i, c in enumerate(sk.channels[j])} if motion.is_hierarchical else {}
    if motion.is_hierarchical and sk.parents[j] < 0 and len(sk.roots) == 1 and all(
            POSITION_CHANNELS[a] in root_channels for a in ax):
        root_pos = motion.positions()[:, j]
        values = motion.values.copy()
        start = int(sk.channel_starts[j])
        for a in ax:
            values[:, start + root_channels[POSITION_CHANNELS[a]]] -= root_pos[:, a]
        return motion.with_values(values)
    pos = motion.positions().copy()
    ref = pos[:, j, :].copy()
    for a in ax:
        pos[:, :, a] -= ref[:, None, a]
    return motion.with_positions(pos)
