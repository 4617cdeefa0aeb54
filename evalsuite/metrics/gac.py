"""Gesture Area Coverage (Tonoli et al., "Gesture Area Coverage to Assess Gesture Expressiveness and
Human-Likeness", ICMI 2024 companion; code ``AI-Unicamp/gesture-area-coverage``).

A sequence's poses, in the body's frame, are drawn into a 2-D grid of pixels; a pixel is *covered* when
something was drawn on it in at least ``min_count`` frames (the union over time when 1). Two coverages,
natural ``N`` and generated ``G`` (boolean grids ``(P, P)``), are compared by

    TP = |N ∧ G|,   FP = |¬N ∧ G|,   FN = |N ∧ ¬G|   (pixels)
    Dice = 2 TP / (|N| + |G|) = 2 TP / (2 TP + FP + FN)

:class:`GacConvention` names every choice (what is drawn, the plane, the grid, the normalisation, the
binarisation); ``tonoli2024`` is the authors' code and the default.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.errors import InputError, did_you_mean

__all__ = ["GacConvention", "GAC_CONVENTIONS", "parse_gac", "body_frame", "gac_segments", "bresenham_pixels",
           "coverage", "coverage_stats", "dice"]

AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class GacConvention:
    """How poses become a coverage grid. Lengths are in the motion's units (GENEA 2023 BVH: centimetres)."""

    name: str = "tonoli2024"
    joints: str = "skeleton"
    """``skeleton``: every joint from index ``skip`` on (file order); else a group (``wrists``) or names J1;J2."""
    shape: str = "bones"
    """``bones``: the line from each joint to its parent in every frame; ``paths``: each joint's line from
    one drawn frame to the next."""
    skip: int = 2
    """With ``joints=skeleton``, the first joints left out (the authors' ``skipfirstjoints``: 2)."""
    plane: str = "xy"
    """The two axes drawn, horizontal then vertical (``xy``: the frontal plane of a Y-up skeleton)."""
    normalisation: str = "root"
    """``root``: positions minus the root joint's in every frame (the authors' ``posLckHips``);
    ``root_ground``: minus the root's ground-plane (x, z) position, height kept; ``none``."""
    grid_range: float = 200.0
    """Side of the square window drawn (units); beyond it points are clamped to the border pixels."""
    grid_step: float = 0.5
    """Pixel side (units); the grid has ``grid_range / grid_step`` pixels a side (400)."""
    origin_x: float = 0.5
    """Where the body's origin sits across the window, as a share of the range: ``origin_x * range`` is added
    to the horizontal coordinate before drawing (authors: ``+100`` with range 200, i.e. 0.5, centred)."""
    origin_y: float = 0.0
    """The same for the vertical coordinate (authors: 0, so all below the root joint's height is clamped to the
    bottom row; GENEA 2023's root ``body_world`` is on the ground, so nothing is)."""
    frame_skip: int = 1
    """Draw every ``frame_skip``-th frame (the paper's results: 1; their function's default: 5)."""
    min_count: int = 1
    """A pixel is covered when drawn at least this many times (authors: 1, ``clip(grid, 0, 1)``)."""

    @property
    def size(self) -> int:
        return int(self.grid_range / self.grid_step)


GAC_CONVENTIONS: dict[str, GacConvention] = {
    "tonoli2024": GacConvention(),
    "wrists": GacConvention(name="wrists", joints="wrists", shape="paths", normalisation="root_ground",
                            grid_step=2.0),
}
_KEYS = {"joints": "joints", "shape": "shape", "skip": "skip", "plane": "plane", "normalisation": "normalisation",
         "range": "grid_range", "step": "grid_step", "origin_x": "origin_x", "origin_y": "origin_y",
         "frame_skip": "frame_skip", "min_count": "min_count"}


def parse_gac(spec: str | GacConvention | None) -> GacConvention:
    """``"tonoli2024"``, ``"wrists"`` or ``"PRESET:key=value,..."`` (keys: joints, shape, skip, plane,
    normalisation, range, step, origin_x, origin_y, frame_skip, min_count) -> :class:`GacConvention`."""
    if spec is None:
        return GAC_CONVENTIONS["tonoli2024"]
    if isinstance(spec, GacConvention):
        return spec
    preset, _, rest = str(spec).partition(":")
    if preset not in GAC_CONVENTIONS:
        raise InputError(f"unknown GAC convention {preset!r}; expected one of {', '.join(GAC_CONVENTIONS)}"
                         f"{did_you_mean(preset, GAC_CONVENTIONS)}", field="gac")
    conv = GAC_CONVENTIONS[preset]
    changes: dict[str, Any] = {}
    for item in (s.strip() for s in rest.split(",") if s.strip()):
        key, eq, value = item.partition("=")
        if not eq or key not in _KEYS:
            raise InputError(f"expected KEY=VALUE with KEY one of {', '.join(_KEYS)}, got {item!r}"
                             f"{did_you_mean(key, _KEYS)}", field="gac")
        field = _KEYS[key]
        kind = type(getattr(conv, field))
        try:
            changes[field] = kind(value)
        except ValueError:
            raise InputError(f"{key} expects a {kind.__name__}, got {value!r}", field="gac") from None
    out = dataclasses.replace(conv, **changes) if changes else conv
    _check(out)
    return out


def _check(c: GacConvention) -> None:
    problems = []
    if c.shape not in ("bones", "paths"):
        problems.append(f"shape must be bones or paths, got {c.shape!r}")
    if len(c.plane) != 2 or any(a not in AXES for a in c.plane) or c.plane[0] == c.plane[1]:
        problems.append(f"plane must be two different axes of x, y, z (e.g. xy), got {c.plane!r}")
    if c.normalisation not in ("root", "root_ground", "none"):
        problems.append(f"normalisation must be root, root_ground or none, got {c.normalisation!r}")
    if not (c.grid_step > 0 and c.grid_range >= c.grid_step):
        problems.append(f"need step > 0 and range >= step, got range={c.grid_range:g}, step={c.grid_step:g}")
    if c.frame_skip < 1 or c.min_count < 1 or c.skip < 0:
        problems.append("frame_skip and min_count must be at least 1 and skip at least 0")
    if problems:
        raise InputError("; ".join(problems), field="gac")


def body_frame(pos: np.ndarray, root: int, normalisation: str) -> np.ndarray:
    """Positions ``(T, J, 3)`` in the body's frame: minus the root's ``(T, 1, 3)`` position (``root``), its
    ground-plane part only (``root_ground``, Y-up: x and z) or unchanged (``none``)."""
    if normalisation == "none":
        return pos
    origin = pos[:, root:root + 1].copy()
    if normalisation == "root_ground":
        origin[..., 1] = 0.0
    return np.asarray(pos - origin)


def gac_segments(pos: np.ndarray, parents: np.ndarray, names: list[str], conv: GacConvention) -> np.ndarray:
    """The line segments drawn, ``(S, 2, 2)`` (start, end) x (horizontal, vertical), from positions
    ``(T, J, 3)`` already in the body's frame: bones of the drawn frames ``0, k, 2k, ...`` (k = frame_skip),
    joint by joint, or each joint's path between consecutive drawn frames."""
    joints = _joint_indices(names, parents, conv)
    ax = [AXES[a] for a in conv.plane]
    frames = pos[::conv.frame_skip][:, :, ax]                       # (F, J, 2)
    if conv.shape == "bones":
        start, end = frames[:, parents[joints]], frames[:, joints]   # (F, B, 2)
    else:
        start, end = frames[:-1, joints], frames[1:, joints]
    return np.stack([start.reshape(-1, 2), end.reshape(-1, 2)], axis=1)


def _joint_indices(names: list[str], parents: np.ndarray, conv: GacConvention) -> np.ndarray:
    if conv.joints == "skeleton":
        idx = [i for i in range(conv.skip, len(names)) if parents[i] >= 0 or conv.shape == "paths"]
    else:
        from evalsuite.metrics.planning import find_group

        wanted = find_group(conv.joints, names) or [j.strip() for j in conv.joints.split(";") if j.strip()]
        missing = [j for j in wanted if j not in names]
        if missing or not wanted:
            raise InputError(f"GAC joints {conv.joints!r}: {', '.join(missing) or 'none found'} not in the "
                             f"skeleton{did_you_mean(missing[0] if missing else conv.joints, names)}", field="gac")
        idx = [names.index(j) for j in wanted]
    if conv.shape == "bones" and any(parents[i] < 0 for i in idx):
        raise InputError("GAC shape bones needs each drawn joint's parent; this motion has none (positions "
                         "without a hierarchy): use shape=paths", field="gac")
    if not idx:
        raise InputError("GAC draws no joint: the skeleton has no joint after the skipped ones", field="gac")
    return np.asarray(idx, dtype=np.int64)


def bresenham_pixels(segments: np.ndarray, conv: GacConvention) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of every pixel drawn for the segments ``(S, 2, 2)``, one entry per pixel and segment.

    Each end ``(u, v)`` becomes the pixel ``(round((u + origin_x R) / step), round((v + origin_y R) / step))``
    (R the range)
    (round half to even), clamped to ``[0, P-1]``; the pixels between are Bresenham's line (the all-octant
    form with ``err = dx - dy``); a pixel (i, j) is the grid's row ``P - 1 - j``, column ``i`` (up is up)."""
    n = conv.size
    inv = 1.0 / conv.grid_step
    ends = np.rint(np.stack([(segments[..., 0] + conv.origin_x * conv.grid_range) * inv,
                             (segments[..., 1] + conv.origin_y * conv.grid_range) * inv], axis=-1))
    ends = np.clip(ends, 0, n - 1).astype(np.int64)                  # (S, 2 ends, 2 coords)
    x, y, x1, y1 = ends[:, 0, 0], ends[:, 0, 1], ends[:, 1, 0], ends[:, 1, 1]
    dx, dy = np.abs(x1 - x), np.abs(y1 - y)
    sx, sy = np.where(x < x1, 1, -1), np.where(y < y1, 1, -1)
    err = dx - dy
    rows, cols = [], []
    while x.size:
        rows.append(n - 1 - y)
        cols.append(x)
        going = (x != x1) | (y != y1)
        x, y, x1, y1, dx, dy, sx, sy, err = (a[going] for a in (x, y, x1, y1, dx, dy, sx, sy, err))
        e2 = 2 * err
        step_x, step_y = e2 > -dy, e2 < dx
        err = err - np.where(step_x, dy, 0) + np.where(step_y, dx, 0)
        x = x + np.where(step_x, sx, 0)
        y = y + np.where(step_y, sy, 0)
    return np.concatenate(rows), np.concatenate(cols)


def coverage(pos: np.ndarray, parents: np.ndarray, names: list[str], conv: GacConvention) -> np.ndarray:
    """Boolean coverage grid ``(P, P)`` of positions ``(T, J, 3)`` (all joints of the motion, file order):
    body frame, segments, pixels, then ``count >= min_count``."""
    roots = np.flatnonzero(np.asarray(parents) < 0)
    local = body_frame(np.asarray(pos, dtype=np.float64), int(roots[0]) if roots.size else 0, conv.normalisation)
    seg = gac_segments(local, np.asarray(parents), names, conv)
    n = conv.size
    if not len(seg):
        return np.zeros((n, n), dtype=bool)
    r, c = bresenham_pixels(seg, conv)
    counts = np.bincount(r * n + c, minlength=n * n)
    return (counts >= conv.min_count).reshape(n, n)


def coverage_stats(natural: np.ndarray, generated: np.ndarray) -> dict[str, int]:
    """Pixel counts of two boolean grids: ``tp``, ``fp`` (generated only), ``fn`` (natural only),
    ``area_natural`` = |N|, ``area`` = |G|."""
    nat, gen = np.asarray(natural, dtype=bool), np.asarray(generated, dtype=bool)
    return {"tp": int(np.count_nonzero(nat & gen)), "fp": int(np.count_nonzero(gen & ~nat)),
            "fn": int(np.count_nonzero(nat & ~gen)), "area_natural": int(nat.sum()), "area": int(gen.sum())}


def dice(tp: Any, fp: Any, fn: Any) -> Any:
    """Dice = 2 TP / (2 TP + FP + FN) (elementwise; NaN where both grids are empty)."""
    tp, fp, fn = (np.asarray(v, dtype=np.float64) for v in (tp, fp, fn))
    with np.errstate(invalid="ignore", divide="ignore"):
        return 2 * tp / (2 * tp + fp + fn)
