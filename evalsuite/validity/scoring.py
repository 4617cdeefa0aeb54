"""Scoring every condition once, keeping the per-segment records, and bootstrap replicates over segments.

The scoring is the engine's own run (:func:`evalsuite.metrics.engine.score_plan`, as ``evalsuite score
--corpus`` runs it), with every default metric family plus beat alignment and the speech-gesture coupling
family (the corpus brings the speech) and any extra family (FGD). The task results are kept, so a bootstrap
replicate is what ``evalsuite score`` would report on a resample of the segments, the same resample for
every condition (paired). Two ways, one answer:

* most families already compute their resampled values under resampling weights (the engine's own
  bootstrap: means over sequences, pooled histograms, FD_g/FD_k, L1div); a reduce context that keeps those
  values instead of only their percentiles gives them for every condition under one weight matrix;
* the others (cross-fitted CCA, FGD) are reduced again on each replicate's resampled records
  (:func:`evalsuite.metrics.engine.reduce_results`), each drawn segment at a position of the parity it has
  among the sorted segments, so the cross-fitted CCA never fits and tests on copies of one segment.
"""
from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.metrics.engine import ScoreOptions, ScoreResult, copy_task_result, plan_for, reduce_results, score_plan
from evalsuite.metrics.families import (
    MetricFamily,
    ReduceContext,
    metric_index,
    percentile_ci,
    weighted_mean_boot,
)
from evalsuite.parallel import run

__all__ = ["Scored", "score_conditions", "bootstrap_table", "values_table"]

NAN_CI = (float("nan"), float("nan"))


@dataclass
class Scored:
    """The full scoring run (``result``, as ``evalsuite score`` reports it) and its kept task results."""

    result: ScoreResult
    results: list[dict[str, Any]]


def score_conditions(folders: dict[str, pathlib.Path], corpus_root: pathlib.Path, *,
                     extra_families: Sequence[MetricFamily] = (), jobs: int = 1, progress: bool = True) -> Scored:
    """Score every folder against ``folders['natural']`` with all metrics (beats and coupling from the corpus)."""
    options = ScoreOptions(corpus=corpus_root, figures=False, extra_families=tuple(extra_families), jobs=jobs,
                           progress=progress)
    plan = plan_for(f"natural={folders['natural']}", [f"{n}={p}" for n, p in folders.items() if n != "natural"],
                    options)
    result = score_plan(plan, options, keep_task_results=True)
    return Scored(result, result.task_results)


def _resampled(results: list[dict[str, Any]], draw: np.ndarray) -> list[dict[str, Any]]:
    """The drawn task results (renamed copies), each at a position of its original parity (gaps: empty tasks)."""
    parts = [sorted(int(i) for i in draw if i % 2 == p) for p in (0, 1)]
    out: list[dict[str, Any]] = []
    copies: dict[int, int] = {}
    for k in range(max(len(parts[0]), len(parts[1]))):
        for p in (0, 1):
            if k >= len(parts[p]):
                out.append({"name": f"~empty{len(out)}", "records": {}})
                continue
            i = parts[p][k]
            copies[i] = copies.get(i, 0) + 1
            out.append({**copy_task_result(results[i]), "name": f"{results[i]['name']}~{copies[i]}"})
    return out


class _Recording(ReduceContext):
    """A reduce context that keeps the bootstrap replicates of each summary row (``row["replicates"]``): the
    families compute them through :meth:`boot` or :meth:`mean_metric` under this run's shared weights."""

    _stash: np.ndarray | None = None

    def boot(self, statistic: Callable[[np.ndarray], Any]) -> tuple[float, float]:
        if self.weights is None:
            return NAN_CI
        self._stash = np.asarray(statistic(self.weights), dtype=np.float64).reshape(-1)
        return percentile_ci(self._stash)

    def mean_metric(self, metric: str, values: Sequence[float] | np.ndarray, unit: str | None = None) -> None:
        if self.weights is not None:
            self._stash = weighted_mean_boot(self.weights, values)
        super().mean_metric(metric, values, unit)

    def add(self, metric: str, *args: Any, **kwargs: Any) -> None:
        super().add(metric, *args, **kwargs)
        self.summary[-1]["replicates"] = self._stash
        self._stash = None


def _reduce_weighted(scored: Scored, weights: np.ndarray) -> list[dict[str, Any]]:
    """Summary rows of every condition with the replicates under ``weights`` ``(B, n_segments)`` (segments in
    the order of the task results, which is sorted), the same resamples for every condition."""
    res = scored.result
    plan, setup = res.plan, res.setup
    fams = setup.active()
    info = {name: mi for name, (_, mi) in metric_index({f.name: f for f in setup.family_objects}).items()}
    records: dict[str, dict[str, dict[str, Any]]] = {c: {} for c in plan.conditions}
    acc: dict[str, dict[str, Any]] = {}
    for i, task in enumerate(map(copy_task_result, scored.results)):
        nat = task["records"].get(plan.reference, {})
        for cond, rec in task["records"].items():
            if "error" in rec:
                continue
            records[cond][task["name"]] = rec
            if nat and "error" not in nat:
                for fam in fams:
                    fam.fold(i, cond, rec, nat, acc.setdefault(cond, {}))
    order = [t["name"] for t in scored.results]
    rows: list[dict[str, Any]] = []
    ref = records[plan.reference]
    for cond in plan.conditions:
        names = sorted(s for s in records[cond] if s in ref)
        if not names:
            continue
        ctx = _Recording(cond, plan.reference, names, records[cond], ref, setup, res.convention,
                         weights[:, [order.index(s) for s in names]], acc.get(cond, {}), info=info, seed=res.seed)
        for fam in fams:
            fam.reduce(ctx)
        rows += ctx.summary
    return rows


def _rereduce(task: tuple[Any, ...]) -> np.ndarray:
    """Values of replicates ``draws`` (rows of segment indices) by reducing resampled records again."""
    plan, setup, results, draws, conditions, metrics = task
    return np.concatenate([values_table([reduce_results(plan, setup, _resampled(results, d)).summary], conditions,
                                        metrics) for d in draws])


def bootstrap_table(scored: Scored, conditions: Sequence[str], metrics: Sequence[str], n_boot: int, seed: int,
                    progress: bool = True, jobs: int = 1) -> np.ndarray:
    """``(1 + n_boot, conditions, metrics)``: row 0 the values on every segment, then ``n_boot`` paired
    bootstrap replicates over segments (seeded). Metrics whose family gives its resampled values under
    weights (means over sequences, pooled histograms, FD_g/FD_k, L1div) are computed so; the others (CCA,
    FGD) by reducing each replicate's resampled records again."""
    n = len(scored.results)
    if n < 2 and n_boot:
        raise InputError(f"a bootstrap over segments needs at least 2 segments, got {n}", field="--split")
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, n, size=(n_boot, n))
    weights = np.zeros((n_boot, n))
    np.add.at(weights, (np.arange(n_boot)[:, None], draws), 1.0)
    rows = _reduce_weighted(scored, weights)
    table = values_table([rows], conditions, metrics)
    table = np.concatenate([table, np.full((n_boot,) + table.shape[1:], np.nan)])
    ci, mi = {c: i for i, c in enumerate(conditions)}, {m: i for i, m in enumerate(metrics)}
    missing = set()
    for r in rows:
        if r["condition"] in ci and r["metric"] in mi:
            if r.get("replicates") is not None and len(r["replicates"]) == n_boot:
                table[1:, ci[r["condition"]], mi[r["metric"]]] = r["replicates"]
            elif np.isfinite(r["value"]):
                missing.add(r["metric"])
    if missing and n_boot:
        setup = dataclasses.replace(scored.result.setup, metrics=sorted(missing))
        chunks = np.array_split(np.arange(n_boot), max(1, min(n_boot, 2 * jobs)))
        tasks = [(scored.result.plan, setup, scored.results, draws[c], list(conditions), list(metrics))
                 for c in chunks if len(c)]
        parts = run(_rereduce, tasks, jobs=jobs, progress=progress, weights=[len(c) for c in chunks if len(c)],
                    desc="bootstrap " + ", ".join(sorted(missing)))
        again = np.concatenate(parts)
        table[1:] = np.where(np.isnan(table[1:]), again, table[1:])
    return table


def values_table(summaries: Sequence[list[dict[str, Any]]], conditions: Sequence[str],
                 metrics: Sequence[str]) -> np.ndarray:
    """``(len(summaries), len(conditions), len(metrics))`` values (NaN where a row is missing)."""
    ci = {c: i for i, c in enumerate(conditions)}
    mi = {m: i for i, m in enumerate(metrics)}
    table = np.full((len(summaries), len(conditions), len(metrics)), np.nan)
    for b, rows in enumerate(summaries):
        for r in rows:
            if r["condition"] in ci and r["metric"] in mi:
                table[b, ci[r["condition"]], mi[r["metric"]]] = r["value"]
    return table
