"""Likert statistics against hand computations."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from evalsuite.analysis.likert import cronbach_alpha, likert_tables, participant_scores, statement_matrix


def alpha_from_covariances(x):
    """Cronbach's alpha from the mean item variance and mean inter-item covariance."""
    c = np.cov(x, rowvar=False)
    k = c.shape[0]
    v_bar = np.trace(c) / k
    c_bar = (c.sum() - np.trace(c)) / (k * (k - 1))
    return k * c_bar / (v_bar + (k - 1) * c_bar)


def test_cronbach_alpha_by_formula():
    x = np.array([[4, 5, 4], [2, 3, 3], [5, 5, 4], [3, 2, 2], [4, 4, 5], [1, 2, 1]], float)
    assert cronbach_alpha(x) == pytest.approx(alpha_from_covariances(x))
    assert math.isnan(cronbach_alpha(x[:, :1]))      # one item
    assert math.isnan(cronbach_alpha(np.ones((4, 3))))  # no variance


def make_likert(scores):
    """scores: {(participant, condition): [item values]} on scale S with items i0.."""
    rows = []
    for (p, c), vals in scores.items():
        for j, v in enumerate(vals):
            rows.append({"participant": p, "session": "s" + p, "page": "pg_" + c, "condition": c,
                         "question": f"i{j}", "scale": "S", "value": float(v)})
    return pd.DataFrame(rows)


def test_participant_scores_average_statements_then_units():
    """A unit's score is the mean of its statements; a participant who rated a condition on two pages counts
    once, with the mean of the two unit scores; likert_means' mean is the mean over participants."""
    rows = make_likert({("p1", "A"): [4, 2], ("p2", "A"): [5, 5], ("p1", "B"): [1, 2]})
    second_page = make_likert({("p1", "A"): [1, 1]}).assign(page="pg_A2")
    lk = pd.concat([rows, second_page], ignore_index=True)
    wide = statement_matrix(lk)
    assert list(wide.columns) == ["i0", "i1"] and len(wide) == 4
    scores = participant_scores(wide)
    assert scores.to_dict("records") == [{"participant": "p1", "condition": "A", "score": (3 + 1) / 2},
                                         {"participant": "p1", "condition": "B", "score": 1.5},
                                         {"participant": "p2", "condition": "A", "score": 5.0}]
    means = likert_tables(lk)["means"].set_index("condition")
    assert means.loc["A", "mean"] == (2 + 5) / 2 and means.loc["A", "n_participants"] == 2


def test_anova_rm_anova_and_t_tests_by_hand():
    rng = np.random.default_rng(3)
    conds = ["A", "B", "C"]
    parts = [f"p{i}" for i in range(8)]
    scores = {(p, c): list(np.clip(np.round(4 + k + rng.normal(0, 1.2, 3)), 1, 7))
              for p in parts for k, c in enumerate(conds)}
    t = likert_tables(make_likert(scores))
    y = pd.DataFrame([(p, c, np.mean(v)) for (p, c), v in scores.items()], columns=["p", "c", "y"])
    grand = y["y"].mean()
    # One-way ANOVA.
    means = y.groupby("c")["y"].mean()
    ss_b = sum(len(parts) * (means[c] - grand) ** 2 for c in conds)
    ss_w = sum(((y.loc[y.c == c, "y"] - means[c]) ** 2).sum() for c in conds)
    df_b, df_w = 2, len(y) - 3
    F = (ss_b / df_b) / (ss_w / df_w)
    ow = t["anova"].set_index("test").loc["one-way ANOVA"]
    assert pytest.approx(F) == ow.F
    assert ow.p_value == pytest.approx(stats.f.sf(F, df_b, df_w))
    # Repeated-measures ANOVA.
    subj = y.groupby("p")["y"].mean()
    ss_s = 3 * ((subj - grand) ** 2).sum()
    ss_e = ((y["y"] - grand) ** 2).sum() - ss_b - ss_s
    F_rm = (ss_b / 2) / (ss_e / (2 * 7))
    rm = t["anova"].set_index("test").loc["repeated-measures ANOVA"]
    assert pytest.approx(F_rm) == rm.F
    assert rm.p_value == pytest.approx(stats.f.sf(F_rm, 2, 14))
    # Paired t with Bonferroni over the 3 pairs.
    w = y.pivot(index="p", columns="c", values="y")
    d = w["A"] - w["C"]
    tt = d.mean() / (d.std(ddof=1) / math.sqrt(len(d)))
    p = 2 * stats.t.sf(abs(tt), len(d) - 1)
    ph = t["posthoc"].set_index(["condition_1", "condition_2", "test"]).loc[("A", "C", "paired t")]
    assert ph.t == pytest.approx(tt)
    assert ph.p_value == pytest.approx(p)
    assert ph.p_bonferroni == pytest.approx(min(1, 3 * p))
    # Means with t CIs of participant scores.
    m = t["means"].set_index("condition").loc["B"]
    v = w["B"].to_numpy()
    h = stats.t.ppf(0.975, len(v) - 1) * v.std(ddof=1) / math.sqrt(len(v))
    assert (m["mean"], m.ci_low, m.ci_high) == pytest.approx((v.mean(), v.mean() - h, v.mean() + h))
    # Alpha on the 24 response units.
    units = np.array(list(scores.values()))
    assert t["reliability"].iloc[0]["alpha"] == pytest.approx(alpha_from_covariances(units))


def test_single_participant_gives_notes_not_crashes():
    t = likert_tables(make_likert({("p0", "A"): [4, 5], ("p0", "B"): [2, 3]}))
    assert "a single participant" in t["means"]["note"].iloc[0]
    notes = " ".join(t["anova"]["note"])
    assert "too few participants" in notes
    assert ">= 2 participants" in notes
    assert t["posthoc"]["p_value"].isna().all()
    assert (t["posthoc"]["note"] != "").all()
