"""Which joints of a skeleton are part of the body: only those are drawn and framed.

Motion-capture skeletons carry joints that are not part of the body: a world/reference
root at the origin of the room (GENEA 2022/2023 ``body_world``, whose bone to the pelvis
``b_root`` would be drawn as a pole down to the floor) and zero-length helpers (CMU's
``LHipJoint``/``RHipJoint``/``LowerBack``, which sit exactly on ``Hips``). The rule,
decided from the data of the clip (positions ``(T, J, 3)``, figure size ``s`` from
:func:`~renderers.figure.body_size` over the non-root joints):

* **zero-length helper**: a non-root joint whose distance to its parent is below
  ``1e-3 * s`` in every frame (never the head joint: the head marker hangs from it);
* **world/reference root**: a root whose nearest child (after skipping helpers) is more
  than ``0.2 * s`` away in the median frame (a pelvis is within about 0.1 s of its
  hips and spine) *and* which is named like a world/reference root (``world``,
  ``body_world``, ``reference``, ``*_world``), or stays put (moves less than ``0.02 * s``
  over the clip), or lies at the floor (no higher than the lowest body joint + ``0.05 * s``).

Dropped joints' children hang from their nearest kept ancestor, so helpers leave the
bones unchanged and the children of a world root become roots. ``drop_joints`` names
further joints to leave out (``--drop-joints``, ``drop_joints:`` in a stimuli config).
"""
from __future__ import annotations

import re

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion import Motion
from renderers.camera import UP_AXES
from renderers.figure import body_size, head_index

_WORLD_RE = re.compile(r"^(world|body_?world|reference|ref_?root|.*_world|world_.*)$")
HELPER_LENGTH = 1e-3     # x figure size: a bone shorter than this in every frame is a helper
ANCHOR_DISTANCE = 0.2    # x figure size: a root this far from its nearest child is no pelvis
STATIC_RANGE = 0.02      # x figure size: a root that moves less than this over the clip stays put
FLOOR_TOLERANCE = 0.05   # x figure size


def joint_list(value) -> tuple[str, ...]:
    """Joint names from a comma-separated string or a list (``drop_joints`` settings)."""
    if value is None or value == "":
        return ()
    if isinstance(value, str):
        items = value.split(",")
    elif isinstance(value, (list, tuple)):
        items = list(value)
    else:
        raise InputError(f"expected joint names (a list or comma-separated text), got {value!r}",
                         field="drop_joints")
    return tuple(str(n).strip() for n in items if str(n).strip())


def is_world_name(name: str) -> bool:
    """True for names of world/reference roots (``body_world``, ``World``, ``reference``)."""
    return bool(_WORLD_RE.match(name.rsplit(":", 1)[-1].lower()))


def non_body_joints(names, parents, positions, up_axis: str = "y") -> np.ndarray:
    """Boolean mask ``(J,)`` of the joints that are not part of the body (see the module doc).

    Args:
        names: joint names ``(J,)``.
        parents: parent index per joint ``(J,)``, -1 for roots.
        positions: world positions ``(T, J, 3)``.
    """
    names = list(names)
    parents = np.asarray(parents, dtype=np.int64)
    pos = np.asarray(positions, dtype=np.float64)
    n = len(names)
    roots = parents < 0
    size = body_size(pos[:, ~roots]) if (~roots).any() else body_size(pos)
    head = head_index(names)
    drop = np.zeros(n, dtype=bool)
    with np.errstate(invalid="ignore"):
        for j in np.flatnonzero(~roots):
            if j != head:
                length = np.linalg.norm(pos[:, j] - pos[:, parents[j]], axis=-1)
                drop[j] = bool(np.all(np.nan_to_num(length, nan=np.inf) < HELPER_LENGTH * size))
    effective = _reparent(parents, drop)
    up = UP_AXES[up_axis]
    heights = np.nanmedian(pos @ up, axis=0)                      # (J,)
    for r in np.flatnonzero(roots):
        children = np.flatnonzero((effective == r) & ~drop)
        if len(children) == 0:
            continue
        gaps = np.nanmedian(np.linalg.norm(pos[:, children] - pos[:, r:r + 1], axis=-1), axis=0)
        if not np.nanmin(gaps) > ANCHOR_DISTANCE * size:
            continue
        others = ~drop & ~roots
        static = float(np.nanmax(np.ptp(pos[:, r], axis=0))) < STATIC_RANGE * size
        at_floor = others.any() and heights[r] <= float(np.nanmin(heights[others])) + FLOOR_TOLERANCE * size
        if is_world_name(names[r]) or static or at_floor:
            drop[r] = True
    return drop


def _reparent(parents: np.ndarray, drop: np.ndarray) -> np.ndarray:
    """Parent of each joint once the dropped joints are gone: the nearest kept ancestor, or -1."""
    out = parents.copy()
    for j in range(len(parents)):
        p = int(parents[j])
        while p >= 0 and drop[p]:
            p = int(parents[p])
        out[j] = p
    return out


def body_motion(motion: Motion, up_axis: str = "y", drop_joints=()) -> Motion:
    """``motion`` without its non-body joints and the joints named in ``drop_joints``.

    Returns the motion unchanged when nothing is dropped, else a positional motion whose
    kept joints hang from their nearest kept ancestor.
    """
    names = motion.joint_names
    unknown = [j for j in drop_joints if j not in names]
    if unknown:
        raise InputError(f"drop_joints names {', '.join(repr(j) for j in unknown)}, not a joint of this motion "
                         f"(its joints: {', '.join(names[:12])}{', ...' if len(names) > 12 else ''})",
                         path=motion.source, field="drop_joints")
    pos = motion.positions()
    drop = non_body_joints(names, motion.parents, pos, up_axis)
    drop |= np.isin(names, list(drop_joints))
    if not drop.any():
        return motion
    if drop.all():
        raise InputError("every joint would be dropped; nothing is left to draw", path=motion.source,
                         field="drop_joints")
    keep = np.flatnonzero(~drop)
    new_index = np.full(len(names), -1, dtype=np.int64)
    new_index[keep] = np.arange(len(keep))
    parents = _reparent(np.asarray(motion.parents, dtype=np.int64), drop)[keep]
    parents = np.where(parents >= 0, new_index[np.maximum(parents, 0)], -1)
    return Motion.from_positions(pos[:, keep], [names[k] for k in keep], motion.fps, parents,
                                 name=motion.name, source=motion.source)
