"""The ``positions`` motion format: joint positions as ``.npy``, ``.npz`` or ``.csv``.

Positions files as the GENEA scripts write them hold ``(T, J, 3)`` or ``(T, 3J)`` arrays
without names or frame rate; pass ``joint_names`` and ``fps``. evalsuite's own ``.npz``
holds ``positions`` (T, J, 3), ``joint_names`` and ``fps`` (and ``parents``). A positions
``.csv`` has a header ``[time,]<joint>.x,<joint>.y,<joint>.z,...`` (the layout of
bvh-toolbox's ``bvh2csv``); the fps comes from the ``time`` column when present.
"""
from __future__ import annotations

import os
import pathlib
import zipfile
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError, MotionError
from evalsuite.motion.formats import MotionFormat
from evalsuite.motion.motion import Motion, _clean_fps

__all__ = ["FORMAT", "load_positions", "POSITION_SUFFIXES"]

POSITION_SUFFIXES = (".npy", ".npz", ".csv")


def load_positions(path: pathlib.Path, *, fps: float | None = None, joint_names: Sequence[str] | None = None,
                   parents: npt.ArrayLike | None = None, fallback_fps: float | None = None, **_: Any) -> Motion:
    """A positional motion from ``.npy``, ``.npz`` or ``.csv`` (``fallback_fps`` for files storing no rate)."""
    suffix = path.suffix.lower()
    if fallback_fps is not None and fps is None and suffix in (".npy", ".csv"):
        fps = fallback_fps
    if suffix == ".npz":
        return _load_npz(path, fps, joint_names, parents, fallback_fps)
    if suffix == ".npy":
        try:
            arr = np.load(path, allow_pickle=False)
        except Exception as exc:  # numpy raises many types for a corrupt file
            raise InputError(f"not a readable .npy array ({exc})", path=path) from None
        return _positions_motion(path, arr, fps, joint_names, parents)
    return _load_csv(path, fps, joint_names, parents)


def _positions_motion(path: pathlib.Path, arr: npt.ArrayLike, fps: float | None, joint_names: Sequence[str] | None,
                      parents: npt.ArrayLike | None) -> Motion:
    arr = np.asarray(arr)
    if arr.dtype.kind not in "fiu":
        raise InputError(f"expected a numeric array, found dtype {arr.dtype}", path=path)
    if arr.ndim == 3 and arr.shape[2] == 3:
        n_joints = arr.shape[1]
    elif arr.ndim == 2 and arr.shape[1] % 3 == 0:
        n_joints = arr.shape[1] // 3
    else:
        raise InputError(f"expected joint positions of shape (T, J, 3) or (T, 3J), found {arr.shape}", path=path)
    if fps is None:
        raise InputError("this positions file stores no frame rate; give fps (CLI: --fps)", path=path)
    if joint_names is None:
        joint_names = [f"joint{j}" for j in range(n_joints)]
    joint_names = list(joint_names)
    if len(joint_names) != n_joints:
        raise InputError(f"{len(joint_names)} joint names given but the array has {n_joints} joints", path=path)
    arr = arr.astype(np.float64).reshape(len(arr), n_joints, 3)
    if not np.isfinite(arr).all():
        t, j, _ = np.argwhere(~np.isfinite(arr))[0]
        raise InputError(f"non-finite position at frame {t}, joint {joint_names[j]!r}", path=path)
    try:
        return Motion.from_positions(arr, joint_names, fps, parents, name=path.stem, source=os.fspath(path))
    except MotionError as exc:
        raise InputError(exc.reason, path=path) from None


def _load_npz(path: pathlib.Path, fps: float | None, joint_names: Sequence[str] | None, parents: npt.ArrayLike | None,
              fallback_fps: float | None = None) -> Motion:
    try:
        with np.load(path, allow_pickle=False) as data:
            contents = {k: data[k] for k in data.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise InputError(f"not a readable .npz archive ({exc})", path=path) from None
    key = "positions" if "positions" in contents else (next(iter(contents)) if len(contents) == 1 else None)
    if key is None:
        raise InputError(f"expected an array named 'positions'; the archive has {sorted(contents)}", path=path)
    if joint_names is None and "joint_names" in contents:
        joint_names = [str(n) for n in contents["joint_names"]]
    if fps is None and "fps" in contents:
        fps = float(contents["fps"])
    if fps is None:
        fps = fallback_fps
    if parents is None and "parents" in contents:
        parents = contents["parents"]
    return _positions_motion(path, contents[key], fps, joint_names, parents)


def _load_csv(path: pathlib.Path, fps: float | None, joint_names: Sequence[str] | None,
              parents: npt.ArrayLike | None) -> Motion:
    import pandas as pd

    try:
        frame = pd.read_csv(path, skipinitialspace=True)
    except Exception as exc:  # pandas raises several parser/encoding errors
        raise InputError(f"not a readable CSV file ({exc})", path=path) from None
    columns = [c.strip() for c in frame.columns]
    frame.columns = columns
    time = None
    if columns and columns[0].lower() in ("time", "t", "frame_time"):
        time = frame.pop(columns[0]).to_numpy(dtype=float)
        columns = columns[1:]
    if len(columns) % 3:
        raise InputError(f"expected 3 columns per joint (<joint>.x, .y, .z), found {len(columns)} columns", path=path)
    names = []
    for j in range(0, len(columns), 3):
        trio = columns[j:j + 3]
        base = trio[0].rsplit(".", 1)[0] if "." in trio[0] else None
        expected = [f"{base}.{a}" for a in "xyz"] if base else None
        if expected is None or [c.lower() for c in trio] != [e.lower() for e in expected]:
            raise InputError(f"columns {trio} are not '<joint>.x, <joint>.y, <joint>.z'", path=path,
                             line=1, field=f"column {j + 2 if time is not None else j + 1}")
        names.append(base)
    bad = [c for c in frame.columns if frame[c].dtype.kind not in "fiu"]
    if bad:
        col = bad[0]
        values = pd.to_numeric(frame[col], errors="coerce")
        row = int(np.flatnonzero(values.isna().to_numpy())[0])
        raise InputError(f"expected a number, found {frame[col].iloc[row]!r}", path=path, line=row + 2, field=col)
    if fps is None and time is not None and len(time) > 1:
        fps = _clean_fps(float(np.median(np.diff(time))))
    return _positions_motion(path, frame.to_numpy(dtype=np.float64), fps, joint_names or [str(n) for n in names],
                             parents)


FORMAT = MotionFormat("positions", POSITION_SUFFIXES, load_positions,
                      description="joint positions: .npy (T, J, 3) or (T, 3J), evalsuite's .npz, .csv")
