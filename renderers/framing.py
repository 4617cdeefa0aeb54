"""The shared view of a segment: one static camera, figure size and floor for every condition.

The camera looks at the segment's mean root position: horizontally the root's mean is the centre of the
picture (a static camera as the GENEA Leaderboard places it; with ``center`` on, every clip's mean root is
moved to the origin first, see :func:`renderers.render.center_on_ground`), and the distance is the smallest
that keeps every framed point (plus the body's thickness) inside the picture with the margin. Framings:

- ``full``: every joint;
- ``above-knees``: down to the knees (the GENEA Leaderboard's cut, which hides foot sliding): ankles, feet and
  toes are left out of the framing (and fall below the picture's bottom edge);
- ``upper``: the upper body (no leg joints; the hips' root stays).

Without recognisable names the joints in the top 72 % (above-knees) or 55 % (upper) of the mean pose's height
are framed.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from evalsuite.errors import InputError
from renderers.camera import UP_AXES, Camera, frame_points, view_direction
from renderers.figure import body_size, forward_direction, head_index, head_marker_centres, leg_mask
from renderers.styles import STYLES
from renderers.styles.bones import BELOW_KNEE, body_scale, has_legs, joint_kinds

if TYPE_CHECKING:
    from renderers.scene import RenderSettings


@dataclass(frozen=True)
class View:
    """What the conditions of one segment share: camera, figure size and floor."""

    camera: Camera
    size: float
    floor_height: float | None = None
    floor_centre: tuple = (0.0, 0.0, 0.0)

    def to_dict(self) -> dict:
        return {"camera": self.camera.to_dict(), "size": float(self.size),
                "floor_height": None if self.floor_height is None else float(self.floor_height),
                "floor_centre": [float(x) for x in self.floor_centre]}

    @classmethod
    def from_dict(cls, d: dict) -> View:
        return cls(Camera.from_dict(d["camera"]), float(d["size"]), d["floor_height"], tuple(d["floor_centre"]))


def floor_on(settings: RenderSettings, names_sets=None, parents_sets=None) -> bool:
    """Whether a floor is drawn: the style setting, or when unset (None) the body style's default, except under
    skeletons none of which has legs (an upper body standing on a floor looks like a chess piece)."""
    if settings.style.floor is not None:
        return bool(settings.style.floor)
    known = [(n, p) for n, p in zip(names_sets or [], parents_sets or []) if p is not None]
    if known and not any(has_legs(joint_kinds(n, p)) for n, p in known):
        return False
    return bool(getattr(STYLES[settings.body], "floor", False))


def framed_mask(positions: np.ndarray, names, parents, up: np.ndarray, framing: str) -> np.ndarray:
    """The joints the camera frames under ``framing`` (see the module doc)."""
    if framing == "full":
        return np.ones(positions.shape[1], dtype=bool)
    if parents is not None:
        kinds = joint_kinds(names, parents)
        if not has_legs(kinds) and {"shoulder", "neck"} & set(kinds):
            return np.ones(positions.shape[1], dtype=bool)   # an upper body: no leg to leave out
    if framing == "upper":
        legs = leg_mask(names)
        keep, share, named = ~legs, 0.55, bool(legs.any() and not legs.all())
    else:
        kinds = joint_kinds(names, parents if parents is not None else [-1] * len(names))
        keep, share = ~np.isin(kinds, BELOW_KNEE), 0.72
        named = bool(np.isin(kinds, ["knee", "hip"]).any())
    if named:
        return keep
    heights = np.nanmean(positions @ up, axis=0)
    lo, hi = float(np.nanmin(heights)), float(np.nanmax(heights))
    return heights >= hi - share * (hi - lo)


def _root_index(parents) -> int:
    if parents is None:
        return 0
    roots = np.flatnonzero(np.asarray(parents) < 0)
    return int(roots[0]) if len(roots) else 0


def make_view(position_sets, names_sets, settings: RenderSettings, parents_sets=None) -> View:
    """The shared :class:`View` for several motions (the conditions of one segment).

    Args:
        position_sets: list of world positions ``(T, J, 3)``, one per condition.
        names_sets: the joint names of each.
        parents_sets: the parent indices of each (the head, the root the camera aims at, the knees), optional.
    """
    if not position_sets:
        raise InputError("no motion to frame")
    up = UP_AXES[settings.up_axis]
    size = float(np.median([body_size(p) for p in position_sets]))
    forward = None
    for pos, names in zip(position_sets, names_sets):
        forward = forward_direction(pos, names, up)
        if forward is not None:
            break
    if forward is None:
        forward = np.array([0.0, 0.0, 1.0]) if settings.up_axis == "y" else np.array([0.0, -1.0, 0.0])
    direction = view_direction(forward, settings.up_axis, settings.view, settings.elevation_deg)
    style = settings.style
    body = STYLES[settings.body]
    pts: list[np.ndarray] = []
    roots: list[np.ndarray] = []
    for k, (pos, names) in enumerate(zip(position_sets, names_sets)):
        pos = np.asarray(pos, float)
        parents = parents_sets[k] if parents_sets is not None else None
        if style.head_marker or settings.body != "stick":
            head = head_index(names)
            if head is not None:
                hp = int(parents[head]) if parents is not None else -1
                # a body's head is as big as its stature says, also on an upper body (styles.bones.body_scale)
                scale = size if settings.body == "stick" or parents is None else body_scale(names, parents, pos, size)
                r = style.head_radius * scale
                centres = head_marker_centres(pos, head, hp, r)
                # the head's extreme points along the world axes (it is much bigger than a joint)
                offsets = np.concatenate([np.eye(3), -np.eye(3)]) * r
                pts.append((centres[:, None, :] + offsets[None]).reshape(-1, 3))
        roots.append(np.nanmean(pos[:, _root_index(parents)], axis=0))
        if hasattr(body, "frame_points"):   # parts of the body well beyond its joints (the mannequin's mittens)
            pts.append(np.asarray(body.frame_points(pos, names, parents, size), float).reshape(-1, 3))
        pts.append(pos[:, framed_mask(pos, names, parents, up, settings.framing)].reshape(-1, 3))
    floor = floor_on(settings, names_sets, parents_sets)
    if floor and settings.framing == "full":   # the feet stand on the floor inside the picture
        lowest = min(float(np.nanmin(np.asarray(p, float) @ up)) for p in position_sets)
        ground = np.nanmean(roots, axis=0)
        pts.append((ground + (lowest - ground @ up - style.joint_radius * size) * up)[None])
    cloud = np.concatenate(pts)
    pad = size * max(style.joint_radius * 1.2, float(getattr(body, "frame_pad", 0.0)))
    camera = frame_points(cloud, direction, settings.up_axis, settings.width, settings.height,
                          yfov_deg=settings.yfov_deg, margin=settings.margin, pad=pad,
                          aim=np.nanmean(roots, axis=0))
    floor_height = None
    centre = tuple(float(x) for x in np.nanmean(np.concatenate([p.reshape(-1, 3) for p in position_sets]), axis=0))
    if floor:
        all_pts = np.concatenate([np.asarray(p, float).reshape(-1, 3) for p in position_sets])
        floor_height = float(np.nanmin(all_pts @ up)) - style.joint_radius * size
    return View(camera, size, floor_height, centre)
