"""Motion data: one :class:`Motion` type, BVH I/O, forward kinematics, rotations, operations.

Modules: :mod:`~evalsuite.motion.bvh` (read/write), :mod:`~evalsuite.motion.fk` (forward
kinematics and its conventions), :mod:`~evalsuite.motion.rotations`,
:mod:`~evalsuite.motion.ops` (joint selection, resampling, cutting, centering),
:mod:`~evalsuite.motion.filters` (smoothing), :mod:`~evalsuite.motion.presets` (named joint
sets), :mod:`~evalsuite.motion.io` (loading/saving any registered file type),
:mod:`~evalsuite.motion.formats` (the motion format registry), :mod:`~evalsuite.motion.smplx` and its
siblings (SMPL-X files, positions from the user's model file, :class:`~evalsuite.motion.smplx_motion.SmplxMotion`).
"""
from evalsuite.motion.io import load_motion, save_motion
from evalsuite.motion.motion import Motion
from evalsuite.motion.skeleton import Skeleton

__all__ = ["Motion", "Skeleton", "load_motion", "save_motion"]
