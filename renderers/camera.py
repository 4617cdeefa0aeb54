"""Cameras that frame a stick figure automatically, and the projection they render with.

Pure numpy (no OpenGL): the same :class:`Camera` drives pyrender and :meth:`Camera.project`,
so tests and tools can find where a joint lands in the picture.

Conventions: a camera *pose* is camera-to-world in the OpenGL convention (the camera looks
down its own -Z axis, +Y is up in the picture), the projection is the symmetric perspective
of pyrender's ``PerspectiveCamera``, and pixel coordinates are ``(u, v)`` with ``u`` to the
right and ``v`` downwards from the top-left *corner* of the image, so the pixel holding a
point is ``image[int(v), int(u)]``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from evalsuite.errors import InputError

VIEWS = {"front": 0.0, "three-quarter": 45.0, "side": 90.0}
FRAMINGS = ("full", "above-knees", "upper")
UP_AXES = {"y": np.array([0.0, 1.0, 0.0]), "z": np.array([0.0, 0.0, 1.0])}
# Facing direction assumed when the skeleton has no left/right joints to tell.
DEFAULT_FORWARD = {"y": np.array([0.0, 0.0, 1.0]), "z": np.array([0.0, -1.0, 0.0])}


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass(frozen=True)
class Camera:
    """A perspective camera looking from ``eye`` at ``target``; image ``width`` x ``height``."""

    eye: tuple
    target: tuple
    up: tuple
    yfov_deg: float
    width: int
    height: int
    znear: float
    zfar: float

    @property
    def aspect(self) -> float:
        return self.width / self.height

    def pose(self) -> np.ndarray:
        """Camera-to-world 4x4 matrix (OpenGL convention: looks down local -Z)."""
        eye = np.asarray(self.eye, float)
        z = _unit(eye - np.asarray(self.target, float))
        x = _unit(np.cross(np.asarray(self.up, float), z))
        y = np.cross(z, x)
        pose = np.eye(4)
        pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
        return pose

    def projection(self) -> np.ndarray:
        """4x4 OpenGL projection matrix, identical to pyrender's ``PerspectiveCamera``."""
        t = math.tan(math.radians(self.yfov_deg) / 2.0)
        n, f = self.znear, self.zfar
        p = np.zeros((4, 4))
        p[0, 0] = 1.0 / (self.aspect * t)
        p[1, 1] = 1.0 / t
        p[2, 2] = (f + n) / (n - f)
        p[2, 3] = 2.0 * f * n / (n - f)
        p[3, 2] = -1.0
        return p

    def project(self, points) -> np.ndarray:
        """Pixel coordinates ``(..., 2)`` = ``(u, v)`` of world points ``(..., 3)``.

        ``u = (x_ndc + 1) / 2 * width``, ``v = (1 - y_ndc) / 2 * height``; points behind
        the camera get NaN.
        """
        pts = np.asarray(points, dtype=np.float64)
        homo = np.concatenate([pts, np.ones(pts.shape[:-1] + (1,))], axis=-1)
        view = np.linalg.inv(self.pose())
        clip = homo @ (self.projection() @ view).T
        w = clip[..., 3:4]
        with np.errstate(divide="ignore", invalid="ignore"):
            ndc = np.where(w > 0, clip[..., :2] / w, np.nan)
        u = (ndc[..., 0] + 1.0) * 0.5 * self.width
        v = (1.0 - ndc[..., 1]) * 0.5 * self.height
        return np.stack([u, v], axis=-1)

    def with_size(self, width: int, height: int) -> Camera:
        return Camera(self.eye, self.target, self.up, self.yfov_deg, int(width), int(height), self.znear, self.zfar)

    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("eye", "target", "up"):
            d[k] = [float(x) for x in d[k]]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Camera:
        return cls(tuple(d["eye"]), tuple(d["target"]), tuple(d["up"]), float(d["yfov_deg"]),
                   int(d["width"]), int(d["height"]), float(d["znear"]), float(d["zfar"]))


def view_direction(forward, up_axis: str, view: str, elevation_deg: float) -> np.ndarray:
    """Unit vector from the figure towards the camera for a named view.

    ``front`` looks at the figure's face, ``side`` from its left, ``three-quarter`` halfway
    between; the camera is raised by ``elevation_deg`` and looks slightly down.
    """
    if view not in VIEWS:
        raise InputError(f"unknown view {view!r}; expected one of {', '.join(VIEWS)}", field="view")
    up = UP_AXES[up_axis]
    f = np.asarray(forward, float) - np.dot(forward, up) * up
    f = _unit(f) if np.linalg.norm(f) > 1e-9 else DEFAULT_FORWARD[up_axis]
    a = math.radians(VIEWS[view])
    horizontal = f * math.cos(a) + np.cross(up, f) * math.sin(a)
    e = math.radians(elevation_deg)
    return _unit(horizontal * math.cos(e) + up * math.sin(e))


def frame_points(points, direction, up_axis: str, width: int, height: int, *, yfov_deg: float = 30.0,
                 margin: float = 0.06, pad: float = 0.0, aim=None) -> Camera:
    """The camera along ``direction`` that fits every point (plus ``pad``) in the picture.

    The points' projected extent is centred and leaves ``margin`` (a fraction of the
    half-width/height) free on its tightest side. Fitting is exact for the perspective
    projection: the distance is the smallest at which every point is inside the shrunken
    frustum; centring is refined by a few fixed-point steps. With ``aim`` (a world point, e.g.
    the mean root position) the picture's vertical centre line passes through ``aim`` instead,
    and the extent is fitted symmetrically about it.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if len(pts) == 0:
        raise InputError("nothing to frame: the motion has no finite joint positions")
    up = UP_AXES[up_axis]
    zc = _unit(np.asarray(direction, float))
    xc = _unit(np.cross(up, zc))
    yc = np.cross(zc, xc)
    basis = np.stack([xc, yc, zc])            # rows: camera right, up, back
    local = pts @ basis.T                      # (N, 3) coordinates in the camera basis
    ty = math.tan(math.radians(yfov_deg) / 2.0)
    tx = ty * width / height
    sx, sy = tx * (1.0 - margin), ty * (1.0 - margin)
    centre = (local.min(axis=0) + local.max(axis=0)) / 2.0
    if aim is not None:
        centre[0] = float(np.asarray(aim, dtype=np.float64) @ xc)
    extent = float(np.max(local.max(axis=0) - local.min(axis=0))) + 2 * pad
    dist = 1.0
    for _ in range(6):
        rel = local - centre
        dist = float(np.max(np.maximum((np.abs(rel[:, 0]) + pad) / sx, (np.abs(rel[:, 1]) + pad) / sy)
                            + rel[:, 2] + pad))
        depth = dist - rel[:, 2]
        nx, ny = rel[:, 0] / (depth * tx), rel[:, 1] / (depth * ty)
        # Shift the aim so the projected extent is symmetric about the image centre.
        mid_x, mid_y = (nx.min() + nx.max()) / 2.0, (ny.min() + ny.max()) / 2.0
        if aim is not None:
            mid_x = 0.0   # the aim stays on the centre line
        if abs(mid_x) < 1e-4 and abs(mid_y) < 1e-4:
            break
        centre = centre + np.array([mid_x * tx * dist, mid_y * ty * dist, 0.0])
    rel = local - centre
    dist = float(np.max(np.maximum((np.abs(rel[:, 0]) + pad) / sx, (np.abs(rel[:, 1]) + pad) / sy)
                        + rel[:, 2] + pad))
    target = centre @ basis
    eye = target + zc * dist
    return Camera(tuple(eye), tuple(target), tuple(up), float(yfov_deg), int(width), int(height),
                  znear=max(dist - float(np.max(rel[:, 2])) - pad, 1e-3 * extent) * 0.25,
                  zfar=dist + 50.0 * extent)
