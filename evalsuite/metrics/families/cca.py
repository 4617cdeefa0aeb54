"""CCA family: canonical correlation between generated and natural poses (:mod:`evalsuite.metrics.cca`),
cross-fitted over two folds of sequences (or two halves in time), or in-sample by convention."""
from __future__ import annotations

from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.metrics.cca import cca_fit_moments, cca_score_moments
from evalsuite.metrics.distribution import combine_moments
from evalsuite.metrics.families.base import MetricFamily, MetricInfo, ReduceContext, SequenceContext

__all__ = ["CCAFamily", "FAMILY", "cca_halves"]

Moments = tuple[Any, np.ndarray, np.ndarray]


def _centred_halves(x: np.ndarray) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """``[(n, mean, x - mean)]`` of the first and second half of ``(N, D)`` frames."""
    half = len(x) // 2
    return [(len(p), p.mean(axis=0), p - p.mean(axis=0)) for p in (x[:half], x[half:])]


def cca_halves(ctx: SequenceContext) -> tuple[tuple[Moments, Moments], list[Moments]] | None:
    """Moments of stacked ``[x; y]`` frames (this file, natural) in two halves in time, and the ``Sxx``
    halves alone (from which the pose moments follow without another product: the distribution family
    reuses them when CCA runs too). Built from blocks: ``Sxx`` and ``Sxy`` per file, the natural ``Syy``
    once per sequence. Computed once per file."""
    aligned = ctx.aligned()
    if aligned is None:
        return None

    def compute() -> tuple[tuple[Moments, Moments], list[Moments]]:
        x, _ = aligned
        x_flat = x.reshape(len(x), -1)
        n_common = len(x_flat)
        nat = ctx.natural_pos
        assert nat is not None
        if n_common not in ctx.natural_cache:
            hy = _centred_halves(nat.reshape(len(nat), -1)[:n_common])
            ctx.natural_cache[n_common] = (hy, [cy.T @ cy for _, _, cy in hy])
        hy, syy = ctx.natural_cache[n_common]
        out, xx = [], []
        for (n, mx, cx), (_, my, cy), s_yy in zip(_centred_halves(x_flat), hy, syy):
            s_xx, s_xy = cx.T @ cx, cx.T @ cy
            out.append((n, np.concatenate([mx, my]), np.block([[s_xx, s_xy], [s_xy.T, s_yy]])))
            xx.append((n, mx, s_xx))
        return (out[0], out[1]), xx

    return ctx.memo("cca_halves", compute)


class CCAFamily(MetricFamily):
    name = "cca"
    metrics = (MetricInfo("cca", "r", "higher", description="first canonical correlation, generated vs natural"),)

    def measure(self, ctx: SequenceContext) -> None:
        halves = cca_halves(ctx)
        if halves is not None:
            ctx.record["cca_halves"] = halves[0]

    def fold(self, index: int, cond: str, record: dict[str, Any], natural: dict[str, Any], acc: dict[str, Any]) -> None:
        halves = record.pop("cca_halves", None)
        if halves is None:
            return
        _add(acc, f"cca_fold{index % 2}", combine_moments(list(halves)))
        _add(acc, "cca_first_half", halves[0])
        _add(acc, "cca_second_half", halves[1])

    def reduce(self, ctx: ReduceContext) -> None:
        if ctx.wants("cca"):
            value = _cca_value(ctx.acc, len(ctx.setup.joints) * 3, ctx.conv.cca_in_sample, ctx)
            ctx.add("cca", value, n=ctx.n)


def _add(acc: dict[str, Any], key: str, m: Moments) -> None:
    acc[key] = m if key not in acc else combine_moments([acc[key], m])


def _cca_value(acc: dict[str, Any], dx: int, in_sample: bool, ctx: ReduceContext) -> float:
    """In-sample, or cross-fitted over two folds of sequences (both ways, averaged); when a fold is empty
    (a single sequence), over the first and second halves in time."""
    try:
        folds: list[Any] = [acc.get("cca_fold0"), acc.get("cca_fold1")]
        if in_sample:
            whole = combine_moments([f for f in folds if f is not None])
            return float(cca_fit_moments(*whole, dx).correlation)
        if folds[0] is None or folds[1] is None:
            folds = [acc["cca_first_half"], acc["cca_second_half"]]
        (na, mean_a, s_a), (nb, mean_b, s_b) = folds
        scores = [cca_score_moments(cca_fit_moments(na, mean_a, s_a, dx), nb, mean_b, s_b, dx),
                  cca_score_moments(cca_fit_moments(nb, mean_b, s_b, dx), na, mean_a, s_a, dx)]
        return float(np.mean(scores))
    except InputError as exc:
        ctx.issues.append(f"{ctx.cond}: CCA not computed ({exc.reason})")
        return float("nan")


FAMILY = CCAFamily()
