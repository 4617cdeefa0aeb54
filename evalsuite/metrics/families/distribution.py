"""Distribution family: FD_g, FD_k (Fréchet distances of poses and frame differences), L1 diversity and
Div_k (:mod:`evalsuite.metrics.distribution`)."""
from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from evalsuite.metrics.distribution import (
    bootstrap_frechet,
    combine_moments,
    div_k_sequence,
    frechet_from_moments,
    l1div_parts,
    moments,
)
from evalsuite.metrics.families.base import (
    NAN,
    NAN_CI,
    MetricFamily,
    MetricInfo,
    ReduceContext,
    SequenceContext,
    bootstrap_bias,
    centred_ci,
)
from evalsuite.metrics.families.cca import cca_halves
from evalsuite.metrics.frechet import FrechetWarning, sample_size_warnings

__all__ = ["DistributionFamily", "FAMILY"]

_FD = {"fd_g": "pose_moments", "fd_k": "diff_moments"}


class DistributionFamily(MetricFamily):
    """Per sequence: exact moments (count, mean, scatter) of the pose vectors and of their frame
    differences, the L1 sum and Div_k; per condition: Fréchet distances of the pooled moments against the
    natural sequences paired with it, L1div pooled over frames, Div_k mean.

    Bootstrap: the sequence names are resampled, the same draw for the condition and its natural
    counterparts (paired). The Fréchet distances' interval is :func:`centred_ci` (it contains the
    estimate) with the bootstrap bias in the row's ``bootstrap_bias``; too small samples are reported
    (:func:`~evalsuite.metrics.frechet.sample_size_warnings`)."""

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

    def bootstrap_work(self, setup: Any) -> int:
        return sum(q in setup.metrics for q in _FD)

    def reduce(self, ctx: ReduceContext) -> None:
        for q, key in _FD.items():
            if not ctx.wants(q):
                continue
            nat, mine = ctx.acc["natural_" + key], ctx.acc[key]
            with warnings.catch_warnings():  # sample_size_warnings below says it, once and with the reason
                warnings.simplefilter("ignore", FrechetWarning)
                value = frechet_from_moments(nat, mine)
            if ctx.cond != ctx.reference:  # natural vs itself: 0 by construction, in every resample too
                ctx.issues.extend(f"{ctx.cond}: {q}: {w}" for w in sample_size_warnings(
                    (nat[0], mine[0]), len(nat[1]), (ctx.n, ctx.n), "frames" if q == "fd_g" else "frame differences"))
            ci, bias = NAN_CI, NAN
            if ctx.weights is not None:
                if ctx.cond == ctx.reference:
                    samples = np.zeros(ctx.n_bootstrap)
                else:
                    samples = bootstrap_frechet([ctx.ref[s][key] for s in ctx.names],
                                                [ctx.recs[s][key] for s in ctx.names], ctx.weights,
                                                threads=ctx.threads, progress=ctx.advance)
                ci, bias = centred_ci(value, samples), bootstrap_bias(value, samples)
            ctx.add(q, value, n=ctx.n, ci=ci)
            if ctx.weights is not None:
                ctx.summary[-1]["bootstrap_bias"] = bias
        if ctx.wants("l1div"):
            sums = np.array([ctx.recs[s]["l1_sum"] for s in ctx.names])
            frames = np.array([ctx.recs[s]["n_frames"] for s in ctx.names], dtype=np.float64)
            ctx.sequence_rows("l1div", sums / frames)
            ctx.add("l1div", sums.sum() / frames.sum(), n=ctx.n, ci=ctx.boot(lambda w: (w @ sums) / (w @ frames)))
        if ctx.wants("div_k"):
            ctx.mean_metric("div_k", [ctx.recs[s]["div_k"] for s in ctx.names])


FAMILY = DistributionFamily()
