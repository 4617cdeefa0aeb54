"""Histogram family: speed/acceleration histograms against natural motion with the Hellinger distance
(:mod:`evalsuite.metrics.histograms`), pooled over joint groups and per sequence."""
from __future__ import annotations

from functools import partial

import numpy as np

from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext
from evalsuite.metrics.histograms import clipped_fraction, hellinger_rows, joint_histograms

__all__ = ["HistogramFamily", "FAMILY"]

QUANTITIES = {"speed": 1, "acceleration": 2}


class HistogramFamily(MetricFamily):
    """Per sequence: per-joint counts of the derivative norms in the setup's bins (+ one overflow column).
    Per condition: Hellinger distance of the pooled histogram of each joint group to the natural one
    (``hellinger_<q>[group]``), the mean of per-sequence distances (``hellinger_<q>_seq``), the share above
    the last bin (``clipped_<q>``), and per-joint distances."""

    name = "histograms"
    metrics = tuple(
        m for q in QUANTITIES for m in (
            MetricInfo(f"hellinger_{q}", "H", "lower", description=f"Hellinger distance of {q} histograms"),
            MetricInfo(f"hellinger_{q}_seq", "H", "lower",
                       description=f"mean per-sequence Hellinger distance of {q} histograms"),
            MetricInfo(f"clipped_{q}", "fraction", "closer to natural",
                       description=f"share of {q} values above the last bin")))
    # the summary rows come in this order (hellinger per group, per sequence, clipped) for each quantity

    def measure(self, ctx: SequenceContext) -> None:
        for q, order in QUANTITIES.items():
            if q in ctx.setup.edges:
                ctx.record[f"hist_{q}"] = joint_histograms(ctx.norms(order), ctx.setup.edges[q])

    def reduce(self, ctx: ReduceContext) -> None:
        setup = ctx.setup
        use = slice(None) if ctx.conv.overflow else slice(0, -1)
        for q in QUANTITIES:
            key = f"hist_{q}"
            if q not in setup.edges:
                continue
            hc = np.stack([ctx.recs[s][key] for s in ctx.names]).astype(np.float64)   # (n, J, B+1)
            hr = np.stack([ctx.ref[s][key] for s in ctx.names]).astype(np.float64)
            for gname, members in setup.groups.items():
                gi = [setup.joints.index(m) for m in members]
                gc, gr = hc[:, gi].sum(axis=1), hr[:, gi].sum(axis=1)       # (n, B+1)
                metric = f"hellinger_{q}" + ("" if gname == "all" else f"[{gname}]")
                if ctx.wants(f"hellinger_{q}"):
                    value = hellinger_rows(gc.sum(0)[use], gr.sum(0)[use])
                    ci = ctx.boot(partial(_resampled_hellinger, gc, gr, use))
                    ctx.add(metric, value, n=ctx.n, ci=ci, unit="H")
                ctx.histograms.append({"condition": ctx.cond, "quantity": q, "group": gname, "counts": gc.sum(0)})
            if ctx.wants(f"hellinger_{q}_seq"):
                ctx.mean_metric(f"hellinger_{q}_seq", hellinger_rows(hc.sum(1)[:, use], hr.sum(1)[:, use]), unit="H")
            if ctx.wants(f"clipped_{q}"):
                tot = hc.sum(axis=1)   # (n, B+1)
                ctx.add(f"clipped_{q}", float(clipped_fraction(tot.sum(0))), n=ctx.n,
                        ci=ctx.boot(partial(_resampled_clipped, tot)), unit="fraction")
            if ctx.wants(f"hellinger_{q}"):
                ctx.joint_rows(f"hellinger_{q}", [float(hellinger_rows(hc[:, j].sum(0)[use], hr[:, j].sum(0)[use]))
                                                  for j in range(len(setup.joints))], unit="H")


def _resampled_hellinger(gc: np.ndarray, gr: np.ndarray, use: slice, w: np.ndarray) -> np.ndarray:
    return hellinger_rows((w @ gc)[:, use], (w @ gr)[:, use])


def _resampled_clipped(tot: np.ndarray, w: np.ndarray) -> np.ndarray:
    return clipped_fraction(w @ tot)


FAMILY = HistogramFamily()
