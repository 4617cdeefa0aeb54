"""``random_segments``: random clips of natural motion, cross-faded (the retrieval floor).

For each segment, clips of ``clip_min``..``clip_max`` seconds are drawn from the *other* segments' source
motion (never the segment's own) and joined with cross-fades of ``fade`` seconds (slerp on joint rotations,
linear on positions). Each next clip starts at the best of ``candidates`` random start frames: the one whose
pose is closest to where the previous clip ends (a motion-graph transition), so that cross-fades add no jump
larger than natural frame-to-frame motion. Seeded by the request's seed.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evalsuite.generators.conditions.source import OF_OPTION, source_motion
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)
from evalsuite.motion import Motion
from evalsuite.motion.joint_rotations import blend_values
from evalsuite.motion.ops import resample

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
        pool = [resample(source_motion(self.option("of"), r), fps) for r in requests]
        return [self._one(r, [m for j, m in enumerate(pool) if j != i]) for i, r in enumerate(requests)]

    def _one(self, req: GenerationRequest, pool: list[Motion]) -> GenerationResult:
        rng = np.random.default_rng(req.seed)
        fps = req.fps
        cmin, cmax = self.float_option("clip_min", 2.0), self.float_option("clip_max", 4.0)
        fade = max(1, int(round(self.float_option("fade", 0.5) * fps)))
        n_cand = self.int_option("candidates", 16)
        template = pool[0]
        frames: np.ndarray | None = None
        clips = []
        while frames is None or len(frames) < req.n_frames:
            length = int(round(rng.uniform(cmin, cmax) * fps)) + fade
            k = int(rng.integers(len(pool)))
            src = _frames(pool[k])
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
                joined = (blend_values(template, tail, clip[:fade], w) if template.is_hierarchical
                          else tail * (1 - w)[:, None] + clip[:fade] * w[:, None])
                frames = np.concatenate([frames[:-fade], joined, clip[fade:]])
            clips.append({"from": k, "start": start, "frames": length})
        frames = frames[: req.n_frames]
        m = (template.with_values(frames, fps=fps) if template.is_hierarchical
             else template.with_positions(frames.reshape(len(frames), template.n_joints, 3), fps=fps))
        return GenerationResult(m, {"clips": len(clips)})
