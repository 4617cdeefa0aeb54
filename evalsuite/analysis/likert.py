"""Likert questionnaires ("Moving fast and slow"): reliability, means, ANOVA, t-tests.

Data layout: one likert row per (session, page, condition, statement); ``question`` is
the statement and ``scale`` the construct it measures. A *response unit* is one session
rating one condition on one page; a unit's scale score is the mean of its statements.

- Cronbach's alpha per scale on the unit x statement matrix (units missing a statement
  are dropped, listwise): ``alpha = k / (k - 1) * (1 - sum_i var_i / var_total)`` with
  sample variances (ddof = 1) and ``var_total`` the variance of the unit sums.
- Means with 95 % Student-t CIs of participant-level scores (each participant's unit
  scores averaged per condition, so a participant counts once per condition).
- One-way ANOVA (``scipy.stats.f_oneway``) across conditions on those scores, post-hoc
  Welch t-tests with Bonferroni correction; repeated-measures ANOVA (statsmodels
  ``AnovaRM``, computed in closed form by :func:`rm_anova`) on the participants who rated every condition, post-hoc paired t-tests
  (``scipy.stats.ttest_rel``) with Bonferroni correction.
"""
from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
from scipy import stats

from evalsuite.analysis.pairwise import adjust_pvalues
from evalsuite.analysis.ratings import mean_ci

UNIT = ["participant", "session", "page", "condition"]


def cronbach_alpha(items) -> float:
    """Cronbach's alpha of a (units x items) array without missing values (nan if undefined).

    ``alpha = k / (k - 1) * (1 - sum(var(item_i)) / var(sum of items))``, ddof = 1.
    Undefined for fewer than 2 items or 2 units, or when the sums have zero variance.
    """
    x = np.asarray(items, dtype=float)
    if x.ndim != 2 or x.shape[1] < 2 or x.shape[0] < 2:
        return math.nan
    k = x.shape[1]
    total_var = x.sum(axis=1).var(ddof=1)
    if total_var == 0:
        return math.nan
    return float(k / (k - 1) * (1 - x.var(axis=0, ddof=1).sum() / total_var))


def _bonferroni(p):
    return adjust_pvalues(p, "bonferroni")


def rm_anova(Y) -> tuple[float, float, float, float]:
    """One-way repeated-measures ANOVA on a complete ``(subjects, conditions)`` matrix.

    ``SS_cond = n sum_j (m_j - m)^2``, ``SS_subj = k sum_i (m_i - m)^2``,
    ``SS_err = SS_total - SS_cond - SS_subj``; ``F = (SS_cond / (k - 1)) / (SS_err / ((n - 1)(k - 1)))``.
    The same numbers as statsmodels ``AnovaRM`` with one within factor (tested), in O(n k) instead
    of a design matrix with a column per subject. Returns ``(F, df_num, df_den, p)``; F and p are
    NaN when there is no residual variance.
    """
    Y = np.asarray(Y, dtype=float)
    n, k = Y.shape
    m = Y.mean()
    ss_cond = n * ((Y.mean(axis=0) - m) ** 2).sum()
    ss_subj = k * ((Y.mean(axis=1) - m) ** 2).sum()
    ss_err = ((Y - m) ** 2).sum() - ss_cond - ss_subj
    df1, df2 = k - 1, (n - 1) * (k - 1)
    if ss_err <= 1e-12 * max(((Y - m) ** 2).sum(), 1e-300):
        return math.nan, float(df1), float(df2), math.nan
    F = (ss_cond / df1) / (ss_err / df2)
    return float(F), float(df1), float(df2), float(stats.f.sf(F, df1, df2))


def statement_matrix(lk: pd.DataFrame) -> pd.DataFrame:
    """Response units x statements of one scale's likert rows: index :data:`UNIT`, one column per statement
    (``question``), the unit's answer (a statement answered twice on a page: the mean)."""
    return lk.pivot_table(index=UNIT, columns="question", values="value", aggfunc="mean")


def participant_scores(wide: pd.DataFrame) -> pd.DataFrame:
    """Participant-level scale scores from a :func:`statement_matrix`: a unit's score is the mean of its
    statements, a participant's score for a condition the mean of their unit scores. Columns
    ``participant, condition, score``, sorted by participant then condition. ``likert_means.csv``'s ``mean``
    is the mean of these scores over the participants."""
    unit_score = wide.mean(axis=1).rename("score").reset_index()
    return unit_score.groupby(["participant", "condition"])["score"].mean().reset_index()


def likert_tables(lk: pd.DataFrame, alpha: float = 0.05) -> dict:
    """All Likert tables: ``reliability``, ``means``, ``anova``, ``posthoc`` (DataFrames)."""
    rel, means, anova, post = [], [], [], []
    for scale, g in lk.groupby("scale", sort=True):
        wide = statement_matrix(g)
        complete = wide.dropna()
        a = cronbach_alpha(complete.to_numpy())
        note = ""
        if wide.shape[1] < 2:
            note = "a single statement: alpha undefined"
        elif len(complete) < 2:
            note = "fewer than 2 complete response units: alpha undefined"
        elif not np.isfinite(a):
            note = "no variance in the scale sums: alpha undefined"
        rel.append({"scale": scale, "n_items": wide.shape[1], "n_units": len(complete),
                    "alpha": a, "note": note})

        scores = participant_scores(wide)
        conds = sorted(scores["condition"].unique())
        for c in conds:
            v = scores.loc[scores["condition"] == c, "score"].to_numpy()
            lo, hi = mean_ci(v, alpha)
            means.append({"scale": scale, "condition": c, "n_participants": v.size, "mean": float(v.mean()),
                          "ci_low": lo, "ci_high": hi, "sd": float(v.std(ddof=1)) if v.size > 1 else math.nan,
                          "note": "" if np.isfinite(lo) else "a single participant: no CI"})

        groups = [scores.loc[scores["condition"] == c, "score"].to_numpy() for c in conds]
        rec = {"scale": scale, "test": "one-way ANOVA", "F": math.nan, "df_num": math.nan,
               "df_den": math.nan, "p_value": math.nan, "n": int(len(scores)), "note": ""}
        if len(conds) < 2:
            rec["note"] = "fewer than 2 conditions: no ANOVA"
        elif sum(len(x) for x in groups) - len(conds) < 1 or all(len(x) < 2 for x in groups):
            rec["note"] = "too few participants per condition: no ANOVA"
        else:
            res = stats.f_oneway(*groups)
            rec.update(F=float(res.statistic), df_num=len(conds) - 1,
                       df_den=sum(len(x) for x in groups) - len(conds), p_value=float(res.pvalue))
            if not np.isfinite(rec["F"]):
                rec.update(F=math.nan, p_value=math.nan, note="no variance within conditions: no ANOVA")
        anova.append(rec)

        full = scores.pivot(index="participant", columns="condition", values="score").dropna()
        rm = {"scale": scale, "test": "repeated-measures ANOVA", "F": math.nan, "df_num": math.nan,
              "df_den": math.nan, "p_value": math.nan, "n": int(len(full)), "note": ""}
        if len(conds) < 2 or len(full) < 2:
            rm["note"] = "needs >= 2 conditions and >= 2 participants who rated all of them"
        else:
            F, df1, df2, p = rm_anova(full.to_numpy(float))
            rm.update(F=F, df_num=df1, df_den=df2, p_value=p)
            if not np.isfinite(rm["F"]):
                rm.update(F=math.nan, p_value=math.nan,
                          note=rm["note"] or "no residual variance: repeated-measures ANOVA undefined")
        anova.append(rm)

        ph = []
        for c1, c2 in itertools.combinations(conds, 2):
            x = scores.loc[scores["condition"] == c1, "score"].to_numpy()
            y = scores.loc[scores["condition"] == c2, "score"].to_numpy()
            rec = {"scale": scale, "condition_1": c1, "condition_2": c2, "test": "Welch t",
                   "n": int(x.size + y.size), "mean_diff": float(x.mean() - y.mean()), "t": math.nan,
                   "p_value": math.nan, "note": ""}
            if x.size >= 2 and y.size >= 2 and (x.var() > 0 or y.var() > 0):
                r = stats.ttest_ind(x, y, equal_var=False)
                rec.update(t=float(r.statistic), p_value=float(r.pvalue))
            else:
                rec["note"] = "needs >= 2 participants per condition and some variance"
            ph.append(rec)
            both = scores.pivot(index="participant", columns="condition", values="score")[[c1, c2]].dropna()
            d = both[c1] - both[c2]
            rec = {"scale": scale, "condition_1": c1, "condition_2": c2, "test": "paired t",
                   "n": int(len(both)), "mean_diff": float(d.mean()) if len(d) else math.nan,
                   "t": math.nan, "p_value": math.nan, "note": ""}
            if len(both) >= 2 and d.var() > 0:
                r = stats.ttest_rel(both[c1], both[c2])
                rec.update(t=float(r.statistic), p_value=float(r.pvalue))
            else:
                rec["note"] = ("no participant rated both" if len(both) == 0 else
                               "needs >= 2 paired participants with varying differences")
            ph.append(rec)
        ph = pd.DataFrame(ph)
        if not ph.empty:
            ph["p_bonferroni"] = np.nan
            for _, idx in ph.groupby("test").groups.items():
                ph.loc[idx, "p_bonferroni"] = _bonferroni(ph.loc[idx, "p_value"])
            post.append(ph)
    posthoc = pd.concat(post, ignore_index=True) if post else pd.DataFrame(
        columns=["scale", "condition_1", "condition_2", "test", "n", "mean_diff", "t", "p_value",
                 "note", "p_bonferroni"])
    if not posthoc.empty:
        posthoc["significant"] = posthoc["p_bonferroni"] < alpha
        posthoc = posthoc[["scale", "condition_1", "condition_2", "test", "n", "mean_diff", "t",
                           "p_value", "p_bonferroni", "significant", "note"]]
    return {"reliability": pd.DataFrame(rel), "means": pd.DataFrame(means),
            "anova": pd.DataFrame(anova), "posthoc": posthoc}
