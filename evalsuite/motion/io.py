"""Loading and saving motion files of every registered format (:mod:`evalsuite.motion.formats`): BVH,
SMPL-X/BEAT2 ``.npz`` and joint positions as ``.npy``, ``.npz`` or ``.csv``.

Positions files as the GENEA scripts write them hold ``(T, J, 3)`` or ``(T, 3J)`` arrays
without names or frame rate; pass ``joint_names`` and ``fps``. evalsuite's own ``.npz``
holds ``positions`` (T, J, 3), ``joint_names`` and ``fps`` (and ``parents``). A positions
``.csv`` has a header ``[time,]<joint>.x,<joint>.y,<joint>.z,...`` (the layout of
bvh-toolbox's ``bvh2csv``); the fps comes from the ``time`` column when present.
An ``.npz`` holding ``poses`` is an SMPL-X recording (:mod:`evalsuite.motion.smplx`).
"""
from __future__ import annotations

import os
import pathlib
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError, MotionError
from evalsuite.motion.bvh import write_bvh
from evalsuite.motion.formats import motion_format_for, motion_suffixes
from evalsuite.motion.motion import Motion
from evalsuite.motion.smplx import write_smplx
from evalsuite.motion.smplx_motion import SmplxMotion

POSITION_SUFFIXES = (".npy", ".npz", ".csv")
MOTION_SUFFIXES = (".bvh",) + POSITION_SUFFIXES   # the built-in formats' (motion_suffixes() adds plug-ins')


def load_motion(path: str | os.PathLike[str], *, fps: float | None = None, joint_names: Sequence[str] | None = None,
                parents: npt.ArrayLike | None = None,
                convention: str | None = None, root_offset: str | None = None,
                joint_translation: str | None = None, fallback_fps: float | None = None,
                smplx_model: str | os.PathLike[str] | None = None, positions: str = "full",
                betas: npt.ArrayLike | None = None, nan: str = "error", format: str | None = None) -> Motion:
    """Load a motion file (``.bvh``, ``.npy``, ``.npz``, ``.csv``, or a plug-in format's).

    Args:
        path: the file.
        fps: frame rate; required for ``.npy`` (and for files that do not store one).
            For BVH and SMPL-X it must agree with the file's rate if given.
        joint_names: names for positions files without names (default ``joint0``...).
        parents: parent index per joint for positions files (used for drawing bones).
        convention: BVH translation conventions by name: ``"default"``, ``"pymo"``,
            ``"pymotion"``, ``"bvhtoolbox"`` (see :mod:`evalsuite.motion.fk`);
            ``root_offset``/``joint_translation`` override single settings.
        fallback_fps: frame rate of positions files that store none (unlike ``fps``, not checked elsewhere).
        smplx_model: the user's SMPL-X model ``.npz`` for SMPL-X positions (default: the environment variable
            ``EVALSUITE_SMPLX_MODEL``; neither: rotations only).
        positions: SMPL-X positions mode, ``"full"`` or ``"leaderboard"`` (:mod:`evalsuite.motion.smplx_body`).
        betas: SMPL-X shape coefficients for positions instead of the file's (the Leaderboard: the ground truth's).
        nan: SMPL-X NaN handling: ``"error"`` or ``"zero"``.
        format: a format name (``bvh``, ``smplx``, ``positions``, ...) instead of telling it from the file.

    Raises:
        InputError (BVHError for BVH files) naming the file and what is wrong.
    """
    path = pathlib.Path(path)
    fmt = motion_format_for(path, format) if format is not None else None
    if fmt is None and path.suffix.lower() not in motion_suffixes():
        raise InputError(f"unknown motion file type {path.suffix!r}; expected one of {', '.join(motion_suffixes())}",
                         path=path)
    if not path.exists():
        raise InputError("no such file", path=path)
    fmt = fmt or motion_format_for(path)
    return fmt.load(path, fps=fps, joint_names=joint_names, parents=parents, convention=convention,
                    root_offset=root_offset, joint_translation=joint_translation, fallback_fps=fallback_fps,
                    smplx_model=smplx_model, positions=positions,
                    betas=None if betas is None else np.asarray(betas, dtype=np.float64), nan=nan)


def list_motion_files(folder: str | os.PathLike[str], *, what: str | None = None) -> dict[str, pathlib.Path]:
    """The motion files directly in ``folder``, keyed by file stem, in name order.

    ``what`` names the folder's owner in error messages (e.g. ``"condition 'SysA'"``). InputError if the
    folder is missing, is a file, holds no motion file, or holds two files of one stem (``a.bvh``, ``a.npy``).
    """
    folder = pathlib.Path(folder)
    if not folder.exists():
        raise InputError(f"folder of {what} does not exist" if what else "no such folder", path=folder)
    if not folder.is_dir():
        raise InputError("expected a folder of motion files" + (f" for {what}" if what else ""), path=folder)
    found: dict[str, pathlib.Path] = {}
    suffixes = motion_suffixes()
    for path in sorted(folder.iterdir()):
        if path.is_file() and path.suffix.lower() in suffixes:
            if path.stem in found:
                raise InputError(f"two files for sequence {path.stem!r}: {found[path.stem].name} and "
                                 f"{path.name}; keep one per sequence", path=folder)
            found[path.stem] = path
    if not found:
        where = f"the folder of {what}" if what else "this folder"
        raise InputError(f"no motion files ({', '.join(suffixes)}) in {where}", path=folder)
    return found


def positions_joint_count(path: str | os.PathLike[str]) -> int | None:
    """Joints of a ``.npy`` positions array without loading it (memory-mapped header), None if unknown."""
    arr = np.load(path, mmap_mode="r", allow_pickle=False)
    if arr.ndim == 3:
        return int(arr.shape[1])
    return int(arr.shape[1] // 3) if arr.ndim == 2 else None


def load_motion_folder(folder: str | os.PathLike[str], *, convention: str | None = None, fps: float | None = None,
                       joint_names: Sequence[str] | None = None) -> dict[str, Motion]:
    """Every motion file of a folder (or one file), keyed by file stem, loaded under ``convention``.

    ``fps`` and ``joint_names`` are used for positions files that do not store them (GENEA ``.npy``
    files: ``(T, 3J)`` arrays without names); names whose count does not fit a file are not used there.
    """
    folder = pathlib.Path(folder)
    paths = {folder.stem: folder} if folder.is_file() else list_motion_files(folder)
    out: dict[str, Motion] = {}
    for stem, path in paths.items():
        suffix = path.suffix.lower()
        if suffix == ".bvh":
            out[stem] = load_motion(path, convention=convention)
            continue
        names = joint_names if suffix != ".npz" else None
        if names is not None and suffix == ".npy" and positions_joint_count(path) != len(names):
            names = None  # let the loader name them; the caller's joint check reports the mismatch
        out[stem] = load_motion(path, fallback_fps=fps, joint_names=names)
    return out


def save_motion(motion: Motion, path: str | os.PathLike[str], *, end_sites: bool = False, precision: int = 6) -> None:
    """Write a motion: ``.bvh`` (hierarchical motion only), ``.npz``, ``.npy``, ``.csv``.

    ``.npz`` holds ``positions`` (T, J, 3), ``joint_names``, ``fps`` and ``parents``, except for an SMPL-X
    motion, which is written as an SMPL-X ``.npz`` (:func:`~evalsuite.motion.smplx.write_smplx`);
    ``.npy`` only the ``(T, J, 3)`` array; ``.csv`` a ``time`` column and ``<joint>.x/y/z``.
    An SMPL-X motion written as ``.bvh`` needs its model file (OFFSETs are J(β), metres, 9 decimals).
    """
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if isinstance(motion, SmplxMotion):
        end_sites = False
        if suffix == ".npz":
            write_smplx(path, motion.smplx)
            return
        if suffix == ".bvh":
            motion.positions()   # the one-line error without a model file: zero OFFSETs are no skeleton
            if motion.position_mode == "leaderboard":
                motion = motion.leaderboard_zeroed()
            precision = max(precision, 9)
    if suffix == ".bvh":
        if not motion.is_hierarchical:
            raise MotionError("this motion holds positions only and cannot be written as BVH; "
                              "write .npz, .npy or .csv", path=path)
        write_bvh(path, motion.skeleton, motion.values, motion.frame_time, precision)
        return
    if suffix not in POSITION_SUFFIXES:
        raise InputError(f"unknown output type {path.suffix!r}; expected one of {', '.join(MOTION_SUFFIXES)}",
                         path=path)
    pos = motion.positions(end_sites=end_sites and motion.is_hierarchical)
    names = motion.position_names(end_sites=end_sites and motion.is_hierarchical)
    parents = motion.parents
    if len(names) > motion.n_joints:
        parents = np.concatenate([parents, motion.skeleton.end_site_parents])
    if suffix == ".npz":
        np.savez(path, positions=pos, joint_names=np.array(names), fps=np.float64(motion.fps), parents=parents)
    elif suffix == ".npy":
        np.save(path, pos)
    else:
        import pandas as pd

        header = ["time"] + [f"{n}.{a}" for n in names for a in "xyz"]
        data = np.column_stack([np.arange(len(pos)) / motion.fps, pos.reshape(len(pos), -1)])
        pd.DataFrame(data, columns=header).to_csv(path, index=False, float_format=f"%.{precision}f")
