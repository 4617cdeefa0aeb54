"""Distribution family: FD_g, FD_k (Fréchet distances of poses and frame differences), L1 diversity and
Div_k (:mod:`evalsuite.metrics.distribution`)."""
from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from evalsuite.metrics.distribution import combine_moments, div_k_sequence, frechet_from_moments, l1div_parts, moments
from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext
from evalsuite.metrics.families.cca import cca_halves
from evalsuite.metrics.frechet import FrechetWarning

__all__ = ["DistributionFamily", "FAMILY"]

_FD = {"fd_g": "pose_moments", "fd_k": "diff_moments"}


class DistributionFamily(MetricFamily):
    """Per sequence: exact moments (count, mean, scatter) of the pose vectors and of their frame
    differences, the L1 sum and Div_k; per condition: Fréchet distances of the pooled moments against the
    natural sequences paired with it (bootstrap over sequences), L1div pooled over frames, Div_k mean."""

    name = "distribution"
    metrics = (MetricInfo("fd_g", "units^2", "lower", description="Fréchet distance of pose vectors"),
               MetricInfo("fd_k", "units^2", "lower", description="Fréchet distance of frame differences"),
               MetricInfo("l1div", "units", "closer to natural", description="L1 diversity"),
               MetricInfo("div_k", "units^2", "closer to natural", description="mean variance over time"))

    def measure(self, ctx: SequenceContext) -> None:
        flat = ctx.pos.reshape(len(ctx.pos), -1)
        halves = cca_halves(ctx) if "cca" in ctx.families else None
        if halves is not None and halves[1][0][0] + halves[1][1][0] == len(flat):
            # the CCA family's Sxx halves give the same moments without another D x D product
            ctx.record["pose_moments"] = combine_moments(halves[1])
        else:
            ctx.record["pose_moments"] = moments(flat)
        ctx.record["diff_moments"] = moments(np.diff(flat, axis=0))
        ctx.record["l1_sum"] = l1div_parts(ctx.pos)[0]
        ctx.record["div_k"] = div_k_sequence(ctx.pos)

    def fold(self, index: int, cond: str, record: dict[str, Any], natural: dict[str, Any], acc: dict[str, Any]) -> None:
        for key in _FD.values():
            if key in record:
                for k, m in ((key, record[key]), ("natural_" + key, natural[key])):
                    acc[k] = m if k not in acc else combine_moments([acc[k], m])

    def drop(self, record: dict[str, Any]) -> None:
        for key in _FD.values():
            record.pop(key, None)

    def reduce(self, ctx: ReduceContext) -> None:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", FrechetWarning)
            for q, key in _FD.items():
                if not ctx.wants(q):
                    continue
                value = frechet_from_moments(ctx.acc["natural_" + key], ctx.acc[key])
                pc = [ctx.recs[s].get(key) for s in ctx.names]
                pr = [ctx.ref[s].get(key) for s in ctx.names]

                def resampled(w: np.ndarray, pc: list[Any] = pc, pr: list[Any] = pr) -> list[float]:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", FrechetWarning)
                        return [frechet_from_moments(combine_moments(pr, wb), combine_moments(pc, wb)) for wb in w]

                ctx.add(q, value, n=ctx.n, ci=ctx.boot(resampled))
        ctx.issues.extend(f"{ctx.cond}: {c.message}" for c in caught)
        if ctx.wants("l1div"):
            sums = np.array([ctx.recs[s]["l1_sum"] for s in ctx.names])
            frames = np.array([ctx.recs[s]["n_frames"] for s in ctx.names], dtype=np.float64)
            ctx.sequence_rows("l1div", sums / frames)
            ctx.add("l1div", sums.sum() / frames.sum(), n=ctx.n, ci=ctx.boot(lambda w: (w @ sums) / (w @ frames)))
        if ctx.wants("div_k"):
            ctx.mean_metric("div_k", [ctx.recs[s]["div_k"] for s in ctx.names])


FAMILY = DistributionFamily()
