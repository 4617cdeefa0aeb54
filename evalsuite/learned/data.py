"""Loading a folder of motion files for training and scoring, and hashing what was used."""
from __future__ import annotations

import hashlib
import pathlib

import numpy as np

from evalsuite import hashing
from evalsuite.errors import InputError
from evalsuite.motion import Motion, load_motion
from evalsuite.motion.io import MOTION_SUFFIXES


def motion_files(folder) -> list[pathlib.Path]:
    """Motion files directly in ``folder`` (sorted by name); InputError if there are none."""
    folder = pathlib.Path(folder)
    if folder.is_file():
        return [folder]
    if not folder.is_dir():
        raise InputError("no such folder", path=folder)
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in MOTION_SUFFIXES)
    if not files:
        raise InputError(f"no motion files ({', '.join(MOTION_SUFFIXES)}) in this folder", path=folder)
    return files


def load_folder(folder, *, convention: str | None = None, fps: float | None = None,
                joint_names=None) -> dict[str, Motion]:
    """Every motion file of a folder, keyed by file stem, loaded under ``convention``.

    ``fps`` and ``joint_names`` are used for positions files that do not store them
    (GENEA ``.npy`` files: ``(T, 3J)`` arrays without names).
    """
    out: dict[str, Motion] = {}
    for path in motion_files(folder):
        if path.suffix.lower() == ".bvh":
            motion = load_motion(path, convention=convention)
        else:
            names = joint_names
            if names is not None and path.suffix.lower() == ".npy":
                arr = np.load(path, mmap_mode="r", allow_pickle=False)
                n_joints = arr.shape[1] if arr.ndim == 3 else (arr.shape[1] // 3 if arr.ndim == 2 else -1)
                if n_joints != len(names):
                    names = None  # let the loader name them; the model's joint check reports it
            motion = load_motion(path, fps=fps, joint_names=names if path.suffix.lower() != ".npz" else None)
        if path.stem in out:
            raise InputError(f"two files share the name {path.stem!r}", path=path)
        out[path.stem] = motion
    return out


def file_sha256(path) -> str | None:
    """The file's SHA-256, or None for motion that did not come from a file."""
    path = pathlib.Path(path) if path else None
    if path is None or not path.is_file():
        return None
    return hashing.file_sha256(path)


def array_sha256(arr: np.ndarray) -> str:
    a = np.ascontiguousarray(arr)
    return hashlib.sha256(f"{a.dtype}|{a.shape}|".encode() + a.tobytes()).hexdigest()
