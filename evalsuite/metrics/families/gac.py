"""Gesture Area Coverage family (:mod:`evalsuite.metrics.gac`): each file's coverage grid against the natural
file's, truncated to their common length.

Per sequence: TP, FP, FN (pixels) and Dice = 2 TP / (2 TP + FP + FN). Per condition:

* ``gac_dice``, ``gac_fp``, ``gac_fn``: means over sequences (std across sequences, bootstrap CI);
* ``gac_dice[pooled]`` = 2 ΣTP / (2 ΣTP + ΣFP + ΣFN); ``gac_fp[pooled]`` = ΣFP / Σ|N| and
  ``gac_fn[pooled]`` = ΣFN / Σ|N| (fractions of the natural coverage), sums over sequences.

Not in the default metric set: ``-m gac`` (convention ``tonoli2024``) or ``--gac CONVENTION``.
"""
from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np

from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext
from evalsuite.metrics.gac import GacConvention, coverage, coverage_stats, dice, parse_gac

__all__ = ["GacFamily", "FAMILY"]

KEYS = ("tp", "fp", "fn", "area_natural", "area")


class GacFamily(MetricFamily):
    """GAC under one :class:`~evalsuite.metrics.gac.GacConvention` (``convention``: a name or spec)."""

    name = "gac"
    metrics = (
        MetricInfo("gac_dice", "Dice", "higher", description="Dice of the coverage grids (2 TP / (2 TP + FP + FN))"),
        MetricInfo("gac_fp", "px", "lower", description="pixels covered by the condition only (false positives)"),
        MetricInfo("gac_fn", "px", "lower", description="pixels covered by natural motion only (false negatives)"),
    )
    default = False

    def __init__(self, convention: str | GacConvention | None = None, *, default: bool = False):
        self.convention = parse_gac(convention)
        self.default = default

    def _grid(self, motion: Any, n: int | None = None) -> np.ndarray:
        pos = motion.positions()
        return coverage(pos if n is None else pos[:n], motion.parents, motion.joint_names, self.convention)

    def measure(self, ctx: SequenceContext) -> None:
        if ctx.natural_pos is ctx.pos:   # the natural file, measured first: keep it for the others
            ctx.natural_cache["gac_motion"] = ctx.motion
        natural = ctx.natural_cache.get("gac_motion")
        if natural is None:
            return
        n = min(ctx.motion.n_frames, natural.n_frames)
        nat = ctx.natural_cache.get(("gac_grid", n))
        if nat is None:
            nat = ctx.natural_cache[("gac_grid", n)] = self._grid(natural, n)
        own = nat if natural is ctx.motion else self._grid(ctx.motion, n)
        ctx.record.update({f"gac_{k}": v for k, v in coverage_stats(nat, own).items()})
        if ctx.setup.figures:
            ctx.record["gac_grids"] = (np.packbits(own), np.packbits(nat), own.shape)

    def fold(self, index: int, cond: str, record: dict[str, Any], natural: dict[str, Any], acc: dict[str, Any]) -> None:
        grids = record.get("gac_grids")
        if grids is None:
            return
        own = np.unpackbits(grids[0])[: int(np.prod(grids[2]))].reshape(grids[2])
        acc["gac_sum"] = acc.get("gac_sum", 0) + own.astype(np.int32)
        acc["gac_count"] = acc.get("gac_count", 0) + 1
        if "gac_first" not in acc:
            acc["gac_first"] = grids

    def drop(self, record: dict[str, Any]) -> None:
        record.pop("gac_grids", None)

    def reduce(self, ctx: ReduceContext) -> None:
        names = [s for s in ctx.names if "gac_tp" in ctx.recs[s]]
        if not names:
            return
        t = {k: np.array([ctx.recs[s][f"gac_{k}"] if s in names else np.nan for s in ctx.names], dtype=np.float64)
             for k in KEYS}
        per_seq = {"gac_dice": dice(t["tp"], t["fp"], t["fn"]), "gac_fp": t["fp"], "gac_fn": t["fn"]}
        totals = np.stack([t["tp"], t["fp"], t["fn"], t["area_natural"]], axis=1)   # (n, 4)
        totals = np.where(np.isfinite(totals), totals, 0.0)
        pooled = _pooled(totals[None])[0]
        for k, metric in enumerate(("gac_dice", "gac_fp", "gac_fn")):
            if ctx.wants(metric):
                ctx.mean_metric(metric, per_seq[metric])
                unit = "Dice" if k == 0 else "fraction of natural coverage"
                ctx.add(f"{metric}[pooled]", pooled[k], n=len(names), unit=unit,
                        ci=ctx.boot(partial(_resampled, totals, k)))
        if "gac_sum" in ctx.acc:
            ctx.figure_data.setdefault("gac", {})[ctx.cond] = {
                "share": ctx.acc["gac_sum"] / ctx.acc["gac_count"], "first": ctx.acc["gac_first"],
                "convention": self.convention.name}


def _pooled(totals: np.ndarray) -> np.ndarray:
    """``(B, 3)`` pooled Dice, FP and FN shares from summed ``(B, 4)`` [TP, FP, FN, |N|] (or ``(B, n, 4)``)."""
    s = totals.sum(axis=-2) if totals.ndim == 3 else totals
    tp, fp, fn, area = s[..., 0], s[..., 1], s[..., 2], s[..., 3]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.stack([dice(tp, fp, fn), fp / area, fn / area], axis=-1)


def _resampled(totals: np.ndarray, k: int, w: np.ndarray) -> np.ndarray:
    return np.asarray(_pooled(w @ totals))[:, k]


FAMILY = GacFamily()
