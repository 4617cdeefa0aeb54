"""Per-segment correlations: a metric's per-sequence values against the human judgements of the same segment.

``evalsuite score`` writes ``per_sequence.csv`` (``condition, sequence, metric, value``); a study's results.csv
rates each condition on segments. For every metric, question and segment that both have, the conditions'
metric values are correlated with the segment's human measure: the mean 0-100 or Likert rating of the
condition on that segment, or for pairwise questions its win rate ((wins + ties / 2) / judgements, matched
vs mismatched comparisons left out). The summary row of a metric and question is the mean of the per-segment
rho and tau-b with a percentile bootstrap CI over segments (seeded ``numpy.random.default_rng(seed)``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from evalsuite.analysis.correlate.statistics import percentile
from evalsuite.analysis.pairwise import is_mismatch

__all__ = ["SEGMENT_COLUMNS", "human_by_segment", "per_segment"]

SEGMENT_COLUMNS = ["metric", "question", "segment", "n", "spearman_rho", "kendall_tau_b", "spearman_ci_low",
                   "spearman_ci_high", "kendall_ci_low", "kendall_ci_high", "conditions"]


def human_by_segment(results: pd.DataFrame, mismatch_suffix: str = ":mismatched") -> pd.DataFrame:
    """``question, segment, condition, value`` from results rows (training and attention checks left out)."""
    d = results[(results["is_training"].astype(str) == "0") & (results["is_attention_check"].astype(str) == "0")]
    d = d[d["segment"].astype(str) != ""]
    rated = d[d["page_type"].isin(["mushra", "likert"])]
    out = [rated.assign(value=pd.to_numeric(rated["answer"], errors="coerce"))
           .groupby(["question", "segment", "condition"], as_index=False)["value"].mean()]
    pw = d[d["page_type"] == "pairwise"]
    pw = pw[~is_mismatch(pw["condition_a"], pw["condition_b"], mismatch_suffix)]
    if not pw.empty:
        score_a = pw["answer"].map({"a": 1.0, "b": 0.0, "tie": 0.5})
        both = pd.concat([pw.assign(condition=pw["condition_a"], value=score_a),
                          pw.assign(condition=pw["condition_b"], value=1.0 - score_a)])
        out.append(both.groupby(["question", "segment", "condition"], as_index=False)["value"].mean())
    return pd.concat(out, ignore_index=True)


def per_segment(per_sequence: pd.DataFrame, human: pd.DataFrame, *, n_boot: int = 1000, seed: int = 42,
                alpha: float = 0.05) -> pd.DataFrame:
    """Rows of :data:`SEGMENT_COLUMNS`: one per metric, question and segment with at least 3 conditions and
    neither side constant, and a ``segment="(mean)"`` row per metric and question (mean over segments, CI from
    resampling the segments)."""
    seq = per_sequence.rename(columns={"sequence": "segment"})
    seq = seq.assign(value=pd.to_numeric(seq["value"], errors="coerce"), segment=seq["segment"].astype(str))
    merged = seq.merge(human.assign(segment=human["segment"].astype(str)), on=["segment", "condition"],
                       suffixes=("_metric", "_human")).dropna(subset=["value_metric", "value_human"])
    rows = []
    for (metric, question), g in merged.groupby(["metric", "question"], sort=False):
        per = []
        for segment, s in g.groupby("segment", sort=True):
            x, y = s["value_metric"].to_numpy(float), s["value_human"].to_numpy(float)
            if len(s) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
                continue
            rho = float(stats.spearmanr(x, y).statistic)
            tau = float(stats.kendalltau(x, y, variant="b").statistic)
            per.append((rho, tau))
            rows.append(dict(metric=metric, question=question, segment=segment, n=len(s), spearman_rho=rho,
                             kendall_tau_b=tau, conditions=";".join(s["condition"])))
        if not per:
            continue
        arr = np.array(per)
        mean = dict(metric=metric, question=question, segment="(mean)", n=len(per),
                    spearman_rho=float(arr[:, 0].mean()), kendall_tau_b=float(arr[:, 1].mean()), conditions="")
        if n_boot > 0 and len(per) > 1:
            idx = np.random.default_rng(seed).integers(0, len(per), size=(n_boot, len(per)))
            boot = arr[idx].mean(axis=1)
            mean["spearman_ci_low"], mean["spearman_ci_high"] = percentile(boot[:, 0], alpha)
            mean["kendall_ci_low"], mean["kendall_ci_high"] = percentile(boot[:, 1], alpha)
        rows.append(mean)
    return pd.DataFrame(rows, columns=SEGMENT_COLUMNS)
