"""evalsuite: evaluation platform for speech-driven gesture generation.

The stable Python API::

    import evalsuite
    motion = evalsuite.load_motion("take.bvh")
    motion.fps, motion.joint_names, motion.positions()   # (T, J, 3)
"""
from __future__ import annotations

__version__ = "0.1.0"

from evalsuite.errors import BVHError, InputError, MotionError  # noqa: E402
from evalsuite.motion import Motion, Skeleton, load_motion, save_motion  # noqa: E402

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
