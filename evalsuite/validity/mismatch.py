"""The objective mismatch test: does a metric that uses the speech notice when the speech is not the motion's?

The objective twin of the human audio-mismatch test. Each condition's motion is scored twice by every
metric that reads the speech (families with ``needs_audio`` or ``needs_corpus``: beat alignment, coupling):
with its own segment's speech, and with the speech (and transcript) of another segment of the same speaker,
given by a seeded derangement ``π`` (no segment keeps its own speech). Per sequence ``s`` and condition:

    d_s = badness(value with the speech of π(s)) − badness(value with its own speech)

with the metric's direction (:func:`evalsuite.validity.analysis.badness`: the value for "lower", minus it for
"higher", ``|value − natural's value with its own speech|`` for "closer to natural"). The ``effect`` is the
mean of ``d_s`` over sequences, with a percentile bootstrap interval over sequences (the same resamples for
every condition, so differences between conditions are paired). Verdicts: ``sees speech`` (interval above
0), ``blind`` (contains 0), ``inverted`` (below 0), ``unchanged`` (every ``d_s`` is exactly 0: the metric
does not read the speech, e.g. phase statistics from label files, or the motion gives it nothing to compare,
e.g. a mean pose), ``n/a`` (fewer than 2 sequences with a value).

Motion in time with its speech (``natural``, the synthetic speaker's ``oracle``) must lose more from
deranged speech than motion already shifted against it (``offset_*``): ``separation`` is the oracle's
effect minus the strongest offset's, with its paired interval.

The derangement: per speaker, the segments in a seeded random order, each given the speech of the next one
in that order (one cycle; a speaker with a single segment cannot be deranged and is left out). Speech
shorter than the motion is followed by silence (zero energy, no onsets); longer speech is cut.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.metrics.families import metric_index
from evalsuite.metrics.families.base import bootstrap_weights, percentile_ci, weighted_mean_boot
from evalsuite.validity.analysis import badness

__all__ = ["MismatchResult", "derangement", "speech_metrics", "mismatch_test", "separation", "write_csv", "markdown",
           "COLUMNS"]

COLUMNS = ("metric", "condition", "own", "deranged", "effect", "ci_low", "ci_high", "n", "verdict")


@dataclass(frozen=True)
class MismatchResult:
    metric: str
    condition: str
    own: float           # mean over sequences with the own speech
    deranged: float      # ... with the deranged speech
    effect: float        # mean of d_s (positive: worse with the wrong speech)
    ci_low: float
    ci_high: float
    n: int
    verdict: str
    replicates: np.ndarray = dataclasses.field(repr=False, compare=False, default_factory=lambda: np.zeros(0))

    def row(self) -> dict[str, Any]:
        return {c: getattr(self, c) for c in COLUMNS}


def derangement(ids: Sequence[str], speakers: dict[str, str | None], seed: int = 0) -> dict[str, str]:
    """``{segment: the segment whose speech it gets}``: within each speaker a seeded random cycle (no fixed
    point). Segments of a speaker with no other segment are left out."""
    rng = np.random.default_rng(seed)
    groups: dict[str | None, list[str]] = {}
    for s in sorted(ids):
        groups.setdefault(speakers.get(s), []).append(s)
    out: dict[str, str] = {}
    for members in groups.values():
        if len(members) < 2:
            continue
        order = [members[i] for i in rng.permutation(len(members))]
        out.update({a: b for a, b in zip(order, order[1:] + order[:1])})
    return out


def speech_metrics(setup: Any) -> list[str]:
    """The run's metrics whose family reads the speech (``needs_audio`` or ``needs_corpus``)."""
    fams = {f.name: f for f in setup.family_objects}
    index = metric_index(fams)
    return [m for m in setup.metrics if m in index and (fams[index[m][0]].needs_audio or fams[index[m][0]].needs_corpus)]


def _deranged_records(scored: Any, metrics: list[str], seed: int, jobs: int, progress: bool) -> tuple[Any, dict]:
    from evalsuite.metrics.engine import reduce_results, score_sequence, tasks_for
    from evalsuite.metrics.options import ScoreTask
    from evalsuite.parallel import run

    plan = scored.result.plan
    setup = dataclasses.replace(scored.result.setup, metrics=metrics, figures=False)
    speakers = {s: getattr(seg, "speaker", None) for s, seg in plan.segments.items()}
    if not plan.segments:
        speakers = {s: None for s in plan.names}
    pi = derangement([s for s in plan.names if s in plan.audio or s in plan.segments], speakers, seed)
    if not pi:
        raise InputError("the mismatch test needs at least 2 segments of one speaker with speech", field="--corpus")
    tasks = [ScoreTask(t.name, t.entries, plan.audio.get(pi[t.name]), setup, plan.segments.get(pi[t.name]))
             for t in tasks_for(plan, setup) if t.name in pi]
    results = run(score_sequence, tasks, jobs=jobs, progress=progress, weights=[len(t.entries) for t in tasks],
                  desc="deranged speech", describe=ScoreTask.describe)
    return reduce_results(plan, setup, results), pi


def _per_sequence(rows: list[dict[str, Any]]) -> dict[tuple[str, str], dict[str, float]]:
    out: dict[tuple[str, str], dict[str, float]] = {}
    for r in rows:
        out.setdefault((r["condition"], r["metric"]), {})[r["sequence"]] = float(r["value"])
    return out


def mismatch_test(scored: Any, conditions: Sequence[str] | None = None, *, n_bootstrap: int = 200, seed: int = 0,
                  jobs: int = 1, progress: bool = False) -> list[MismatchResult]:
    """The test on a scoring run with speech (``scored``: :class:`evalsuite.validity.scoring.Scored`, or any
    object with ``.result``, a ScoreResult of a run with ``--corpus`` or ``--audio``): one result per speech
    metric and condition (default: every condition of the run, natural included)."""
    result = scored.result
    metrics = speech_metrics(result.setup)
    if not metrics:
        raise InputError("no metric of this run reads the speech (beats needs --audio, coupling --corpus)",
                         field="metrics")
    deranged, pi = _deranged_records(scored, metrics, seed, jobs, progress)
    own, der = _per_sequence(result.per_sequence), _per_sequence(deranged.per_sequence)
    better = {m: info.better for m, (_, info) in metric_index({f.name: f for f in result.setup.family_objects}).items()}
    conds = list(conditions) if conditions is not None else list(result.plan.conditions)
    seqs = sorted(pi)
    weights = bootstrap_weights(len(seqs), n_bootstrap, seed, 0) if n_bootstrap else None
    out = []
    for metric in metrics:
        nat = own.get((result.plan.reference, metric), {})
        target = np.array([nat.get(s, np.nan) for s in seqs])
        for cond in conds:
            a = np.array([own.get((cond, metric), {}).get(s, np.nan) for s in seqs])
            b = np.array([der.get((cond, metric), {}).get(s, np.nan) for s in seqs])
            if not (np.isfinite(a) & np.isfinite(b)).any():
                continue
            d = badness(b, target, better[metric]) - badness(a, target, better[metric])
            ok = np.isfinite(d)
            reps = weighted_mean_boot(weights, d) if weights is not None else np.zeros(0)
            ci = percentile_ci(reps) if reps.size else (float("nan"), float("nan"))
            effect = float(d[ok].mean())
            if ok.sum() < 2 or not np.all(np.isfinite(ci)):
                ci = (float("nan"), float("nan"))
                verdict = "n/a"
            elif np.all(d[ok] == 0):
                verdict = "unchanged"
            else:
                verdict = "sees speech" if ci[0] > 0 else ("inverted" if ci[1] < 0 else "blind")
            out.append(MismatchResult(metric, cond, float(np.nanmean(a)), float(np.nanmean(b)), effect, ci[0], ci[1],
                                      int(ok.sum()), verdict, reps))
    return out


def separation(results: Sequence[MismatchResult], better: str = "oracle",
               worse: str | None = None) -> dict[str, tuple[float, float, float]]:
    """Per metric: ``(effect(better) − effect(worse), ci_low, ci_high)`` from the paired replicates; ``worse``
    defaults to the offset condition with the largest offset in the results."""
    by = {(r.metric, r.condition): r for r in results}
    if worse is None:
        offsets = sorted({r.condition for r in results if r.condition.startswith("offset_")},
                         key=lambda c: float(c.split("_", 1)[1]))
        if not offsets:
            return {}
        worse = offsets[-1]
    out = {}
    for metric in dict.fromkeys(r.metric for r in results):
        a, b = by.get((metric, better)), by.get((metric, worse))
        if a is None or b is None:
            continue
        diff = a.effect - b.effect
        lo, hi = percentile_ci(a.replicates - b.replicates) if a.replicates.size else (float("nan"), float("nan"))
        out[metric] = (diff, lo, hi)
    return out


def _num(x: float) -> str:
    return "" if not np.isfinite(x) else f"{x:.6g}"


def write_csv(results: Sequence[MismatchResult], path: Any) -> None:
    """``mismatch.csv``: one row per metric and condition (:data:`COLUMNS`)."""
    import csv

    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(COLUMNS)
        for r in results:
            w.writerow([_num(v) if isinstance(v, float) else v for v in r.row().values()])


def markdown(results: Sequence[MismatchResult]) -> str:
    """Per metric: the effect of deranged speech (95 % interval) per condition, and the oracle's separation
    from the strongest offset."""
    conds = list(dict.fromkeys(r.condition for r in results))
    by = {(r.metric, r.condition): r for r in results}
    sep = separation(results)
    lines = ["| metric | " + " | ".join(conds) + " | oracle − strongest offset |",
             "|---|" + "---|" * (len(conds) + 1)]
    for m in dict.fromkeys(r.metric for r in results):
        cells = []
        for c in conds:
            r = by.get((m, c))
            cells.append("" if r is None else f"{r.effect:+.3g} [{r.ci_low:.3g}, {r.ci_high:.3g}] {r.verdict}"
                         if np.isfinite(r.ci_low) else ("" if r is None else f"{r.effect:+.3g} {r.verdict}"))
        d = sep.get(m)
        cells.append("" if d is None else f"{d[0]:+.3g} [{d[1]:.3g}, {d[2]:.3g}]")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    lines += ["", "Effect: the metric's badness with a deranged segment's speech (same speaker) minus with the "
              "motion's own speech, mean over segments, 95 % bootstrap interval; positive: the metric notices the "
              "wrong speech. Motion in time with its speech (natural, oracle) should lose more than motion "
              "already shifted against it (offset)."]
    return "\n".join(lines) + "\n"
