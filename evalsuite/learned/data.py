"""Loading a folder of motion files for training and scoring, and hashing what was used."""
from __future__ import annotations

import hashlib
import pathlib

import numpy as np

from evalsuite import hashing
from evalsuite.motion import Motion
from evalsuite.motion.io import load_motion_folder


def load_folder(folder, *, convention: str | None = None, fps: float | None = None,
                joint_names=None) -> dict[str, Motion]:
    """Every motion file of a folder keyed by stem (:func:`evalsuite.motion.io.load_motion_folder`)."""
    return load_motion_folder(folder, convention=convention, fps=fps, joint_names=joint_names)


def file_sha256(path) -> str | None:
    """The file's SHA-256, or None for motion that did not come from a file."""
    path = pathlib.Path(path) if path else None
    if path is None or not path.is_file():
        return None
    return hashing.file_sha256(path)


def array_sha256(arr: np.ndarray) -> str:
    a = np.ascontiguousarray(arr)
    return hashlib.sha256(f"{a.dtype}|{a.shape}|".encode() + a.tobytes()).hexdigest()
