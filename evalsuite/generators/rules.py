"""The rules the runner enforces on every plug-in's output (``docs/generators.md`` § Rules).

:func:`conform` takes what a plug-in returned for one request and gives the motion as it will be written,
plus notes of every change made to it, or raises :class:`GeneratorError` naming the plug-in and segment:

1. a :class:`~evalsuite.motion.Motion` of the kind the spec declares (BVH rotations or positions);
2. finite values only;
3. joint names unique and non-empty, and within the spec's declared joints when it declares them;
4. frame rate: resampled to the requested fps when it differs (slerp on rotations, linear on positions),
   noted as ``resampled``;
5. length: ``round(duration * fps)`` frames; a result within ``max(1 frame, 2 %)`` is trimmed, or padded by
   holding the last frame, and noted; anything else is an error.

An SMPL-X result (``GenerationResult.smplx``, from an SMPL-X source) is checked by :func:`conform_smplx`.
"""
from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from evalsuite.generators.contract import GenerationRequest, GenerationResult, GeneratorError, GeneratorSpec
from evalsuite.motion import Motion
from evalsuite.motion.ops import resample

__all__ = ["conform", "conform_smplx", "length_tolerance", "motion_digest"]


def length_tolerance(n_frames: int) -> int:
    """Frames a result may be off by and still be trimmed or padded: ``max(1, floor(0.02 * n))``."""
    return max(1, int(0.02 * n_frames))


def motion_digest(motion: Motion) -> str:
    """sha256 of the motion's numbers (channel values, or positions) and fps: equal digests, equal output."""
    h = hashlib.sha256()
    data = motion.values if motion.is_hierarchical else motion.positions()
    h.update(np.ascontiguousarray(data, dtype=np.float64).tobytes())
    h.update(repr((motion.fps, tuple(motion.joint_names))).encode())
    return h.hexdigest()


def _fail(spec: GeneratorSpec, req: GenerationRequest, message: str) -> GeneratorError:
    return GeneratorError(f"generator {spec.name!r}, segment {req.segment_id!r}: {message}")


def _check_finite(spec: GeneratorSpec, req: GenerationRequest, motion: Motion) -> None:
    data = motion.values if motion.is_hierarchical else motion.positions().reshape(motion.n_frames, -1)
    bad = ~np.isfinite(data)
    if bad.any():
        frame, col = (int(v) for v in np.argwhere(bad)[0])
        what = (motion.skeleton.channel_names()[col] if motion.is_hierarchical
                else f"{motion.joint_names[col // 3]}.{'xyz'[col % 3]}")
        raise _fail(spec, req, f"output has {int(bad.sum())} non-finite values (first at frame {frame}, {what}); "
                               "every value must be a finite number")


def _check_joints(spec: GeneratorSpec, req: GenerationRequest, motion: Motion) -> None:
    names = motion.joint_names
    if any(not isinstance(n, str) or not n.strip() for n in names):
        raise _fail(spec, req, "output has an empty joint name")
    if spec.joints:
        unknown = [n for n in names if n not in spec.joints]
        if unknown:
            raise _fail(spec, req, f"output has joints the spec does not declare: {', '.join(unknown[:5])}"
                                   f"{' …' if len(unknown) > 5 else ''} (declared: {', '.join(spec.joints[:8])}"
                                   f"{' …' if len(spec.joints) > 8 else ''})")


def _fix_length(spec: GeneratorSpec, req: GenerationRequest, motion: Motion, notes: list[dict[str, Any]]) -> Motion:
    want, got = req.n_frames, motion.n_frames
    if got == want:
        return motion
    tol = length_tolerance(want)
    if abs(got - want) > tol:
        raise _fail(spec, req, f"output has {got} frames at {req.fps:g} fps, expected {want} "
                               f"({req.duration:.3f} s) within {tol} frame(s) (max of 1 frame and 2 %)")
    if motion.is_hierarchical:
        v = motion.values
        new = v[:want] if got > want else np.concatenate([v, np.repeat(v[-1:], want - got, axis=0)])
        out = motion.with_values(new)
    else:
        p = motion.positions()
        new = p[:want] if got > want else np.concatenate([p, np.repeat(p[-1:], want - got, axis=0)])
        out = motion.with_positions(new)
    notes.append({"rule": "length", "action": "trimmed" if got > want else "padded (last frame held)",
                  "from_frames": got, "to_frames": want})
    return out


def conform(spec: GeneratorSpec, req: GenerationRequest, result: Any) -> tuple[Motion, list[dict[str, Any]]]:
    """The plug-in's result for ``req`` checked and fixed by the rules above; ``notes`` lists every fix."""
    motion = result.motion if isinstance(result, GenerationResult) else None
    if not isinstance(motion, Motion):
        raise _fail(spec, req, f"generate() must return a GenerationResult holding an evalsuite Motion, "
                               f"got {type(result).__name__}")
    if spec.output == "bvh" and not motion.is_hierarchical:
        raise _fail(spec, req, "the spec declares BVH output (rotations) but the motion holds positions only")
    if motion.n_frames == 0:
        raise _fail(spec, req, "output has no frames")
    notes: list[dict[str, Any]] = []
    _check_finite(spec, req, motion)
    _check_joints(spec, req, motion)
    if abs(motion.fps - req.fps) > 1e-6 * req.fps:
        notes.append({"rule": "fps", "action": "resampled", "from_fps": motion.fps, "to_fps": req.fps,
                      "method": "slerp (rotations), linear (positions)"})
        motion = resample(motion, req.fps)
        # resampling keeps frames up to the last original frame's time; the length rule pads the rest
    return _fix_length(spec, req, motion, notes), notes


def conform_smplx(spec: GeneratorSpec, req: GenerationRequest, data: Any, post: bool) -> Any:
    """The rules for an SMPL-X result (:attr:`GenerationResult.smplx`): finite ``poses``/``trans``, the requested
    frame rate and exactly ``req.n_frames`` frames (the SMPL-X operators fit them), no post-processing filter."""
    if post:
        raise _fail(spec, req, "post-processing filters work on BVH or positions motion, not on SMPL-X output")
    for key in ("poses", "trans"):
        bad = ~np.isfinite(np.asarray(getattr(data, key)))
        if bad.any():
            frame, col = (int(v) for v in np.argwhere(bad)[0])
            raise _fail(spec, req, f"SMPL-X output has {int(bad.sum())} non-finite {key} values (first at frame "
                                   f"{frame}, column {col}); every value must be a finite number")
    if abs(data.fps - req.fps) > 1e-6 * req.fps or data.n_frames != req.n_frames:
        raise _fail(spec, req, f"SMPL-X output has {data.n_frames} frames at {data.fps:g} fps, expected "
                               f"{req.n_frames} at {req.fps:g} fps")
    return data
