"""MUSHRA rating statistics against independent computations."""
import itertools
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from evalsuite.analysis.ratings import (
    mean_ci,
    median_ci,
    rank_biserial,
    rating_summary,
    significance_matrix,
    wilcoxon_pairs,
)


def exact_signed_rank_p(t, n):
    """Two-sided exact p of the signed-rank statistic min(T+, T-) = t: enumerate all 2^n sign patterns."""
    count = sum(1 for signs in itertools.product((0, 1), repeat=n)
                if sum(r for r, s in zip(range(1, n + 1), signs) if s) <= t)
    return min(1.0, 2 * count / 2 ** n)


def mushra(pairs, question="q"):
    """pairs: list of (session, page, condition, value)."""
    return pd.DataFrame([{"question": question, "participant": "P" + s, "session": s, "page": pg,
                          "condition": c, "value": float(v), "role": ""} for s, pg, c, v in pairs])


def designed(neg_ranks, n=10, zeros=0):
    """X - Y differences with |d| = 1..n, negative on `neg_ranks`, plus `zeros` equal pairs."""
    out = []
    for r in range(1, n + 1):
        d = -r if r in neg_ranks else r
        out += [(f"s{r}", "p1", "X", 50 + d), (f"s{r}", "p1", "Y", 50)]
    for z in range(zeros):
        out += [(f"z{z}", "p1", "X", 40), (f"z{z}", "p1", "Y", 40)]
    return mushra(out)


def test_table_value_n10_critical_T_is_8():
    # Published tables: n = 10, two-sided alpha = .05 -> reject when T <= 8.
    assert exact_signed_rank_p(8, 10) <= 0.05 < exact_signed_rank_p(9, 10)
    at8 = wilcoxon_pairs(designed({8})).iloc[0]
    at9 = wilcoxon_pairs(designed({9})).iloc[0]
    assert at8.statistic == 8
    assert at9.statistic == 9
    assert at8.p_value == pytest.approx(exact_signed_rank_p(8, 10))
    assert at8.p_value <= 0.05
    assert at9.p_value == pytest.approx(exact_signed_rank_p(9, 10))
    assert at9.p_value > 0.05
    assert at8.p_value == pytest.approx(2 * 25 / 1024)


def test_zero_differences_wilcox_drops_them_and_says_so():
    base = wilcoxon_pairs(designed({8})).iloc[0]
    with_zeros = wilcoxon_pairs(designed({8}, zeros=3)).iloc[0]
    assert with_zeros.n_pages == 13
    assert with_zeros.n_zero == 3
    assert with_zeros.p_value == pytest.approx(base.p_value)
    assert "3 zero difference(s) dropped" in with_zeros.note
    pratt = wilcoxon_pairs(designed({8}, zeros=3), zero_method="pratt").iloc[0]
    assert pratt.note == ""
    assert np.isfinite(pratt.p_value)
    assert pratt.p_value != pytest.approx(base.p_value)


def test_no_cooccurrence_and_all_equal_give_messages_not_nan_tests():
    df = mushra([("s1", "p1", "X", 10), ("s1", "p2", "Z", 20), ("s2", "p1", "X", 30), ("s2", "p1", "Y", 30),
                 ("s3", "p1", "X", 40), ("s3", "p1", "Y", 40)])
    t = wilcoxon_pairs(df).set_index(["condition_1", "condition_2"])
    assert "never appear on the same page" in t.loc[("X", "Z"), "note"]
    assert "all 2 paired ratings are equal" in t.loc[("X", "Y"), "note"]
    assert t["p_holm"].isna().all()
    assert not t["significant"].any()


def test_holm_and_direction_in_significance_matrix():
    rng = np.random.default_rng(0)
    rows = []
    for i in range(20):
        rows += [(f"s{i}", "p", "Good", 80 + rng.normal(0, 3)), (f"s{i}", "p", "Bad", 20 + rng.normal(0, 3)),
                 (f"s{i}", "p", "Mid", 50 + rng.normal(0, 40))]
    t = wilcoxon_pairs(mushra(rows))
    ps = list(t["p_value"])
    m = len(ps)
    order = np.argsort(ps)
    expect, running = np.empty(m), 0
    for rank, i in enumerate(order):
        running = max(running, min(1, (m - rank) * ps[i]))
        expect[i] = running
    assert list(t["p_holm"]) == pytest.approx(list(expect))
    mat = significance_matrix(t, "q", ["Good", "Mid", "Bad"])
    assert mat.loc["Good", "Bad"] == 1
    assert mat.loc["Bad", "Good"] == -1
    assert math.isnan(mat.loc["Good", "Good"])


def test_median_ci_order_statistics_by_hand():
    x = np.array([7, 3, 10, 1, 5, 9, 2, 8, 6, 4], float)
    # n = 10: P(B <= 1) = 11/1024 <= .025 < P(B <= 2) = 56/1024, so j = 2: [x_(2), x_(9)].
    lo, hi, cov = median_ci(x)
    assert (lo, hi) == (2, 9)
    assert cov == pytest.approx(1 - 2 * 11 / 1024)
    assert all(math.isnan(v) for v in median_ci(x[:5]))


def test_mean_ci_by_formula_and_single_value():
    x = np.array([60, 70, 75, 90], float)
    h = stats.t.ppf(0.975, 3) * x.std(ddof=1) / 2
    assert mean_ci(x) == pytest.approx((x.mean() - h, x.mean() + h))
    assert all(math.isnan(v) for v in mean_ci([50.0]))


def test_rating_summary_small_and_single_participant():
    df = mushra([("s1", "p1", "X", 40), ("s1", "p2", "X", 60), ("s1", "p1", "Y", 90)])
    t = rating_summary(df).set_index("condition")
    assert t.loc["X", "median"] == 50
    assert t.loc["X", "n_participants"] == 1
    assert "too few ratings" in t.loc["X", "note"]
    assert "a single rating" in t.loc["Y", "note"]


def test_rank_biserial():
    assert rank_biserial([1, 2, 3]) == 1.0
    # ranks of |d| = 1, 2, 3 -> T+ = 1 + 3, T- = 2.
    assert rank_biserial([1, -2, 3, 0]) == pytest.approx((4 - 2) / 6)
