"""Large studies: Barnard's test has a large-n path, the repeated-measures ANOVA is closed form, and a
big results file is read and analysed fast."""
import time

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from statsmodels.stats.anova import AnovaRM

from evalsuite.analysis.likert import rm_anova
from evalsuite.analysis.pairwise import (
    BARNARD_ASYMPTOTIC,
    BARNARD_EXACT,
    BARNARD_EXACT_MAX_CELLS,
    barnard_p,
    barnard_test,
    mismatch_tables,
)


def test_barnard_small_tables_are_exact():
    t = [[30, 22], [10, 18]]
    p, test = barnard_test(t)
    assert test == BARNARD_EXACT
    assert p == pytest.approx(stats.barnard_exact(t, pooled=True).pvalue, rel=1e-12)


def test_barnard_large_counts_use_the_pooled_z_test_without_an_n_by_n_table():
    # 1,000,000-row studies have tens of thousands of judgements per condition: the exact test would
    # build a 30000 x 30000 table per nuisance value (MemoryError in the review).
    t = [[20_150, 18_400], [13_850, 15_600]]
    t0 = time.perf_counter()
    p, test = barnard_test(t)
    assert time.perf_counter() - t0 < 0.5
    assert test == BARNARD_ASYMPTOTIC
    chi2 = stats.chi2_contingency(np.array(t), correction=False)[1]     # the same pooled statistic, squared
    assert p == pytest.approx(chi2, rel=1e-9)
    assert barnard_p(t) == p


def test_switch_point_is_stated_and_the_two_tests_agree_there():
    n = int(BARNARD_EXACT_MAX_CELLS ** 0.5) - 1            # the largest square table still exact
    t = [[int(0.56 * n), int(0.5 * n)], [n - int(0.56 * n), n - int(0.5 * n)]]
    p_exact, test = barnard_test(t)
    assert test == BARNARD_EXACT
    t_big = [[t[0][0] + 1, t[0][1] + 1], [t[1][0] + 1, t[1][1] + 1]]
    p_big, test_big = barnard_test(t_big)
    assert test_big == BARNARD_ASYMPTOTIC
    assert abs(p_exact - p_big) < 1e-2


def test_mismatch_table_names_the_test_per_comparison():
    rows = []
    for c, (m, x) in {"A": (20_000, 14_000), "B": (18_000, 16_000), "C": (30, 12)}.items():
        rows.append({"question": "app", "condition_a": c, "condition_b": c + ":mismatched", "n_a": m, "n_b": x,
                     "n_tie": 0})
    _, between = mismatch_tables(pd.DataFrame(rows))
    tests = dict(zip(zip(between["condition_1"], between["condition_2"]), between["test"]))
    assert tests[("A", "B")] == BARNARD_ASYMPTOTIC
    assert tests[("A", "C")] == BARNARD_ASYMPTOTIC              # 34,000 x 42 tables: above the limit too
    assert between.loc[between["test"] == BARNARD_ASYMPTOTIC, "note"].str.contains("pooled z").all()


def test_rm_anova_equals_statsmodels_anovarm():
    rng = np.random.default_rng(0)
    Y = rng.normal(size=(30, 4)) + np.array([0, 0.3, 0.5, 0.1]) + rng.normal(size=(30, 1))
    long = pd.DataFrame([{"s": i, "c": j, "y": Y[i, j]} for i in range(30) for j in range(4)])
    t = AnovaRM(long, depvar="y", subject="s", within=["c"]).fit().anova_table
    F, d1, d2, p = rm_anova(Y)
    assert (F, d1, d2, p) == pytest.approx((t["F Value"].iloc[0], t["Num DF"].iloc[0], t["Den DF"].iloc[0],
                                            t["Pr > F"].iloc[0]), rel=1e-10)
    F0, _, _, p0 = rm_anova(np.ones((5, 3)) + np.arange(5)[:, None])        # no residual variance
    assert np.isnan(F0) and np.isnan(p0)
