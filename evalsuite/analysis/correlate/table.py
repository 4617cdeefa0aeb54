"""The ``correlations.csv`` table: every metric against every human measure across conditions.

One row per metric and human measure (columns :data:`COLUMNS`): n, rho and tau-b with their p-values
(:mod:`~evalsuite.analysis.correlate.statistics`), condition, participant and two-level (conditions and
participants together, ``*_both``) bootstrap CIs (:mod:`~evalsuite.analysis.correlate.bootstrap`), the
metric's direction and whether the sign agrees with it;
an undefined correlation gives a row with empty numbers and a ``note``.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from evalsuite.analysis.correlate.bootstrap import condition_bootstrap, two_level_bootstrap
from evalsuite.analysis.correlate.statistics import percentile, rank_p_values, replicates
from evalsuite.errors import InputError

__all__ = ["COLUMNS", "MIN_CONDITIONS", "correlate", "metric_direction", "add_distance_to_natural",
           "check_conditions", "human_label"]

COLUMNS = ["metric", "human_measure", "n", "spearman_rho", "spearman_p", "spearman_ci_low", "spearman_ci_high",
           "kendall_tau_b", "kendall_p", "kendall_ci_low", "kendall_ci_high", "question", "measure", "better",
           "agrees", "spearman_ci_low_participants", "spearman_ci_high_participants",
           "kendall_ci_low_participants", "kendall_ci_high_participants", "conditions", "note",
           "spearman_p_method", "kendall_p_method", "spearman_ci_low_both", "spearman_ci_high_both",
           "kendall_ci_low_both", "kendall_ci_high_both"]
MIN_CONDITIONS = 3


def _registry_directions() -> dict[str, str]:
    from evalsuite.metrics.families import metric_index

    return {name: info.better for name, (_, info) in metric_index().items()}


def metric_direction(metric: str, registry: dict[str, str] | None = None, fallback: str = "") -> str:
    """``lower``/``higher``/``closer to natural`` for a metric name (``hellinger_speed[wrists]`` is
    ``hellinger_speed`` on a joint group): the registry's, else ``fallback`` (e.g. the summary's own
    ``better`` column), else ``""`` (unknown)."""
    reg = _registry_directions() if registry is None else registry
    base = metric.split("[", 1)[0].strip()
    return reg.get(metric, reg.get(base, fallback if fallback in ("lower", "higher", "closer to natural") else ""))


def _agrees(rho: float, better: str, human_higher: bool):
    if not math.isfinite(rho) or better not in ("lower", "higher"):
        return None
    expected = (1 if better == "higher" else -1) * (1 if human_higher else -1)
    return bool(rho * expected > 0)


def _snap(row: dict, est: str, lo: str, hi: str, tol: float = 1e-12) -> None:
    """Bounds that differ from scipy's estimate by floating-point rounding only (e.g. 1.0 vs
    0.9999999999999999 for a perfect correlation) are moved onto it."""
    for key, pick in ((lo, min), (hi, max)):
        if math.isfinite(row[key]) and abs(row[key] - row[est]) < tol:
            row[key] = pick(row[key], row[est])


def _label(path) -> str:
    return f" ({path})" if path else ""


def check_conditions(score_conds, human_conds, scores_path=None, human_path=None) -> None:
    """InputError naming the conditions present in one input and not the other."""
    only_s = sorted(set(score_conds) - set(human_conds))
    only_h = sorted(set(human_conds) - set(score_conds))
    if only_s or only_h:
        parts = []
        if only_s:
            parts.append(f"in the scores{_label(scores_path)} but not the human judgements: {', '.join(only_s)}")
        if only_h:
            parts.append(f"in the human judgements{_label(human_path)} but not the scores: {', '.join(only_h)}")
        raise InputError("conditions differ between the inputs: " + "; ".join(parts)
                         + " (rename with --rename SCORE=HUMAN, leave out with --exclude NAME, or correlate "
                           "the shared ones with --shared-only)")


def correlate(scores: pd.DataFrame, human: pd.DataFrame, *, n_boot: int = 1000, seed: int = 42,
              alpha: float = 0.05, participants=None, shared_only: bool = False, human_higher: bool = True,
              notes: list | None = None, natural: str | None = None, row_notes: list | None = None
              ) -> pd.DataFrame:
    """The ``correlations.csv`` table: one row per metric and human measure (the package docstring).

    ``scores``: columns ``condition, metric, value`` (optional ``better``); ``human``: columns
    ``condition, value`` and optional ``question``, ``measure`` (as read by
    :func:`~evalsuite.analysis.correlate.io.read_human`). Conditions must be the same in both (an
    :class:`InputError` names those that are not) unless ``shared_only``; at least 3 must be shared.
    ``participants``: optional resampler for participant-bootstrap CIs. Notes about the inputs (left-out
    conditions) are appended to ``notes`` when given; the rows' notes to ``row_notes`` as ``(kind, metric,
    human_measure, text)``. ``natural``: see :func:`add_distance_to_natural`.
    """
    scores, human = _normalise(scores, "scores"), _normalise(human, "human")
    if natural:
        scores = add_distance_to_natural(scores, natural)
    s_path, h_path = scores.attrs.get("path"), human.attrs.get("path")
    s_conds, h_conds = set(scores["condition"]), set(human["condition"])
    shared = sorted(s_conds & h_conds)
    if not shared_only:
        check_conditions(s_conds, h_conds, s_path, h_path)
    elif notes is not None and s_conds != h_conds:
        for what, conds in (("scores", s_conds - h_conds), ("human judgements", h_conds - s_conds)):
            if conds:
                notes.append(f"only in the {what}, left out: {', '.join(sorted(conds))}")
    if len(shared) < MIN_CONDITIONS:
        raise InputError(f"{len(shared)} condition(s) shared by the scores{_label(s_path)} and the human "
                         f"judgements{_label(h_path)} ({', '.join(shared) or 'none'}): a rank correlation needs "
                         f"at least {MIN_CONDITIONS}")
    registry = _registry_directions()
    rows = []
    hum_groups = list(human.groupby(["question", "measure"], sort=False))
    for metric, sg in scores.groupby("metric", sort=False):
        svals = dict(zip(sg["condition"], sg["value"]))
        fallback = str(sg["better"].iloc[0]) if "better" in sg.columns else ""
        better = metric_direction(str(metric), registry, fallback)
        for (question, measure), hg in hum_groups:
            hvals = dict(zip(hg["condition"], hg["value"]))
            rows.append(_row(str(metric), str(question), str(measure), svals, hvals, shared, better,
                             n_boot=n_boot, seed=seed, alpha=alpha, participants=participants,
                             human_higher=human_higher, source=human.attrs.get("source", ""),
                             row_notes=row_notes))
    return pd.DataFrame(rows, columns=COLUMNS)


def add_distance_to_natural(scores: pd.DataFrame, natural: str) -> pd.DataFrame:
    """``scores`` plus, for every "closer to natural" metric ``m``, a metric ``|m - natural|`` (the
    absolute difference from the natural condition's value; lower is better), so such metrics get an
    expected sign too. ``natural``: the natural condition's name in ``scores``."""
    scores = _normalise(scores, "scores")
    if natural not in set(scores["condition"]):
        raise InputError(f"--natural {natural!r}: no such condition in the scores; they have "
                         f"{', '.join(sorted(set(scores['condition'])))}", path=scores.attrs.get("path"))
    registry = _registry_directions()
    extra = []
    for metric, sg in scores.groupby("metric", sort=False):
        fallback = str(sg["better"].iloc[0]) if "better" in sg.columns else ""
        nat = sg.loc[sg["condition"] == natural, "value"]
        if metric_direction(str(metric), registry, fallback) != "closer to natural" or nat.empty:
            continue
        extra.append(sg.assign(metric=f"|{metric} - {natural}|", value=(sg["value"] - float(nat.iloc[0])).abs(),
                               better="lower"))
    out = pd.concat([scores, *extra], ignore_index=True)
    out.attrs.update(scores.attrs)
    return out


def _normalise(df: pd.DataFrame, what: str) -> pd.DataFrame:
    need = ["condition", "metric", "value"] if what == "scores" else ["condition", "value"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError(f"missing column(s) {', '.join(missing)} in the {what} table", path=df.attrs.get("path"))
    out = df.copy()
    out.attrs.update(df.attrs)
    out["condition"] = out["condition"].astype(str)
    out["value"] = pd.to_numeric(out["value"], errors="coerce").astype(float)
    if what == "human":
        for col in ("question", "measure"):
            if col not in out.columns:
                out[col] = "" if col == "question" else "value"
            out[col] = out[col].fillna("").astype(str)
    return out


def human_label(question: str, measure: str) -> str:
    return f"{measure} ({question})" if question else measure


def _row(metric, question, measure, svals, hvals, shared, better, *, n_boot, seed, alpha, participants,
         human_higher, source, row_notes=None):
    usable = [c for c in shared if c in svals and c in hvals
              and math.isfinite(svals[c]) and math.isfinite(hvals[c])]
    x = np.array([svals[c] for c in usable], dtype=float)
    y = np.array([hvals[c] for c in usable], dtype=float)
    row = {c: math.nan for c in COLUMNS}
    row.update(metric=metric, human_measure=human_label(question, measure), question=question, measure=measure,
               n=len(usable), better=better, agrees=None, conditions=";".join(usable), note="",
               spearman_p_method="", kendall_p_method="")
    notes: list[tuple[str, str]] = []  # (kind, text)
    if len(usable) < len(shared):
        missing = ", ".join(c for c in shared if c not in usable)
        notes.append(("no value for some conditions", f"no value for {missing}"))
    if len(usable) < MIN_CONDITIONS:
        notes.append(("too few conditions", f"{len(usable)} condition(s) with values: a rank correlation needs "
                                            f"{MIN_CONDITIONS}"))
    elif np.all(x == x[0]):
        notes.append(("metric constant", "metric constant across conditions: rho and tau undefined"))
    elif np.all(y == y[0]):
        notes.append(("human measure constant", "human measure constant across conditions: rho and tau undefined"))
    else:
        rho, tau = float(stats.spearmanr(x, y).statistic), float(stats.kendalltau(x, y, variant="b").statistic)
        p_rho, rho_method, p_tau, tau_method = rank_p_values(x, y)
        row.update(spearman_rho=rho, spearman_p=p_rho, kendall_tau_b=tau, kendall_p=p_tau,
                   spearman_p_method=rho_method, kendall_p_method=tau_method,
                   agrees=_agrees(rho, better, human_higher))
        if n_boot > 0:
            lo, hi, tlo, thi, bad = condition_bootstrap(x, y, n_boot, seed, alpha)
            row.update(spearman_ci_low=lo, spearman_ci_high=hi, kendall_ci_low=tlo, kendall_ci_high=thi)
            _snap(row, "spearman_rho", "spearman_ci_low", "spearman_ci_high")
            _snap(row, "kendall_tau_b", "kendall_ci_low", "kendall_ci_high")
            if bad:
                notes.append(("constant condition resamples",
                              f"{bad} of {n_boot} condition resamples constant (no correlation), left out"))
        if participants is not None and n_boot > 0:
            H = participants.replicates(source, question, measure, usable, n_boot, seed)
            if H is None:
                notes.append(("no participant bootstrap", f"no participant bootstrap for {measure!r}"))
            else:
                rr, tt = replicates(np.broadcast_to(x, H.shape), H)
                (row["spearman_ci_low_participants"], row["spearman_ci_high_participants"]) = percentile(rr, alpha)
                (row["kendall_ci_low_participants"], row["kendall_ci_high_participants"]) = percentile(tt, alpha)
                _snap(row, "spearman_rho", "spearman_ci_low_participants", "spearman_ci_high_participants")
                _snap(row, "kendall_tau_b", "kendall_ci_low_participants", "kendall_ci_high_participants")
                bad = int((~np.isfinite(rr)).sum())
                if bad:
                    notes.append(("participant resamples without a correlation",
                                  f"{bad} of {n_boot} participant resamples without a correlation, left out"))
                (row["spearman_ci_low_both"], row["spearman_ci_high_both"], row["kendall_ci_low_both"],
                 row["kendall_ci_high_both"], bad) = two_level_bootstrap(x, H, seed, alpha)
                _snap(row, "spearman_rho", "spearman_ci_low_both", "spearman_ci_high_both")
                _snap(row, "kendall_tau_b", "kendall_ci_low_both", "kendall_ci_high_both")
                if bad:
                    notes.append(("two-level resamples without a correlation",
                                  f"{bad} of {n_boot} condition+participant resamples without a correlation, "
                                  "left out"))
    if better == "closer to natural" and math.isfinite(row["spearman_rho"]):
        notes.append(("no expected sign", "closer to natural is better: no expected sign"))
    row["note"] = "; ".join(text for _, text in notes)
    if row_notes is not None:
        row_notes.extend((kind, metric, row["human_measure"], text) for kind, text in notes)
    return row
