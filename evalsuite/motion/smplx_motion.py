"""SMPL-X recordings as a rotation :class:`~evalsuite.motion.motion.Motion`.

A :class:`SmplxMotion` is a hierarchical motion over the 55 SMPL-X joints: the root has the channels
``Xposition Yposition Zposition Zrotation Xrotation Yrotation`` and every other joint ``Zrotation Xrotation
Yrotation`` (degrees, converted from the file's axis-angle with scipy), so every rotation-space metric and
operation works on it. The recording itself stays on the motion as ``motion.smplx``
(:class:`~evalsuite.motion.smplx.SmplxData`, axis-angle in radians) for metrics that want the axis-angle.

Joint positions need the user's SMPL-X model file (``smplx_model``): then the skeleton's OFFSETs are
J(β) (metres; root OFFSET the rest pelvis, root position channels pelvis + ``trans``) and
:meth:`SmplxMotion.positions` are :func:`~evalsuite.motion.smplx_body.smplx_positions` in the motion's
``position_mode``. Without one, the OFFSETs are zero and anything asking for positions gets the one-line
error naming ``--smplx-model`` / ``EVALSUITE_SMPLX_MODEL``.
"""
from __future__ import annotations

import dataclasses
import os
import pathlib
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion.motion import Motion
from evalsuite.motion.skeleton import Skeleton
from evalsuite.motion.smplx import SmplxData
from evalsuite.motion.smplx_body import MODES, SmplxModelMissing, model_missing_message, rest_joints, smplx_positions
from evalsuite.motion.smplx_layout import JAW_EYES, N_JOINTS, SMPLX_JOINT_NAMES, SMPLX_PARENTS

__all__ = ["SmplxMotion", "SmplxJointsMotion", "smplx_skeleton", "EULER_ORDER"]

EULER_ORDER = "ZXY"
ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition") + tuple(f"{a}rotation" for a in EULER_ORDER)
JOINT_CHANNELS = tuple(f"{a}rotation" for a in EULER_ORDER)


def smplx_skeleton(rest: np.ndarray | None) -> Skeleton:
    """The 55-joint SMPL-X skeleton; OFFSETs from rest joints ``rest`` (55, 3) (root: its rest position), or
    zero when None."""
    offsets = np.zeros((N_JOINTS, 3))
    if rest is not None:
        parents = np.array(SMPLX_PARENTS)
        offsets[0] = rest[0]
        offsets[1:] = rest[1:] - rest[parents[1:]]
    channels = [ROOT_CHANNELS] + [JOINT_CHANNELS] * (N_JOINTS - 1)
    return Skeleton(list(SMPLX_JOINT_NAMES), np.array(SMPLX_PARENTS), offsets, channels)


def _values(data: SmplxData, root: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    n = data.n_frames
    euler = Rotation.from_rotvec(data.poses.reshape(-1, 3)).as_euler(EULER_ORDER, degrees=True)
    return np.concatenate([data.trans + root, euler.reshape(n, -1)], axis=1)


def _poses_from_values(values: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    n = len(values)
    angles = values[:, 3:].reshape(-1, 3)
    return np.asarray(Rotation.from_euler(EULER_ORDER, angles, degrees=True).as_rotvec().reshape(n, -1))


class SmplxMotion(Motion):
    """A :class:`Motion` read from an SMPL-X file (see the module docstring).

    Args:
        data: the recording.
        smplx_model: the user's SMPL-X model ``.npz`` (None: positions are not available).
        position_mode: ``"full"`` or ``"leaderboard"`` (see :mod:`evalsuite.motion.smplx_body`).
        betas: shape coefficients for positions and OFFSETs instead of the recording's (the Leaderboard uses
            the ground truth's).
    """

    def __init__(self, data: SmplxData, *, smplx_model: str | os.PathLike[str] | None = None,
                 position_mode: str = "full", betas: np.ndarray | None = None, name: str | None = None,
                 source: str | None = None) -> None:
        if position_mode not in MODES:
            raise InputError(f"unknown positions mode {position_mode!r}; expected one of {', '.join(MODES)}",
                             field="positions")
        self.smplx = data
        self.smplx_model = pathlib.Path(smplx_model) if smplx_model is not None else None
        self.position_mode = position_mode
        self.position_betas = None if betas is None else np.asarray(betas, dtype=np.float64).ravel()
        rest = None
        if self.smplx_model is not None:
            shape = data.betas if self.position_betas is None else self.position_betas
            rest = rest_joints(self.smplx_model, shape)
        skeleton = smplx_skeleton(rest)
        super().__init__(skeleton, _values(data, skeleton.offsets[0]), data.fps, root_offset="ignore",
                         joint_translation="replace", name=name, source=source or data.source)

    @property
    def has_positions(self) -> bool:
        """Whether a model file is known, so :meth:`positions` can be computed."""
        return self.smplx_model is not None

    def with_model(self, smplx_model: str | os.PathLike[str] | None, *, position_mode: str | None = None,
                   betas: np.ndarray | None = None) -> SmplxMotion:
        """The same recording with a model file (and optionally another positions mode or betas)."""
        return SmplxMotion(self.smplx, smplx_model=smplx_model, position_mode=position_mode or self.position_mode,
                           betas=self.position_betas if betas is None else betas, name=self.name,
                           source=self.source)

    def leaderboard_zeroed(self) -> SmplxMotion:
        """The recording with global orientation, translation, jaw, eyes and expressions zeroed (what the
        Leaderboard's positions are the forward kinematics of), in ``full`` mode."""
        rot = self.smplx.rotvecs.copy()
        rot[:, [0, *JAW_EYES]] = 0.0
        data = dataclasses.replace(self.smplx, poses=rot.reshape(self.n_frames, -1),
                                   trans=np.zeros_like(self.smplx.trans), expressions=None)
        return SmplxMotion(data, smplx_model=self.smplx_model, position_mode="full", betas=self.position_betas,
                           name=self.name, source=self.source)

    def positions(self, end_sites: bool = False) -> np.ndarray:
        """Joint positions (T, 55, 3) in metres (needs the model file; SMPL-X has no End Sites)."""
        if self.smplx_model is None:
            raise SmplxModelMissing(model_missing_message(repr(self.name) if self.name else 'this SMPL-X motion'))
        if end_sites:
            raise InputError("SMPL-X motion has no End Sites", field="end_sites")
        key = ("positions", False)
        if key not in self._cache:
            pos = smplx_positions(self.smplx, self.smplx_model, mode=self.position_mode, betas=self.position_betas)
            pos.setflags(write=False)
            self._cache[key] = pos
        return self._cache[key]

    def local_rotations(self) -> np.ndarray:
        """Local rotation matrices (T, 55, 3, 3) straight from the axis-angle."""
        from scipy.spatial.transform import Rotation

        mats = Rotation.from_rotvec(self.smplx.poses.reshape(-1, 3)).as_matrix()
        return np.asarray(mats.reshape(self.n_frames, N_JOINTS, 3, 3))

    def with_values(self, values: np.ndarray, fps: float | None = None,
                    skeleton: Skeleton | None = None) -> Motion:
        """An SMPL-X motion with other channel values (after cutting, resampling, smoothing); a plain
        :class:`Motion` when the skeleton changes (joints selected). Expressions are kept when the frame count
        is unchanged and dropped otherwise."""
        if skeleton is not None and skeleton != self.skeleton:
            return SmplxJointsMotion(skeleton, values, fps or self.fps, has_model=self.has_positions,
                                     position_mode=self.position_mode, name=self.name, source=self.source)
        values = np.asarray(values, dtype=np.float64)
        expr = self.smplx.expressions
        data = dataclasses.replace(
            self.smplx, poses=_poses_from_values(values), trans=values[:, :3] - self.skeleton.offsets[0],
            expressions=expr if expr is not None and len(expr) == len(values) else None, fps=fps or self.fps)
        return SmplxMotion(data, smplx_model=self.smplx_model, position_mode=self.position_mode,
                           betas=self.position_betas, name=self.name, source=self.source)

    def summary(self) -> dict[str, Any]:
        """What ``evalsuite info`` prints for an SMPL-X file (no positions are computed)."""
        d = self.smplx
        return {
            "name": self.name, "source": self.source, "kind": "SMPL-X (axis-angle rotations)",
            "format": "smplx", "joints": self.n_joints, "end_sites": 0, "channels": self.skeleton.n_channels,
            "frames": self.n_frames, "fps": self.fps, "duration_s": self.duration, "roots": ["pelvis"],
            "pose_width": d.stored.get("pose_width", 165), "betas": int(d.betas.size),
            "expressions": None if d.expressions is None else int(d.expressions.shape[1]),
            "gender": d.gender or None, "model": d.model or None,
            "units": "radians (poses), metres (trans)",
            "positions": (f"available ({self.position_mode} mode, model {self.smplx_model})" if self.has_positions
                          else "need --smplx-model or EVALSUITE_SMPLX_MODEL"),
        }

    def __repr__(self) -> str:
        return (f"SmplxMotion(55 joints, {self.n_frames} frames @ {self.fps:g} fps"
                + (f", {self.name!r}" if self.name else "") + ")")


class SmplxJointsMotion(Motion):
    """Some joints of an SMPL-X motion (:func:`evalsuite.motion.ops.select_joints` keeping a closed set): the
    Euler channels of those joints, positions by forward kinematics of their J(β) OFFSETs (expressions not
    applied). Without a model file, :meth:`positions` is the one-line missing-model error (the OFFSETs are
    zero); in ``leaderboard`` mode the pelvis, jaw and eye rotations are zeroed and the pelvis stays at rest."""

    def __init__(self, skeleton: Skeleton, values: np.ndarray, fps: float, *, has_model: bool,
                 position_mode: str = "full", name: str | None = None, source: str | None = None) -> None:
        values = np.array(values, dtype=np.float64)
        if position_mode == "leaderboard":
            starts = skeleton.channel_starts
            for j, joint in enumerate(skeleton.names):
                if joint in ("pelvis",) + tuple(SMPLX_JOINT_NAMES[k] for k in JAW_EYES):
                    for c, channel in enumerate(skeleton.channels[j]):
                        col = int(starts[j]) + c
                        values[:, col] = skeleton.offsets[j]["XYZ".index(channel[0])] \
                            if channel.endswith("position") else 0.0
        super().__init__(skeleton, values, fps, root_offset="ignore", joint_translation="replace", name=name,
                         source=source)
        self.has_model = has_model
        self.position_mode = position_mode

    def positions(self, end_sites: bool = False) -> np.ndarray:
        if not self.has_model:
            raise SmplxModelMissing(model_missing_message(repr(self.name) if self.name else 'this SMPL-X motion'))
        return super().positions(end_sites)

    def with_values(self, values: np.ndarray, fps: float | None = None,
                    skeleton: Skeleton | None = None) -> Motion:
        return SmplxJointsMotion(skeleton or self.skeleton, values, fps or self.fps, has_model=self.has_model,
                                 position_mode=self.position_mode, name=self.name, source=self.source)
