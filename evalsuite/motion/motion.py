"""The one motion type that flows through evalsuite."""
from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np
import numpy.typing as npt

from evalsuite.errors import MotionError
from evalsuite.motion.fk import check_conventions, forward_kinematics
from evalsuite.motion.skeleton import Skeleton


def _clean_fps(frame_time: float) -> float:
    """fps from a frame time in seconds, snapped to a whole rate where the value is that rate's frame time as
    written: ``0.0333333`` gives 30.0, not 30.0000003, and ``0.03333`` (how GENEA and many exporters write
    30 fps) gives 30.0, not 30.003.

    Two rules: the rate is within 1e-4 (relative) of a whole number, or the frame time printed with its
    shortest decimal digits (``repr``) equals a whole rate's frame time rounded to those digits (rates 1-1000).
    """
    fps = 1.0 / frame_time
    nearest = round(fps)
    if nearest > 0 and abs(fps - nearest) <= 1e-4 * nearest:
        return float(nearest)
    printed = repr(float(frame_time))
    if "e" not in printed and "." in printed:
        decimals = len(printed.partition(".")[2])
        if decimals >= 2:
            for rate in sorted(range(max(1, int(fps) - 2), min(1000, int(fps) + 3) + 1), key=lambda r: abs(r - fps)):
                if round(1.0 / rate, decimals) == float(printed):
                    return float(rate)
    return fps


class Motion:
    """A skeleton with per-frame values, at a frame rate.

    Two kinds, one interface:

    * *hierarchical* motion (from BVH): a :class:`Skeleton` with channels and ``values``
      of shape ``(T, C)``; world positions come from forward kinematics under the
      conventions given at load time (``root_offset``, ``joint_translation``, see
      :mod:`evalsuite.motion.fk`);
    * *positional* motion (from ``.npy``/``.npz``/``.csv`` or after operations that
      leave the hierarchy, e.g. smoothing positions): world positions ``(T, J, 3)``
      stored directly, with joint names and optional parents.

    Units are those of the file (BVH units; often centimetres, but not guaranteed).
    """

    def __init__(self, skeleton: Skeleton, values: np.ndarray | None, fps: float, *,
                 positions: np.ndarray | None = None, root_offset: str = "ignore",
                 joint_translation: str = "replace", name: str | None = None, source: str | None = None):
        check_conventions(root_offset, joint_translation)
        if not (isinstance(fps, (int, float, np.floating)) and math.isfinite(fps) and fps > 0):
            raise MotionError(f"fps must be a positive number, got {fps!r}")
        if (values is None) == (positions is None):
            raise ValueError("give exactly one of values (hierarchical) or positions (positional)")
        self.skeleton = skeleton
        self.fps = float(fps)
        self.root_offset = root_offset
        self.joint_translation = joint_translation
        self.name = name
        self.source = source
        if values is not None:
            values = np.asarray(values, dtype=np.float64)
            if values.ndim != 2 or values.shape[1] != skeleton.n_channels:
                raise MotionError(f"values must have shape (T, {skeleton.n_channels}), got {values.shape}")
            self.values = values
            self._positions = None
        else:
            positions = np.asarray(positions, dtype=np.float64)
            if positions.ndim != 3 or positions.shape[1:] != (skeleton.n_joints, 3):
                raise MotionError(f"positions must have shape (T, {skeleton.n_joints}, 3), got {positions.shape}")
            # positional motion has no channel values (is_hierarchical is False)
            self.values = None  # type: ignore[assignment]
            self._positions = positions
        self._cache: dict[tuple[str, bool], np.ndarray] = {}

    # --- construction -----------------------------------------------------------------
    @classmethod
    def from_positions(cls, positions: npt.ArrayLike, joint_names: Iterable[str], fps: float,
                       parents: npt.ArrayLike | None = None, *, name: str | None = None,
                       source: str | None = None) -> Motion:
        """Positional motion from world positions ``(T, J, 3)`` (or ``(T, 3J)``)."""
        positions = np.asarray(positions, dtype=np.float64)
        joint_names = [str(n) for n in joint_names]
        if positions.ndim == 2 and positions.shape[1] == 3 * len(joint_names):
            positions = positions.reshape(len(positions), len(joint_names), 3)
        if positions.ndim != 3 or positions.shape[1:] != (len(joint_names), 3):
            raise MotionError(f"positions of shape {positions.shape} do not fit {len(joint_names)} joint names; "
                              "expected (T, J, 3) or (T, 3J)")
        parent_index = (-np.ones(len(joint_names), dtype=np.int64) if parents is None
                        else np.asarray(parents, dtype=np.int64))
        if len(set(joint_names)) != len(joint_names):
            raise MotionError("joint names must be unique")
        skeleton = Skeleton(joint_names, parent_index, np.zeros((len(joint_names), 3)), [()] * len(joint_names))
        return cls(skeleton, None, fps, positions=positions, name=name, source=source)

    def with_values(self, values: np.ndarray, fps: float | None = None, skeleton: Skeleton | None = None) -> Motion:
        """A hierarchical motion like this one with other channel values."""
        return Motion(skeleton or self.skeleton, values, fps or self.fps, root_offset=self.root_offset,
                      joint_translation=self.joint_translation, name=self.name, source=self.source)

    def with_positions(self, positions: np.ndarray, fps: float | None = None, joint_names: Iterable[str] | None = None,
                       parents: npt.ArrayLike | None = None) -> Motion:
        """A positional motion with these positions (joint names/parents kept unless given)."""
        names = list(joint_names) if joint_names is not None else self.joint_names
        par = parents if parents is not None else (self.parents if joint_names is None else None)
        return Motion.from_positions(positions, names, fps or self.fps, par, name=self.name, source=self.source)

    # --- views --------------------------------------------------------------------------
    @property
    def is_hierarchical(self) -> bool:
        return self.values is not None

    @property
    def joint_names(self) -> list[str]:
        return list(self.skeleton.names)

    @property
    def parents(self) -> np.ndarray:
        return self.skeleton.parents

    @property
    def n_joints(self) -> int:
        return self.skeleton.n_joints

    @property
    def n_frames(self) -> int:
        return len(self.values) if self.values is not None else len(self._positions)

    @property
    def frame_time(self) -> float:
        return 1.0 / self.fps

    @property
    def duration(self) -> float:
        """Length in seconds (``n_frames / fps``)."""
        return self.n_frames / self.fps

    def positions(self, end_sites: bool = False) -> np.ndarray:
        """World positions ``(T, J, 3)`` in file units; End Sites appended if asked.

        Computed once per motion and cached; treat the result as read-only.
        """
        if self.values is None:
            if end_sites:
                raise MotionError("this motion holds positions only; it has no End Sites")
            return self._positions
        key = ("positions", end_sites)
        if key not in self._cache:
            pos = forward_kinematics(self.skeleton, self.values, root_offset=self.root_offset,
                                     joint_translation=self.joint_translation, end_sites=end_sites)
            pos.setflags(write=False)
            self._cache[key] = pos
        return self._cache[key]

    def position_names(self, end_sites: bool = False) -> list[str]:
        """Names of the rows of :meth:`positions` (End Sites as ``<parent>_End``)."""
        return self.joint_names + (self.skeleton.end_site_names if end_sites else [])

    def world_rotations(self) -> np.ndarray:
        """World rotation matrices ``(T, J, 3, 3)`` (hierarchical motion only)."""
        if self.values is None:
            raise MotionError("this motion holds positions only; it has no rotations")
        _, rot = forward_kinematics(self.skeleton, self.values, root_offset=self.root_offset,
                                    joint_translation=self.joint_translation, world_rotations=True)
        return rot

    def local_rotations(self) -> np.ndarray:
        """Local (parent-relative) rotation matrices ``(T, J, 3, 3)`` from the channels."""
        if self.values is None:
            raise MotionError("this motion holds positions only; it has no rotations")
        from evalsuite.motion.fk import local_rotation_elements
        from evalsuite.motion.rotations import elements_to_array

        elems = local_rotation_elements(self.skeleton, self.values)
        out = np.empty((self.n_frames, self.n_joints, 3, 3))
        for j, e in enumerate(elems):
            out[:, j] = elements_to_array(e, (self.n_frames,))
        return out

    def joint_index(self, name: str) -> int:
        try:
            return self.skeleton.names.index(name)
        except ValueError:
            raise MotionError(f"no joint named {name!r}; the motion has: {', '.join(self.joint_names)}") from None

    def summary(self) -> dict[str, Any]:
        """What ``evalsuite info`` prints."""
        from evalsuite.motion.units import guess_units

        s = {
            "name": self.name,
            "source": self.source,
            "kind": "hierarchical (BVH)" if self.is_hierarchical else "positions",
            "joints": self.n_joints,
            "end_sites": len(self.skeleton.end_site_parents),
            "channels": self.skeleton.n_channels,
            "frames": self.n_frames,
            "fps": self.fps,
            "duration_s": self.duration,
            "roots": [self.joint_names[r] for r in self.skeleton.roots] if self.is_hierarchical else None,
        }
        if self.n_frames:
            s["units_guess"] = guess_units(self)
        return s

    def __repr__(self) -> str:
        kind = "BVH" if self.is_hierarchical else "positions"
        return (f"Motion({kind}, {self.n_joints} joints, {self.n_frames} frames @ {self.fps:g} fps"
                + (f", {self.name!r}" if self.name else "") + ")")
