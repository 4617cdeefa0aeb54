"""The built-in conditions on SMPL-X motion (BEAT2, GENEA Leaderboard ``.npz``): axis-angle in, SMPL-X out.

When a condition's source motion is an SMPL-X ``.npz`` (:func:`evalsuite.motion.smplx.is_smplx_npz`), the
operators work on its ``poses`` (T, 165: 55 joints x axis-angle, radians) directly, never through Euler angles,
and write an SMPL-X ``.npz`` with every other key of the source carried over (``betas``, ``expressions``,
``model``, ``gender``, the frame rate, unknown keys; dtypes as stored). The four degradations are those of
the GENEA Leaderboard's ``make_synthetic_baseline.py`` with its parameters, applied to the whole source
file before it is fitted to the request's length; its ``np.random`` draws are a generator seeded per segment
and sample here:

* ``gaussian_noise``: ``poses + N(0, sigma^2)`` on all 165 values (global orientation, jaw and eyes too),
  ``sigma = 0.02``; ``trans`` unchanged;
* ``attenuated``: ``(1 - a) poses + a mean_t(poses)``, ``a = 0.8``, the mean over the file's frames;
* ``fluctuation``: ``poses + A sin(2 pi f t + phi)`` with **one** phase ``phi ~ U(0, 2 pi)`` per sample for all
  values, ``t`` in frames, ``A = 0.05``, ``f = 0.2``; the global orientation (columns 0-2) unchanged;
* ``fixing``: 18 of the 55 joints, drawn without replacement among **all** 55 (the global orientation can be
  one), held at their frame-0 rotation.

``mismatched`` takes ``poses`` and ``trans`` from the donor segment (as ``human_mismatch`` does) and the other
keys from the segment's own file, cropped or extended back and forth to the segment's length (so
``expressions`` keep their length, unlike the Leaderboard's files). ``mean_pose`` holds the per-joint rotation
mean (scipy ``Rotation.mean``) and the mean ``trans`` and ``expressions``; ``random_segments`` joins clips with
slerp cross-fades per joint (linear on ``trans`` and ``expressions``).
"""
from __future__ import annotations

import dataclasses
import pathlib

import numpy as np
from scipy.spatial.transform import Rotation

from evalsuite.generators.contract import GenerationRequest, GeneratorError
from evalsuite.motion.smplx import SmplxData, is_smplx_npz, read_smplx

__all__ = ["gaussian_noise", "attenuated", "fluctuation", "fixing", "fit_smplx", "take_frames", "smplx_source",
           "with_motion", "mean_pose_smplx", "blend_smplx", "N_FIXED"]

N_FIXED = 18  # make_synthetic_baseline.py: np.random.choice(55, size=18, replace=False)


def gaussian_noise(poses: np.ndarray, rng: np.random.Generator, sigma: float = 0.02) -> np.ndarray:
    """``poses + N(0, sigma^2)`` per value; ``poses`` (T, 165) -> (T, 165)."""
    return poses + rng.normal(0.0, sigma, poses.shape)


def attenuated(poses: np.ndarray, alpha: float = 0.8) -> np.ndarray:
    """``(1 - alpha) poses + alpha mean_t(poses)``; (T, 165) -> (T, 165)."""
    return (1 - alpha) * poses + alpha * poses.mean(axis=0)


def fluctuation(poses: np.ndarray, rng: np.random.Generator, amplitude: float = 0.05,
                frequency: float = 0.2) -> np.ndarray:
    """``poses + amplitude sin(2 pi frequency t + phi)``, ``t`` = 0..T-1 frames, one ``phi ~ U(0, 2 pi)`` for every
    value; the global orientation (columns 0-2) is left as it is. (T, 165) -> (T, 165)."""
    phase = rng.uniform(0, 2 * np.pi)
    wave = amplitude * np.sin(2 * np.pi * frequency * np.arange(len(poses)) + phase)
    out = poses + wave[:, None]
    out[:, :3] = poses[:, :3]
    return out


def fixing(poses: np.ndarray, rng: np.random.Generator, n_fixed: int = N_FIXED) -> np.ndarray:
    """``n_fixed`` of the 55 joints (drawn without replacement, the root included) held at frame 0.
    (T, 165) -> (T, 165)."""
    joints = rng.choice(poses.shape[1] // 3, size=n_fixed, replace=False)
    out = poses.copy()
    for j in joints:
        out[:, 3 * j:3 * j + 3] = poses[0, 3 * j:3 * j + 3]
    return out


def take_frames(data: SmplxData, index: np.ndarray) -> SmplxData:
    """The frames ``index`` of ``poses``, ``trans`` and ``expressions``; every other key unchanged."""
    expr = None if data.expressions is None else data.expressions[index]
    return dataclasses.replace(data, poses=data.poses[index], trans=data.trans[index], expressions=expr)


def fit_smplx(data: SmplxData, req: GenerationRequest) -> SmplxData:
    """Cropped to ``req.n_frames`` (a shorter motion holds its last frame). SMPL-X motion is not resampled: a
    request at another frame rate is an error."""
    if abs(data.fps - req.fps) > 1e-6 * req.fps:
        raise GeneratorError(f"{data.source or 'SMPL-X motion'} is at {data.fps:g} fps but {req.fps:g} fps were "
                             f"asked for; SMPL-X conditions keep the source's rate (generate with --fps {data.fps:g})")
    if data.n_frames == req.n_frames:
        return data
    return take_frames(data, np.minimum(np.arange(req.n_frames), data.n_frames - 1))


def smplx_source(path: pathlib.Path | None) -> SmplxData | None:
    """The SMPL-X data of a source motion file, or None when it is not an SMPL-X ``.npz``."""
    if path is None or not is_smplx_npz(path):
        return None
    return read_smplx(path)


def with_motion(base: SmplxData, donor: SmplxData) -> SmplxData:
    """``base`` with the donor's ``poses`` and ``trans`` (same length); the other keys stay the base's."""
    if donor.n_frames != base.n_frames:
        raise ValueError("with_motion needs the same number of frames")
    return dataclasses.replace(base, poses=donor.poses.copy(), trans=donor.trans.copy())


def mean_pose_smplx(items: list[SmplxData]) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """``(pose (165,), trans (3,), expressions (E,) or None)``: per joint the rotation mean of every frame of
    ``items`` (scipy ``Rotation.mean``), the arithmetic mean of ``trans`` and of ``expressions``."""
    poses = np.concatenate([d.poses for d in items]).reshape(-1, 55, 3)
    pose = np.stack([Rotation.from_rotvec(poses[:, j]).mean().as_rotvec() for j in range(55)]).reshape(-1)
    trans = np.concatenate([d.trans for d in items]).mean(axis=0)
    widths = {None if d.expressions is None else d.expressions.shape[1] for d in items}
    expr = None
    if len(widths) == 1 and None not in widths:
        expr = np.concatenate([d.expressions for d in items if d.expressions is not None]).mean(axis=0)
    return pose, trans, expr


def blend_smplx(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Cross-fade of SMPL-X frames ``[poses (165) | trans (3) | expressions]`` of equal shape (F, D): per joint
    ``R_a (R_a^-1 R_b)^w`` (slerp) on the 55 axis-angle rotations, linear ``(1 - w) a + w b`` on the rest."""
    f = len(a)
    ra = Rotation.from_rotvec(a[:, :165].reshape(-1, 3))
    rb = Rotation.from_rotvec(b[:, :165].reshape(-1, 3))
    ww = np.repeat(w, 55)[:, None]
    rot = (ra * Rotation.from_rotvec((ra.inv() * rb).as_rotvec() * ww)).as_rotvec().reshape(f, 165)
    rest = a[:, 165:] * (1 - w)[:, None] + b[:, 165:] * w[:, None]
    return np.concatenate([rot, rest], axis=1)
