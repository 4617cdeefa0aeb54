"""Motion data: one :class:`Motion` type, BVH I/O, forward kinematics, rotations, operations.

Modules: :mod:`~evalsuite.motion.bvh` (read/write), :mod:`~evalsuite.motion.fk` (forward
kinematics and its conventions), :mod:`~evalsuite.motion.rotations`,
:mod:`~evalsuite.motion.ops` (joint selection, resampling, cutting, centering),
:mod:`~evalsuite.motion.filters` (smoothing), :mod:`~evalsuite.motion.presets` (named joint
sets), :mod:`~evalsuite.motion.io` (loading/saving any supported file).
"""
from evalsuite.motion.io import load_motion, save_motion
from evalsuite.motion.motion import Motion
from evalsuite.motion.skeleton import Skeleton

__all__ = ["Motion", "Skeleton", "load_motion", "save_motion"]
