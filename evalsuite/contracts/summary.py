"""``summary.csv`` of ``evalsuite score``: one row per condition and metric (long form).

Written by :mod:`evalsuite.metrics.report`; read by other tools (and, next, by ``evalsuite correlate``). The
first six columns are stable; new columns are only ever appended (FGD rows add ``model_hash``, ``window``,
``n_windows_reference``, ``n_windows_condition``).
"""
from __future__ import annotations

__all__ = ["COLUMNS", "REQUIRED"]

COLUMNS = ("condition", "metric", "value", "unit", "ci_low", "ci_high", "std", "n", "better", "convention")
REQUIRED = ("condition", "metric", "value")
