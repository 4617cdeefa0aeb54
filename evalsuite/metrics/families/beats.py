"""Beat-alignment family: speech onsets against motion beats of the wrists (:mod:`evalsuite.metrics.beats`)."""
from __future__ import annotations

from evalsuite.metrics.beats import beat_alignment_score, motion_beats
from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext

__all__ = ["BeatFamily", "FAMILY"]


class BeatFamily(MetricFamily):
    """Per sequence: beat alignment audio->motion and motion->audio (Gaussian kernel of width sigma)."""

    name = "beats"
    metrics = (MetricInfo("beat_a2m", "score", "higher", description="speech onsets matched by motion beats"),
               MetricInfo("beat_m2a", "score", "higher", description="motion beats matched by speech onsets"))
    default = False
    needs_audio = True

    def measure(self, ctx: SequenceContext) -> None:
        if ctx.audio_onsets is None:
            return
        wrists = set(ctx.setup.groups.get("wrists", []))
        idx = [i for i, j in enumerate(ctx.setup.joints) if j in wrists]
        mb = motion_beats(ctx.pos[:, idx] if idx else ctx.pos, ctx.fps)
        ctx.record["beat_a2m"] = beat_alignment_score(ctx.audio_onsets, mb, ctx.setup.sigma)
        ctx.record["beat_m2a"] = beat_alignment_score(mb, ctx.audio_onsets, ctx.setup.sigma)

    def reduce(self, ctx: ReduceContext) -> None:
        for q in ("beat_a2m", "beat_m2a"):
            if ctx.wants(q):
                ctx.mean_metric(q, [ctx.recs[s].get(q, float("nan")) for s in ctx.names])


FAMILY = BeatFamily()
