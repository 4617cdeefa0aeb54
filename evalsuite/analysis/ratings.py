"""Parallel 0-100 ratings (MUSHRA / HEMVIP pages): GENEA's conventions.

- Per question and condition: ``n`` ratings, median with a distribution-free 95 % CI from
  order statistics (the binomial(n, 1/2) cdf; GENEA 2022), mean with a Student-t CI and SD.
  The hidden reference and anchors are conditions like any other (their ``role`` is shown).
- Pairwise tests: two-sided Wilcoxon signed-rank (``scipy.stats.wilcoxon``) for every
  unordered pair of conditions, on the pages where both were rated by the same session
  (paired by session x page). Equal ratings (zero differences) are common with sliders:
  ``zero_method="wilcox"`` (default, the classic test) drops them before ranking and
  reports how many were dropped; ``"pratt"`` ranks them then drops their ranks;
  ``"zsplit"`` splits their ranks between both signs. ``method="auto"``: exact null
  distribution for n <= 50 without ties/zeros, normal approximation otherwise.
- Holm-Bonferroni over all pairs of the study (or per question), alpha = .05; the
  significance matrix marks, for row condition vs column condition, +1 (rated
  significantly higher), -1 (significantly lower) or 0 (not significant).
- Effect size: matched-pairs rank-biserial ``r = (T+ - T-) / (T+ + T-)`` on the ranked
  non-zero differences, and the median of the paired differences.
"""
from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
from scipy import stats

from evalsuite.analysis.pairwise import add_holm

RATINGS_COLUMNS = ["question", "condition", "role", "n", "n_participants", "median", "median_ci_low",
                   "median_ci_high", "median_ci_coverage", "mean", "mean_ci_low", "mean_ci_high", "sd", "note"]
RATING_PAIRS_COLUMNS = ["question", "condition_1", "condition_2", "n_pages", "n_zero", "median_1",
                        "median_2", "median_diff", "statistic", "rank_biserial", "p_value", "p_holm",
                        "significant", "better", "note"]


def median_ci(x, alpha: float = 0.05):
    """Distribution-free CI of the median from order statistics.

    With ``B ~ Binomial(n, 1/2)`` and ``j`` the largest integer such that
    ``P(B <= j - 1) <= alpha / 2``, the interval is ``[x_(j), x_(n-j+1)]`` (1-based order
    statistics) with coverage ``1 - 2 P(B <= j - 1) >= 1 - alpha``.
    Returns ``(low, high, coverage)``; ``(nan, nan, nan)`` when n is too small for the
    requested level (n <= 5 at 95 %).
    """
    x = np.sort(np.asarray(x, dtype=float))
    n = x.size
    if n == 0:
        return (math.nan, math.nan, math.nan)
    j = np.arange(1, n // 2 + 2)
    tail = stats.binom.cdf(j - 1, n, 0.5)
    ok = j[tail <= alpha / 2]
    if ok.size == 0:
        return (math.nan, math.nan, math.nan)
    jj = int(ok.max())
    return (float(x[jj - 1]), float(x[n - jj]), float(1 - 2 * stats.binom.cdf(jj - 1, n, 0.5)))


def mean_ci(x, alpha: float = 0.05):
    """Student-t CI of the mean: ``mean +- t_{1-alpha/2, n-1} s / sqrt(n)``; nan for n < 2."""
    x = np.asarray(x, dtype=float)
    if x.size < 2:
        return (math.nan, math.nan)
    m, se = x.mean(), x.std(ddof=1) / math.sqrt(x.size)
    h = stats.t.ppf(1 - alpha / 2, x.size - 1) * se
    return (float(m - h), float(m + h))


def rating_summary(mu: pd.DataFrame, alpha: float = 0.05, expected=None) -> pd.DataFrame:
    """The ``ratings.csv`` table (module docstring). ``mu``: mushra rows with ``value``.

    ``expected``: optional ``(question, condition)`` pairs of the design; those without
    ratings (e.g. all their raters excluded) get a row with ``n = 0`` and a note.
    """
    rows = []
    have = set(zip(mu["question"], mu["condition"]))
    for q, c in sorted(set(expected or ()) - have):
        rows.append({"question": q, "condition": c, "role": "", "n": 0, "n_participants": 0,
                     "median": math.nan, "median_ci_low": math.nan, "median_ci_high": math.nan,
                     "median_ci_coverage": math.nan, "mean": math.nan, "mean_ci_low": math.nan,
                     "mean_ci_high": math.nan, "sd": math.nan, "note": "no ratings (after exclusions)"})
    for (q, c), g in mu.groupby(["question", "condition"], sort=True):
        v = g["value"].to_numpy(float)
        lo, hi, cov = median_ci(v, alpha)
        mlo, mhi = mean_ci(v, alpha)
        notes = []
        if not np.isfinite(lo):
            notes.append(f"n = {v.size}: too few ratings for a {100 * (1 - alpha):g}% CI of the median")
        if not np.isfinite(mlo):
            notes.append("a single rating: no CI of the mean")
        roles = sorted(set(g["role"]) - {""})
        rows.append({"question": q, "condition": c, "role": ",".join(roles), "n": v.size,
                     "n_participants": g["participant"].nunique(), "median": float(np.median(v)),
                     "median_ci_low": lo, "median_ci_high": hi, "median_ci_coverage": cov,
                     "mean": float(v.mean()), "mean_ci_low": mlo, "mean_ci_high": mhi,
                     "sd": float(v.std(ddof=1)) if v.size > 1 else math.nan, "note": "; ".join(notes)})
    out = pd.DataFrame(rows, columns=RATINGS_COLUMNS)
    return out.sort_values(["question", "condition"], kind="stable").reset_index(drop=True)


def rank_biserial(d) -> float:
    """Matched-pairs rank-biserial correlation of differences ``d`` (zeros dropped)."""
    d = np.asarray(d, dtype=float)
    d = d[d != 0]
    if d.size == 0:
        return math.nan
    r = stats.rankdata(np.abs(d))
    tp, tm = r[d > 0].sum(), r[d < 0].sum()
    return float((tp - tm) / (tp + tm))


def wilcoxon_pairs(mu: pd.DataFrame, *, zero_method: str = "wilcox", holm_scope: str = "study",
                   alpha: float = 0.05) -> pd.DataFrame:
    """Two-sided Wilcoxon signed-rank tests for all condition pairs (module docstring)."""
    if zero_method not in ("wilcox", "pratt", "zsplit"):
        raise ValueError("zero_method must be 'wilcox', 'pratt' or 'zsplit'")
    rows = []
    for q, g in mu.groupby("question", sort=True):
        # One value per (session, page, condition); a repeated condition on a page is averaged.
        wide = g.pivot_table(index=["session", "page"], columns="condition", values="value", aggfunc="mean")
        for c1, c2 in itertools.combinations(sorted(wide.columns), 2):
            both = wide[[c1, c2]].dropna()
            x, y = both[c1].to_numpy(float), both[c2].to_numpy(float)
            d = x - y
            n, n_zero = d.size, int((d == 0).sum())
            rec = {"question": q, "condition_1": c1, "condition_2": c2, "n_pages": n, "n_zero": n_zero,
                   "median_1": float(np.median(x)) if n else math.nan,
                   "median_2": float(np.median(y)) if n else math.nan,
                   "median_diff": float(np.median(d)) if n else math.nan,
                   "statistic": math.nan, "rank_biserial": rank_biserial(d), "p_value": math.nan, "note": ""}
            if n == 0:
                rec["note"] = "the two conditions never appear on the same page: no paired test"
            elif n_zero == n:
                rec["note"] = f"all {n} paired ratings are equal: no test"
            else:
                res = stats.wilcoxon(x, y, zero_method=zero_method, alternative="two-sided")
                rec["statistic"], rec["p_value"] = float(res.statistic), float(res.pvalue)
                if n_zero and zero_method == "wilcox":
                    rec["note"] = f"{n_zero} zero difference(s) dropped (zero_method=wilcox)"
            rows.append(rec)
    table = pd.DataFrame(rows, columns=[c for c in RATING_PAIRS_COLUMNS
                                        if c not in ("p_holm", "significant", "better")])
    if table.empty:
        return pd.DataFrame(columns=RATING_PAIRS_COLUMNS)
    add_holm(table, holm_scope, alpha)
    direction = np.sign(table["rank_biserial"].fillna(0.0))
    table["better"] = np.where(~table["significant"], "",
                               np.where(direction > 0, table["condition_1"], table["condition_2"]))
    return table[RATING_PAIRS_COLUMNS]


def significance_matrix(pairs: pd.DataFrame, question: str, conditions=None) -> pd.DataFrame:
    """Condition x condition matrix for one question: +1 row rated significantly higher than
    column, -1 significantly lower, 0 not significant, NaN no test / diagonal."""
    sub = pairs[pairs["question"] == question]
    conds = list(conditions) if conditions is not None else sorted(
        set(sub["condition_1"]) | set(sub["condition_2"]))
    m = pd.DataFrame(np.nan, index=conds, columns=conds)
    for r in sub.itertuples(index=False):
        if r.condition_1 not in m.index or r.condition_2 not in m.index or not np.isfinite(r.p_value):
            continue
        s = 0.0
        if r.significant:
            s = 1.0 if r.better == r.condition_1 else -1.0
        m.loc[r.condition_1, r.condition_2] = s
        m.loc[r.condition_2, r.condition_1] = -s if s else 0.0
    return m
