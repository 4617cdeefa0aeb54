"""``random_segments``: random clips of natural motion, cross-faded (the retrieval floor).

For each segment, clips of ``clip_min``..``clip_max`` seconds are drawn from the *other* segments' source
motion (never the segment's own) and joined with cross-fades of ``fade`` seconds (slerp on joint rotations,
linear on positions). Each next clip starts at the best of ``candidates`` random start frames: the one whose
pose is closest to where the previous clip ends (a motion-graph transition), so that cross-fades add no jump
larger than natural frame-to-frame motion. Seeded by the request's seed. SMPL-X sources give SMPL-X output
(slerp per joint on the axis-angle, linear on ``trans`` and ``expressions``).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from evalsuite.generators.conditions.smplx_ops import blend_smplx, fit_smplx
from evalsuite.generators.conditions.source import OF_OPTION, source_path
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)
from evalsuite.motion import Motion
from evalsuite.motion.io import load_motion
from evalsuite.motion.joint_rotations import blend_values
from evalsuite.motion.ops import resample
from evalsuite.motion.smplx import SmplxData, is_smplx_npz, read_smplx

__all__ = ["RandomSegments"]


def _frames(m: Motion) -> np.ndarray:
    return m.values if m.is_hierarchical else m.positions().reshape(m.n_frames, -1)


class RandomSegments(Generator):
    spec = GeneratorSpec(
        name="random_segments", version="1", kind="condition", stochastic=True, output="any",
        summary="Random clips (2-4 s) of the other segments' motion joined by 0.5 s cross-fades at the closest "
                "of 16 candidate poses; seeded.",
        config={**OF_OPTION, "clip_min": "shortest clip in seconds (default 2)",
                "clip_max": "longest clip in seconds (default 4)", "fade": "cross-fade in seconds (default 0.5)",
                "candidates": "random start frames tried per transition (default 16)"})
    batch_only = True

    def generate(self, request: GenerationRequest) -> GenerationResult:
        raise GeneratorError("random_segments draws from the other segments of the split (the runner calls "
                             "generate_batch)")

    def generate_batch(self, requests: Sequence[GenerationRequest]) -> list[GenerationResult]:
        if len(requests) < 2:
            raise GeneratorError("random_segments needs at least two segments (clips come from the others)")
        fps = requests[0].fps
        paths = [source_path(self.option("of"), r) for r in requests]
        if all(is_smplx_npz(p) for p in paths):
            return self._smplx(requests, [read_smplx(p) for p in paths])
        pool = [resample(load_motion(p), fps) for p in paths]
        out = []
        for i, r in enumerate(requests):
            others = [m for j, m in enumerate(pool) if j != i]
            template = others[0]

            def blend(tail: np.ndarray, clip: np.ndarray, w: np.ndarray, template: Motion = template) -> np.ndarray:
                return (blend_values(template, tail, clip, w) if template.is_hierarchical
                        else tail * (1 - w)[:, None] + clip * w[:, None])

            frames, n_clips = self._join(r, [_frames(m) for m in others], blend)
            m = (template.with_values(frames, fps=fps) if template.is_hierarchical
                 else template.with_positions(frames.reshape(len(frames), template.n_joints, 3), fps=fps))
            out.append(GenerationResult(m, {"clips": n_clips}))
        return out

    def _smplx(self, requests: Sequence[GenerationRequest], items: list[SmplxData]) -> list[GenerationResult]:
        """SMPL-X: clips of [poses | trans | expressions] frames, slerp cross-fades per joint; each segment's own
        other keys (its expressions too where the widths differ)."""
        widths = {None if d.expressions is None else d.expressions.shape[1] for d in items}
        with_expr = len(widths) == 1 and None not in widths
        for d, r in zip(items, requests):
            fit_smplx(d, r)  # the same frame rate
        pool = [np.concatenate([d.poses, d.trans] + ([d.expressions] if with_expr and d.expressions is not None
                                                      else []), axis=1) for d in items]
        out = []
        for i, r in enumerate(requests):
            frames, n_clips = self._join(r, [f for j, f in enumerate(pool) if j != i], blend_smplx)
            base = fit_smplx(items[i], r)
            data = dataclasses.replace(base, poses=frames[:, :165], trans=frames[:, 165:168],
                                       expressions=frames[:, 168:] if with_expr else base.expressions)
            out.append(GenerationResult(None, {"clips": n_clips}, smplx=data))
        return out

    def _join(self, req: GenerationRequest, pool: list[np.ndarray],
              blend: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]) -> tuple[np.ndarray, int]:
        """Frames ``(req.n_frames, D)`` of random clips of ``pool`` (each ``(T_i, D)``) joined by ``blend``."""
        rng = np.random.default_rng(req.seed)
        fps = req.fps
        cmin, cmax = self.float_option("clip_min", 2.0), self.float_option("clip_max", 4.0)
        fade = max(1, int(round(self.float_option("fade", 0.5) * fps)))
        n_cand = self.int_option("candidates", 16)
        frames: np.ndarray | None = None
        clips = 0
        while frames is None or len(frames) < req.n_frames:
            length = int(round(rng.uniform(cmin, cmax) * fps)) + fade
            k = int(rng.integers(len(pool)))
            src = pool[k]
            length = min(length, len(src))
            starts = rng.integers(0, len(src) - length + 1, size=n_cand)
            if frames is None:
                start = int(starts[0])
                frames = src[start:start + length].copy()
            else:
                tail = frames[-fade:]
                # the candidate whose first `fade` frames are closest to the last `fade` frames of what we have
                dist = [float(np.abs(src[s:s + fade] - tail).sum()) if s + fade <= len(src) else np.inf
                        for s in starts]
                start = int(starts[int(np.argmin(dist))])
                clip = src[start:start + length]
                w = (np.arange(1, fade + 1) / (fade + 1))
                frames = np.concatenate([frames[:-fade], blend(tail, clip[:fade], w), clip[fade:]])
            clips += 1
        return frames[: req.n_frames], clips
