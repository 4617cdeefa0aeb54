"""``summary.csv`` of ``evalsuite score``: one row per condition and metric (long form).

Written by :mod:`evalsuite.metrics.report`; read by other tools (and, next, by ``evalsuite correlate``). The
first six columns are stable; new columns are only ever appended (FGD rows add ``model_hash``, ``window``,
``n_windows_reference``, ``n_windows_condition``). ``samples`` says how the metric used several samples per
sequence (``first``, ``each``: the mean over sample indices, ``all``) and ``n_samples`` the most samples of a
sequence in the condition (1 without samples); see :mod:`evalsuite.metrics.samples`.
"""
from __future__ import annotations

__all__ = ["COLUMNS", "REQUIRED"]

COLUMNS = ("condition", "metric", "value", "unit", "ci_low", "ci_high", "std", "n", "better", "convention", "samples",
           "n_samples")
REQUIRED = ("condition", "metric", "value")
