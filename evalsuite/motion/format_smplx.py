"""The ``smplx`` motion format: SMPL-X/BEAT2 ``.npz`` files (an archive with ``poses``), read as a
:class:`~evalsuite.motion.smplx_motion.SmplxMotion` (see :mod:`evalsuite.motion.smplx` for the keys)."""
from __future__ import annotations

import os
import pathlib
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.motion.formats import MotionFormat
from evalsuite.motion.smplx import is_smplx_npz, read_smplx
from evalsuite.motion.smplx_body import optional_model_path
from evalsuite.motion.smplx_motion import SmplxMotion

__all__ = ["FORMAT", "load_smplx"]


def load_smplx(path: pathlib.Path, *, fps: float | None = None, smplx_model: str | os.PathLike[str] | None = None,
               positions: str = "full", betas: np.ndarray | None = None, nan: str = "error",
               **_: Any) -> SmplxMotion:
    """An SMPL-X motion. ``smplx_model`` (or ``EVALSUITE_SMPLX_MODEL``) makes positions available, in the mode
    ``positions`` (``full`` or ``leaderboard``) with ``betas`` instead of the file's when given; ``fps``, when
    given, must agree with the file's ``mocap_frame_rate``."""
    data = read_smplx(path, nan=nan)
    if fps is not None and abs(fps - data.fps) > 1e-6 * data.fps:
        raise InputError(f"fps {fps:g} was given but the file says {data.fps:g}; use evalsuite.motion.ops.resample "
                         "to change the frame rate", path=path)
    return SmplxMotion(data, smplx_model=optional_model_path(smplx_model), position_mode=positions, betas=betas,
                       name=path.stem, source=os.fspath(path))


FORMAT = MotionFormat("smplx", (".npz",), load_smplx, is_smplx_npz,
                      "SMPL-X/BEAT2 .npz: axis-angle poses (T, 165), trans, betas, mocap_frame_rate")
