"""Loading and saving motion: BVH, and joint positions as ``.npy``, ``.npz`` or ``.csv``.

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

import numpy as np
import numpy.typing as npt

from evalsuite.errors import InputError, MotionError
from evalsuite.motion.bvh import read_bvh_file, write_bvh
from evalsuite.motion.fk import CONVENTIONS
from evalsuite.motion.motion import Motion, _clean_fps

POSITION_SUFFIXES = (".npy", ".npz", ".csv")
MOTION_SUFFIXES = (".bvh",) + POSITION_SUFFIXES


def load_motion(path: str | os.PathLike[str], *, fps: float | None = None, joint_names: Sequence[str] | None = None,
                parents: npt.ArrayLike | None = None,
                convention: str | None = None, root_offset: str | None = None,
                joint_translation: str | None = None, fallback_fps: float | None = None) -> Motion:
    """Load a motion file (``.bvh``, ``.npy``, ``.npz``, ``.csv``).

    Args:
        path: the file.
        fps: frame rate; required for ``.npy`` (and for files that do not store one).
            For BVH it must agree with the file's ``Frame Time`` if given.
        joint_names: names for positions files without names (default ``joint0``...).
        parents: parent index per joint for positions files (used for drawing bones).
        convention: BVH translation conventions by name: ``"default"``, ``"pymo"``,
            ``"pymotion"``, ``"bvhtoolbox"`` (see :mod:`evalsuite.motion.fk`);
            ``root_offset``/``joint_translation`` override single settings.

    Raises:
        InputError (BVHError for BVH files) naming the file and what is wrong.
    """
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if fallback_fps is not None and fps is None and suffix in (".npy", ".csv"):
        fps = fallback_fps
    if suffix not in MOTION_SUFFIXES:
        raise InputError(f"unknown motion file type {path.suffix!r}; expected one of {', '.join(MOTION_SUFFIXES)}",
                         path=path)
    if not path.exists():
        raise InputError("no such file", path=path)
    if suffix == ".bvh":
        conv = dict(CONVENTIONS["default"])
        if convention is not None:
            if convention not in CONVENTIONS:
                raise InputError(f"unknown convention {convention!r}; expected one of {', '.join(CONVENTIONS)}")
            conv = dict(CONVENTIONS[convention])
        if root_offset is not None:
            conv["root_offset"] = root_offset
        if joint_translation is not None:
            conv["joint_translation"] = joint_translation
        skeleton, values, frame_time = read_bvh_file(path)
        file_fps = _clean_fps(frame_time)
        if fps is not None and abs(fps - file_fps) > 1e-6 * file_fps:
            raise InputError(f"fps {fps:g} was given but the file says {file_fps:g} (Frame Time {frame_time:g}); "
                             "use evalsuite.motion.ops.resample to change the frame rate", path=path)
        return Motion(skeleton, values, file_fps, name=path.stem, source=os.fspath(path),
                      root_offset=conv["root_offset"], joint_translation=conv["joint_translation"])
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
    for path in sorted(folder.iterdir()):
        if path.is_file() and path.suffix.lower() in MOTION_SUFFIXES:
            if path.stem in found:
                raise InputError(f"two files for sequence {path.stem!r}: {found[path.stem].name} and "
                                 f"{path.name}; keep one per sequence", path=folder)
            found[path.stem] = path
    if not found:
        where = f"the folder of {what}" if what else "this folder"
        raise InputError(f"no motion files ({', '.join(MOTION_SUFFIXES)}) in {where}", path=folder)
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

    ``.npz`` holds ``positions`` (T, J, 3), ``joint_names``, ``fps`` and ``parents``;
    ``.npy`` only the ``(T, J, 3)`` array; ``.csv`` a ``time`` column and ``<joint>.x/y/z``.
    """
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
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
