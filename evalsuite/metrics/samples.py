"""Several samples per sequence in a condition folder: ``<name>_<k>`` files.

A stochastic generator gives several motions for one input: ``evalsuite generate --samples K`` writes
``<segment>_<k>.*`` and a GENEA Leaderboard submission holds ``<video_id>_<k>.npz`` (or ``_sample_<k>``, as the
organisers' synthetic baselines). :func:`split_samples` recognises them against the natural sequence names: a
file whose stem *is* a natural name is that sequence's only sample; otherwise a stem ``<name>_<k>`` or
``<name>_sample_<k>`` with ``<name>`` a natural name and ``k`` a number is sample ``k`` of ``<name>``. Samples are
ordered by ``k`` as a number (``_2`` before ``_10``), so "the first" is the lowest ``k``.

How a metric uses them (:data:`SAMPLE_USES`; the ``samples`` column of ``summary.csv``):

* ``first``: only the first sample of each sequence is scored (``evalsuite score --samples first``, the default);
* ``each``: the metric is computed on every sample index k (the k-th sample of each sequence, against the
  natural motion) and the value is the mean over k (``--samples each``); a sequence with fewer samples
  contributes its last one to the higher k;
* ``all``: the metric itself takes every sample at once (e.g. a diversity across samples).
"""
from __future__ import annotations

import dataclasses
import pathlib
import re
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

__all__ = ["SAMPLE_USES", "split_samples", "sample_condition", "parent_condition", "expand_for_each", "label_samples"]

SAMPLE_USES = ("first", "each", "all")
_SAMPLE = re.compile(r"^(?P<name>.+?)_(?:sample_)?(?P<k>\d+)$")
_MARK = "#sample"


def split_samples(files: Mapping[str, pathlib.Path], names: Iterable[str]
                  ) -> tuple[dict[str, pathlib.Path], dict[str, list[pathlib.Path]], dict[str, pathlib.Path]]:
    """``(first, samples, other)`` of a condition's files (stem -> path) given the natural ``names``:
    ``first[name]`` the first sample, ``samples[name]`` every sample in ``k`` order (only names with more than
    one), ``other`` the files that are neither a natural name nor a sample of one."""
    natural = set(names)
    found: dict[str, list[tuple[int, str, pathlib.Path]]] = {}
    other: dict[str, pathlib.Path] = {}
    for stem, path in files.items():
        if stem in natural:
            found.setdefault(stem, []).append((-1, stem, path))
            continue
        m = _SAMPLE.match(stem)
        base = None
        if m is not None:  # the longest natural name it extends (2_scott_0_1_1_2 -> 2_scott_0_1_1)
            base = next((b for b in (m.group("name"), stem.rsplit("_", 1)[0]) if b in natural), None)
        if base is None:
            other[stem] = path
            continue
        k = int(stem.rsplit("_", 1)[1])
        found.setdefault(base, []).append((k, stem, path))
    first: dict[str, pathlib.Path] = {}
    samples: dict[str, list[pathlib.Path]] = {}
    for name, entries in found.items():
        entries.sort(key=lambda e: (e[0], e[1]))
        first[name] = entries[0][2]
        if len(entries) > 1:
            samples[name] = [e[2] for e in entries]
    return first, samples, other


def sample_condition(condition: str, k: int) -> str:
    """The internal name of sample index ``k`` (2, 3, ...) of ``condition`` in a ``--samples each`` run."""
    return f"{condition}{_MARK}{k}"


def parent_condition(name: str) -> str:
    """``condition`` of :func:`sample_condition`'s name; any other name unchanged."""
    return name.split(_MARK, 1)[0]


def expand_for_each(plan: Any) -> Any:
    """A copy of ``plan`` (:class:`~evalsuite.metrics.planning.Plan`) in which every condition with samples is
    followed by one internal condition per further sample index k = 2..K (:func:`sample_condition`): the k-th
    sample of each sequence (its last one where it has fewer; its only file where it has one)."""
    if not plan.samples:
        return plan
    files, conditions = dict(plan.files), []
    for cond in plan.conditions:
        conditions.append(cond)
        several = plan.samples.get(cond)
        if not several:
            continue
        for k in range(2, max(len(v) for v in several.values()) + 1):
            sub = sample_condition(cond, k)
            files[sub] = {s: several[s][min(k, len(several[s])) - 1] if s in several else path
                          for s, path in plan.files[cond].items()}
            conditions.append(sub)
    return dataclasses.replace(plan, conditions=conditions, files=files)


_NUMBERS = ("value", "ci_low", "ci_high", "std", "n")


def _mean(values: list[Any]) -> float:
    x = np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64)
    return float(x.mean()) if len(x) else float("nan")


def label_samples(result: Any, plan: Any, use: str, families: Iterable[Any]) -> None:
    """Give every summary row its ``samples`` (how the metric used the samples: kept where the family's row
    already says, else its ``MetricInfo.samples`` in ``families`` where the metric fixes it, else ``use``) and
    ``n_samples`` (most samples of a sequence in the condition); with ``use == 'each'``, replace each
    condition's rows by the mean over its sample indices (value and std; the confidence interval of one sample
    index does not carry over, so ``ci_low``/``ci_high`` are left empty) and fold the internal conditions of
    :func:`expand_for_each` back (per-sequence rows get a ``sample`` column). ``plan`` is the plan before
    expansion; it becomes ``result.plan``."""
    uses = {m.name: m.samples for fam in families for m in fam.metrics if m.samples}
    internal = [c for c in result.plan.conditions if parent_condition(c) != c]
    counts = {c: max((len(v) for v in plan.samples.get(c, {}).values()), default=1) for c in plan.conditions}
    by_key: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    kept: list[tuple[dict[str, Any], tuple[Any, ...]]] = []
    for row in result.summary:
        cond = parent_condition(str(row["condition"]))
        key = (cond,) + tuple(sorted((k, str(v)) for k, v in row.items() if k not in _NUMBERS + ("condition",)))
        by_key.setdefault(key, []).append(row)
        if row["condition"] == cond:
            kept.append((row, key))
    for row, key in kept:
        fixed = uses.get(str(row["metric"]))
        group = by_key[key]
        if use == "each" and fixed is None and len(group) > 1:
            row["value"] = _mean([r.get("value") for r in group])
            if "std" in row:
                row["std"] = _mean([r.get("std") for r in group])
            row["ci_low"] = row["ci_high"] = None
        row.setdefault("samples", fixed or use)
        row["n_samples"] = counts.get(str(row["condition"]), 1)
    result.summary = [row for row, _ in kept]
    if internal:
        for row in result.per_sequence:
            cond = parent_condition(str(row["condition"]))
            row["sample"] = int(str(row["condition"]).rsplit("#sample", 1)[1]) if cond != row["condition"] else 1
            row["condition"] = cond
        result.per_joint = [r for r in result.per_joint if r.get("condition") not in internal]
        result.histograms = [r for r in result.histograms if r.get("condition") not in internal]
        for name in internal:
            result.files.pop(name, None)
            result.wrist_tracks.pop(name, None)
            for data in result.figure_data.values():
                data.pop(name, None)
    result.plan = plan
