"""Kinematics family: average speed, acceleration and jerk (:mod:`evalsuite.metrics.kinematics`)."""
from __future__ import annotations

import numpy as np

from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext
from evalsuite.metrics.kinematics import ORDERS

__all__ = ["KinematicsFamily", "FAMILY"]


class KinematicsFamily(MetricFamily):
    """Per sequence: the per-joint mean of the n-th derivative norm; per condition: the mean over joints,
    averaged over sequences (std across sequences), and per-joint rows (GENEA's procedure)."""

    name = "kinematics"
    metrics = tuple(MetricInfo(q, better="closer to natural", unit_order=o,
                               description=f"average {q} of the joints (finite differences of order {o})")
                    for q, o in ORDERS.items())

    def measure(self, ctx: SequenceContext) -> None:
        for q, order in ORDERS.items():
            ctx.record[f"{q}_joint"] = ctx.norms(order).mean(axis=0)

    def reduce(self, ctx: ReduceContext) -> None:
        for q in ORDERS:
            if ctx.wants(q):
                table = np.stack([ctx.recs[s][f"{q}_joint"] for s in ctx.names])
                ctx.mean_metric(q, table.mean(axis=1))
                ctx.joint_rows(q, table.mean(axis=0))


FAMILY = KinematicsFamily()
