"""Does a metric order a graded family correctly? Kendall's tau, its bootstrap interval, and a verdict.

A metric's *badness* of a condition follows its declared direction (``MetricInfo.better``): the value for
"lower", minus the value for "higher", ``|value - natural's value|`` for "closer to natural" (natural's
value in the same replicate). For a family of ``k`` levels ordered from the oracle (level 0, best) to the
strongest degradation (level ``k - 1``):

* ``tau``: Kendall's tau-b between the levels and the metric's badness (1: the metric orders the family
  exactly as the truth; -1: exactly reversed; ties in the metric count as in tau-b); ``ci_low``/``ci_high``:
  the 2.5th/97.5th percentiles of tau over the paired bootstrap replicates over segments;
* ``worsening``: badness of the strongest level minus the oracle's (in the metric's unit; positive: the
  metric sees the degradation), with its bootstrap interval;
* ``verdict``: ``blind`` when the worsening's interval contains 0 (the metric cannot tell the strongest
  degradation from the oracle beyond its bootstrap noise); ``inverted`` when it lies below 0; otherwise
  ``correct`` when tau is 1 and its interval lies above 0, else ``partial`` (sees the degradation but
  does not order every level); ``n/a`` when the metric has no value for some level.

A metric blind in the ``offset`` family is *blind to speech*: it cannot tell motion shifted 1.2 s against
its speech from motion in time with it.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["FamilyResult", "badness", "kendall_tau_b", "analyse", "VERDICTS"]

VERDICTS = ("correct", "partial", "blind", "inverted", "n/a")


@dataclass(frozen=True)
class FamilyResult:
    metric: str
    family: str
    tau: float
    ci_low: float
    ci_high: float
    n_levels: int
    verdict: str
    better: str
    worsening: float
    worsening_ci_low: float
    worsening_ci_high: float

    def row(self) -> dict[str, object]:
        return dict(self.__dict__)


def badness(values: np.ndarray, natural: np.ndarray, better: str) -> np.ndarray:
    """Badness of ``values`` (any shape) under the direction ``better``; ``natural`` broadcasts against it."""
    if better == "lower":
        return values
    if better == "higher":
        return -values
    if better == "closer to natural":
        return np.abs(values - natural)
    raise ValueError(f"unknown direction {better!r}")


def kendall_tau_b(y: np.ndarray) -> np.ndarray:
    """Kendall's tau-b between the positions ``0..k-1`` (no ties) and each row of ``y`` (``(..., k)``), NaN
    where a row has a NaN or is constant."""
    y = np.asarray(y, dtype=np.float64)
    k = y.shape[-1]
    i, j = np.triu_indices(k, 1)
    s = np.sign(y[..., j] - y[..., i])          # positions j > i, so the level order contributes +1
    n0 = len(i)
    untied = np.count_nonzero(s, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        tau = s.sum(axis=-1) / np.sqrt(n0 * untied)
    return np.where(np.isnan(y).any(axis=-1) | (untied == 0), np.nan, tau)


def _ci(samples: np.ndarray) -> tuple[float, float]:
    s = samples[np.isfinite(samples)]
    if s.size == 0:
        return float("nan"), float("nan")
    lo, hi = np.percentile(s, [2.5, 97.5])
    return float(lo), float(hi)


def _verdict(tau: float, tau_ci: tuple[float, float], worse: float, worse_ci: tuple[float, float]) -> str:
    if not np.isfinite(tau) or not np.isfinite(worse) or not np.all(np.isfinite(worse_ci)):
        return "n/a"
    if worse_ci[0] <= 0.0 <= worse_ci[1]:
        return "blind"
    if worse_ci[1] < 0.0:
        return "inverted"
    return "correct" if tau >= 1.0 - 1e-12 and tau_ci[0] > 0.0 else "partial"


def analyse(table: np.ndarray, conditions: Sequence[str], metrics: Sequence[str], better: dict[str, str],
            families: dict[str, list[str]]) -> list[FamilyResult]:
    """Every (metric, family) pair: ``table`` is ``(1 + B, conditions, metrics)``, row 0 the full data, rows
    1.. the bootstrap replicates; the natural condition gives the target of "closer to natural" metrics."""
    idx = {c: i for i, c in enumerate(conditions)}
    nat = table[:, idx["natural"], :] if "natural" in idx else np.full(table[:, 0, :].shape, np.nan)
    out = []
    for m, metric in enumerate(metrics):
        for fam, members in families.items():
            cols = [idx[c] for c in members if c in idx]
            if len(cols) != len(members):
                continue
            bad = badness(table[:, cols, m], nat[:, m, None], better[metric])
            taus = kendall_tau_b(bad)
            worse = bad[:, -1] - bad[:, 0]
            tau_ci, worse_ci = _ci(taus[1:]), _ci(worse[1:])
            out.append(FamilyResult(metric, fam, float(taus[0]), *tau_ci, len(members),
                                    _verdict(float(taus[0]), tau_ci, float(worse[0]), worse_ci), better[metric],
                                    float(worse[0]), *worse_ci))
    return out
