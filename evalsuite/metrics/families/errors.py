"""Pose-error family: APE and MAE against the natural motion of the same sequence
(:mod:`evalsuite.metrics.pose_errors`)."""
from __future__ import annotations

import numpy as np

from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext
from evalsuite.metrics.pose_errors import average_position_error, mean_absolute_error

__all__ = ["PoseErrorFamily", "FAMILY"]


class PoseErrorFamily(MetricFamily):
    """Per sequence: per-joint APE/MAE over the frames both files have; per condition: means."""

    name = "errors"
    metrics = (MetricInfo("ape", "units", "lower", description="average position error (Euclidean)"),
               MetricInfo("mae", "units", "lower", description="mean absolute coordinate error"))
    _functions = {"ape": average_position_error, "mae": mean_absolute_error}

    def measure(self, ctx: SequenceContext) -> None:
        aligned = ctx.aligned()
        if aligned is None:
            return
        for q, func in self._functions.items():
            ctx.record[f"{q}_joint"] = func(*aligned)

    def reduce(self, ctx: ReduceContext) -> None:
        for q in self._functions:
            if ctx.wants(q):
                table = np.stack([ctx.recs[s][f"{q}_joint"] for s in ctx.names])
                ctx.mean_metric(q, table.mean(axis=1))
                ctx.joint_rows(q, table.mean(axis=0))


FAMILY = PoseErrorFamily()
