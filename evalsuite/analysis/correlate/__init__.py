"""Objective metrics against human judgements across conditions: ``evalsuite correlate``.

For every metric (a ``condition, metric, value`` table, e.g. ``summary.csv`` of ``evalsuite score``)
and every human measure (a ``condition, value`` per question and measure: MUSHRA medians or means,
Likert means, Elo, pairwise win rates; see :mod:`evalsuite.analysis.correlate.io`), over the
conditions both have:

- Spearman's rho and Kendall's tau-b, exactly ``scipy.stats.spearmanr(x, y)`` and
  ``scipy.stats.kendalltau(x, y, variant="b")`` (tau-b corrects for ties), with two-sided p-values that are
  exact for small n (:func:`~evalsuite.analysis.correlate.statistics.rank_p_values`; ``spearman_p_method`` /
  ``kendall_p_method`` say which);
- percentile bootstrap CIs from ``n_boot`` resamples of the **conditions** with replacement (seeded;
  resamples in which either side is constant have no correlation and are left out, the row says how
  many);
- optionally percentile CIs from resamples of the **participants** (``participants=``, a
  :class:`~evalsuite.analysis.correlate.bootstrap.ParticipantResampler` built from the study's results):
  the human measure is recomputed on each resample, the metric values stay fixed;
- the metric's direction (``better``: from the metric registry, else the scores' own ``better``
  column) and ``agrees``: whether the sign of rho is the one a valid metric would give (human measures
  are higher-is-better: a lower-is-better metric should correlate negatively). Empty for
  "closer to natural" metrics, whose sign says nothing by itself, and for unknown metrics.

Undefined correlations (fewer than 3 conditions with a value, a constant metric or human measure) give
a row with empty numbers and a ``note``, never an exception.

Modules: :mod:`~evalsuite.analysis.correlate.io` (the inputs), :mod:`~evalsuite.analysis.correlate.statistics`
(rho, tau-b, p-values, batches of resamples), :mod:`~evalsuite.analysis.correlate.bootstrap` (condition and
participant bootstraps; the human measures come from the analysis modules' own functions),
:mod:`~evalsuite.analysis.correlate.table` (the table), :mod:`~evalsuite.analysis.correlate.output` (files,
figures, the report section) and :mod:`~evalsuite.analysis.correlate.cli` (the command).
"""
from __future__ import annotations

from evalsuite.analysis.correlate.bootstrap import ParticipantResampler, condition_bootstrap
from evalsuite.analysis.correlate.io import HUMAN_MEASURES, read_human, read_scores
from evalsuite.analysis.correlate.statistics import (
    EXACT_MAX_N,
    kendall_b_rows,
    rank_correlations,
    rank_p_values,
    spearman_rows,
)
from evalsuite.analysis.correlate.table import (
    COLUMNS,
    add_distance_to_natural,
    check_conditions,
    correlate,
    metric_direction,
)

__all__ = ["COLUMNS", "EXACT_MAX_N", "HUMAN_MEASURES", "ParticipantResampler", "add_distance_to_natural",
           "check_conditions", "condition_bootstrap", "correlate", "kendall_b_rows", "metric_direction",
           "rank_correlations", "rank_p_values", "read_human", "read_scores", "spearman_rows"]
