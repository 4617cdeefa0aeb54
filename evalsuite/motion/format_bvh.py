"""The ``bvh`` motion format: BVH files under a named translation convention (:mod:`evalsuite.motion.fk`)."""
from __future__ import annotations

import os
import pathlib
from typing import Any

from evalsuite.errors import InputError
from evalsuite.motion.bvh import read_bvh_file
from evalsuite.motion.fk import CONVENTIONS
from evalsuite.motion.formats import MotionFormat
from evalsuite.motion.motion import Motion, _clean_fps

__all__ = ["FORMAT", "load_bvh"]


def load_bvh(path: pathlib.Path, *, fps: float | None = None, convention: str | None = None,
             root_offset: str | None = None, joint_translation: str | None = None, **_: Any) -> Motion:
    """A hierarchical motion; ``fps``, when given, must agree with the file's ``Frame Time``."""
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


FORMAT = MotionFormat("bvh", (".bvh",), load_bvh, description="BVH: a joint hierarchy and Euler channels")
