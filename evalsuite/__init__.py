"""evalsuite: evaluation platform for speech-driven gesture generation.

The stable Python API::

    import evalsuite
    motion = evalsuite.load_motion("take.bvh")
    motion.fps, motion.joint_names, motion.positions()   # (T, J, 3)
"""
from __future__ import annotations

from evalsuite._version import __version__
from evalsuite.errors import BVHError, InputError, MotionError
from evalsuite.motion import Motion, Skeleton, load_motion, save_motion

__all__ = [
    "__version__",
    "BVHError",
    "InputError",
    "MotionError",
    "Motion",
    "Skeleton",
    "load_motion",
    "save_motion",
]
