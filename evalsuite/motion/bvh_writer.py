"""BVH writing: a :class:`~evalsuite.motion.skeleton.Skeleton` and ``(T, C)`` channel values as BVH text
(tabs, LF line endings, ``Frame Time`` with 10 significant digits)."""
from __future__ import annotations

import io
import os

import numpy as np

from evalsuite.motion.skeleton import Skeleton

__all__ = ["format_bvh", "write_bvh"]


def _fmt(x: float, precision: int = 6) -> str:
    return f"{x:.{precision}f}"


def format_bvh(skeleton: Skeleton, values: np.ndarray, frame_time: float, precision: int = 6) -> str:
    """BVH text for a skeleton and ``(T, C)`` channel values (tabs, LF line endings); ``precision`` decimals
    for the values and ``max(6, precision)`` for the OFFSETs. Joints are written depth first (a skeleton
    in another order, such as SMPL-X's, has its columns reordered to match)."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] != skeleton.n_channels:
        raise ValueError(f"values must have shape (T, {skeleton.n_channels}), got {values.shape}")
    offset_digits = max(6, precision)   # OFFSETs keep 6 decimals at least, more when the values get more
    out = io.StringIO()
    out.write("HIERARCHY\n")
    children: dict[int, list[int]] = {j: [] for j in range(skeleton.n_joints)}
    for j, p in enumerate(skeleton.parents):
        if p >= 0:
            children[int(p)].append(j)
    ends: dict[int, list[int]] = {j: [] for j in range(skeleton.n_joints)}
    for e, p in enumerate(skeleton.end_site_parents):
        ends[int(p)].append(e)

    def write_joint(j: int, depth: int) -> None:
        ind = "\t" * depth
        order.append(j)
        kind = "ROOT" if skeleton.parents[j] < 0 else "JOINT"
        out.write(f"{ind}{kind} {skeleton.names[j]}\n{ind}{{\n")
        out.write(f"{ind}\tOFFSET {' '.join(_fmt(v, offset_digits) for v in skeleton.offsets[j])}\n")
        chans = skeleton.channels[j]
        out.write(f"{ind}\tCHANNELS {len(chans)}{''.join(' ' + c for c in chans)}\n")
        for c in children[j]:
            write_joint(c, depth + 1)
        for e in ends[j]:
            out.write(f"{ind}\tEnd Site\n{ind}\t{{\n")
            out.write(f"{ind}\t\tOFFSET {' '.join(_fmt(v, offset_digits) for v in skeleton.end_site_offsets[e])}\n")
            out.write(f"{ind}\t}}\n")
        out.write(f"{ind}}}\n")

    order: list[int] = []
    for root in skeleton.roots:
        write_joint(root, 0)
    if order != sorted(order):   # joints not in depth-first order (SMPL-X): the columns follow the file's order
        starts = skeleton.channel_starts
        cols = [int(starts[j]) + k for j in order for k in range(len(skeleton.channels[j]))]
        values = values[:, cols]
    out.write(f"MOTION\nFrames: {len(values)}\nFrame Time: {frame_time:.10g}\n")
    if len(values) and values.shape[1]:
        np.savetxt(out, values, fmt=f"%.{precision}f", delimiter=" ")
    return out.getvalue()


def write_bvh(path: str | os.PathLike[str], skeleton: Skeleton, values: np.ndarray, frame_time: float,
              precision: int = 6) -> None:
    """Write :func:`format_bvh` text to ``path`` (UTF-8)."""
    text = format_bvh(skeleton, values, frame_time, precision)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
