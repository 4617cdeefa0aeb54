"""Pairwise preference statistics against independent computations written out here."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from evalsuite.analysis.pairwise import (
    barnard_p,
    binomial_p,
    holm,
    is_mismatch,
    mismatch_tables,
    pairwise_counts,
    pairwise_table,
    preference_ci,
    tie_adjusted,
)


def exact_binom_two_sided(k, n):
    """Two-sided exact binomial p against 1/2: twice the smaller tail, written as sums of C(n, i)."""
    lo = min(k, n - k)
    tail = sum(math.comb(n, i) for i in range(lo + 1)) / 2 ** n
    return min(1.0, 2 * tail)


def holm_by_hand(p):
    m = len(p)
    order = sorted(range(m), key=lambda i: p[i])
    adj, running = [0.0] * m, 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * p[i]))
        adj[i] = running
    return adj


def rows(spec, question="q", participant_of=None):
    """spec: list of (condition_a, condition_b, answer, strength)."""
    out = []
    for i, (a, b, ans, st) in enumerate(spec):
        out.append({"question": question, "condition_a": a, "condition_b": b, "answer": ans,
                    "strength": st, "participant": participant_of(i) if participant_of else f"p{i % 4}"})
    return pd.DataFrame(out)


@pytest.mark.parametrize("k,n", [(0, 1), (1, 1), (3, 10), (5, 10), (9, 12), (0, 17), (15, 16), (30, 41)])
def test_binomial_p_matches_tail_sums(k, n):
    assert binomial_p(k, n) == pytest.approx(exact_binom_two_sided(k, n), rel=1e-12, abs=1e-15)


def test_binomial_p_no_data_is_nan_not_zero():
    assert math.isnan(binomial_p(0, 0))


@pytest.mark.parametrize("k,n", [(0, 5), (3, 10), (10, 10), (1, 1), (47, 80)])
def test_clopper_pearson_from_beta_quantiles(k, n):
    lo = 0.0 if k == 0 else stats.beta.ppf(0.025, k, n - k + 1)
    hi = 1.0 if k == n else stats.beta.ppf(0.975, k + 1, n - k)
    assert preference_ci(k, n) == pytest.approx((lo, hi), abs=1e-9)


@pytest.mark.parametrize("k,n", [(0, 5), (3, 10), (10, 10), (47, 80)])
def test_wilson_by_formula(k, n):
    z = stats.norm.ppf(0.975)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    assert preference_ci(k, n, method="wilson") == pytest.approx((centre - half, centre + half), abs=1e-9)


def test_tie_policies():
    assert tie_adjusted(7, 2, 3, "exclude") == (7, 9, pytest.approx(7 / 9))
    # split: 3 ties -> 1 each, the odd one to B (fewer wins): towards 50 %.
    assert tie_adjusted(7, 2, 3, "split") == (8, 12, pytest.approx(8 / 12))
    assert tie_adjusted(2, 7, 3, "split") == (4, 12, pytest.approx(4 / 12))
    k, n, pref = tie_adjusted(7, 2, 3, "half")
    assert (k, n) == (8, 12)
    assert pref == pytest.approx(8.5 / 12)
    assert tie_adjusted(0, 0, 4, "split") == (2, 4, 0.5)
    k, n, pref = tie_adjusted(0, 0, 4, "exclude")
    assert (k, n) == (0, 0)
    assert math.isnan(pref)


def test_holm_matches_step_down_by_hand_and_is_not_holm_sidak():
    p = [0.01, 0.04, 0.03, 0.005, 0.2]
    assert holm(p) == pytest.approx(holm_by_hand(p))
    # Holm-Sidak (statsmodels' default) would give 1 - (1 - 0.01)^3 for the smallest of three.
    assert holm([0.01, 0.02, 0.03])[0] == pytest.approx(0.03)
    out = holm([0.01, float("nan"), 0.03])
    assert out[0] == pytest.approx(0.02)
    assert math.isnan(out[1])
    assert out[2] == pytest.approx(0.03)


def test_counts_reorient_and_flip_answers():
    df = rows([("A", "B", "a", ""), ("B", "A", "a", ""), ("B", "A", "b", ""), ("A", "B", "tie", "")])
    c = pairwise_counts(df).iloc[0]
    assert (c.condition_a, c.condition_b) == ("A", "B")
    assert (c.n_a, c.n_b, c.n_tie) == (2, 1, 1)


def test_pairwise_table_against_hand_computation_with_ties_empty_and_all_ties():
    spec = ([("A", "B", "a", "")] * 9 + [("A", "B", "b", "")] * 2 + [("B", "A", "tie", "")] * 3
            + [("A", "C", "a", "")] * 4 + [("C", "A", "a", "")] * 4        # A vs C: 4 a, 4 b
            + [("B", "C", "tie", "")] * 5)                                   # all ties
    df = rows(spec)
    t = pairwise_table(df, comparisons=[("q", "D", "A")])
    assert list(t.columns[:11]) == ["question", "condition_a", "condition_b", "n_a", "n_b", "n_tie",
                                                  "pref_a", "ci_low", "ci_high", "p_value", "p_holm"]
    t = t.set_index(["condition_a", "condition_b"])
    ab, ac, bc, ad = t.loc[("A", "B")], t.loc[("A", "C")], t.loc[("B", "C")], t.loc[("A", "D")]
    assert (ab.n_a, ab.n_b, ab.n_tie) == (9, 2, 3)
    assert ab.pref_a == pytest.approx(9 / 11)
    p_ab, p_ac = exact_binom_two_sided(9, 11), exact_binom_two_sided(4, 8)
    assert ab.p_value == pytest.approx(p_ab)
    assert ac.p_value == pytest.approx(p_ac) == 1.0
    # Family = the two testable comparisons only.
    assert [ab.p_holm, ac.p_holm] == pytest.approx(holm_by_hand([p_ab, p_ac]))
    assert math.isnan(bc.p_value)
    assert math.isnan(bc.p_holm)
    assert math.isnan(bc.pref_a)
    assert "all 5 judgements are ties" in bc.note
    assert (ad.n_a, ad.n_b, ad.n_tie) == (0, 0, 0)
    assert "no judgements" in ad.note
    assert math.isnan(ad.p_value)
    assert ab.cohens_h == pytest.approx(2 * math.asin(math.sqrt(9 / 11)) - 2 * math.asin(math.sqrt(0.5)))

    split = pairwise_table(df, tie_policy="split").set_index(["condition_a", "condition_b"])
    # A vs B: 3 ties -> 1 + 1 + odd one to B; all-ties B vs C: 2 of 5 (odd tie to the B side? no:
    # equal wins, so the odd tie goes to B) -> p of 2 of 5.
    assert (split.loc[("A", "B"), "k"], split.loc[("A", "B"), "n"]) == (10, 14)
    assert split.loc[("A", "B"), "p_value"] == pytest.approx(exact_binom_two_sided(10, 14))
    assert split.loc[("B", "C"), "p_value"] == pytest.approx(exact_binom_two_sided(2, 5))
    assert split.loc[("B", "C"), "note"] == ""


def test_holm_per_question():
    df = pd.concat([rows([("A", "B", "a", "")] * 8 + [("A", "B", "b", "")], question="q1"),
                    rows([("A", "B", "a", "")] * 7 + [("A", "B", "b", "")] * 2, question="q2")])
    p1, p2 = exact_binom_two_sided(8, 9), exact_binom_two_sided(7, 9)
    study = pairwise_table(df)
    assert list(study["p_holm"]) == pytest.approx(holm_by_hand([p1, p2]))
    per_q = pairwise_table(df, holm_scope="question")
    assert list(per_q["p_holm"]) == pytest.approx([p1, p2])


def test_five_level_mean_score_and_strength_counts():
    df = rows([("A", "B", "a", "strong"), ("A", "B", "a", "weak"), ("B", "A", "a", "strong"),
               ("A", "B", "tie", "")])
    t = pairwise_table(df).iloc[0]
    assert t.levels == 5
    assert t.n_a_strong == 1
    assert t.n_b_strong == 1
    assert t.mean_score == pytest.approx((2 + 1 - 2 + 0) / 4)


def test_single_participant():
    df = rows([("A", "B", "a", "")] * 6, participant_of=lambda i: "only")
    t = pairwise_table(df).iloc[0]
    assert t.n_participants == 1
    assert t.p_value == pytest.approx(2 / 2 ** 6)


def barnard_by_enumeration(x1, n1, x2, n2, grid=2001):
    """Pooled-variance Wald statistic; p = sup over the common rate of the probability of tables at
    least as extreme, enumerated with math.comb and maximised on a fine grid."""
    def wald(a, b):
        p = (a + b) / (n1 + n2)
        var = p * (1 - p) * (1 / n1 + 1 / n2)
        return 0.0 if var == 0 else (a / n1 - b / n2) / math.sqrt(var)
    t_obs = abs(wald(x1, x2))
    extreme = [(a, b) for a in range(n1 + 1) for b in range(n2 + 1) if abs(wald(a, b)) >= t_obs - 1e-9]
    best = 0.0
    for pi in np.linspace(0, 1, grid):
        s = sum(math.comb(n1, a) * pi ** a * (1 - pi) ** (n1 - a) * math.comb(n2, b) * pi ** b * (1 - pi) ** (n2 - b)
                for a, b in extreme)
        best = max(best, s)
    return best


@pytest.mark.parametrize("x1,n1,x2,n2", [(7, 15, 12, 15), (9, 10, 4, 9), (5, 6, 5, 6)])
def test_barnard_against_enumeration(x1, n1, x2, n2):
    p = barnard_p([[x1, x2], [n1 - x1, n2 - x2]])
    assert p == pytest.approx(barnard_by_enumeration(x1, n1, x2, n2), abs=2e-4)


def test_is_mismatch_marks_x_against_x_plus_suffix_either_way():
    a = pd.Series(["A", "A:mismatched", "A", "B", "A"])
    b = pd.Series(["A:mismatched", "A", "B", "A:mismatched", "A:other"])
    assert is_mismatch(a, b).tolist() == [True, True, False, False, False]
    assert is_mismatch(a, b, ":other").tolist() == [False, False, False, False, True]
    assert is_mismatch(a, b, "").tolist() == [False] * 5


def test_mismatch_tables_split_ties_and_barnard_holm():
    spec = ([("X", "X:mismatched", "a", "strong")] * 8 + [("X:mismatched", "X", "a", "weak")] * 2
            + [("X", "X:mismatched", "tie", "")] * 3
            + [("Y", "Y:mismatched", "a", "weak")] * 5 + [("Y", "Y:mismatched", "b", "weak")] * 5
            + [("Z", "Z:mismatched", "a", "")] * 6 + [("Z", "Z:mismatched", "b", "")] * 1)
    table = pairwise_table(rows(spec))
    per, between = mismatch_tables(table, tie_policy="split")
    per = per.set_index("condition")
    # X: 8 matched, 2 mismatched, 3 ties -> 1 + 1, odd tie to the mismatched side: 9 of 13.
    assert (per.loc["X", "n_matched"], per.loc["X", "n_mismatched"], per.loc["X", "n_tie"]) == (8, 2, 3)
    assert per.loc["X", "pref_matched"] == pytest.approx(9 / 13)
    lo = stats.beta.ppf(0.025, 9, 13 - 9 + 1)
    assert per.loc["X", "ci_low"] == pytest.approx(lo)
    b = between.set_index(["condition_1", "condition_2"])
    p_xy = barnard_by_enumeration(9, 13, 5, 10)
    assert b.loc[("X", "Y"), "p_value"] == pytest.approx(p_xy, abs=2e-4)
    assert list(between["p_holm"]) == pytest.approx(holm_by_hand(list(between["p_value"])))


def test_half_policy_reports_exact_half_share_inside_its_ci():
    df = rows([("A", "B", "a", "")] * 7 + [("A", "B", "b", "")] * 2 + [("A", "B", "tie", "")] * 3)
    t = pairwise_table(df, tie_policy="half").iloc[0]
    assert t.pref_a == pytest.approx(8.5 / 12)
    assert t.p_value == pytest.approx(exact_binom_two_sided(8, 12))  # conservative whole count
    assert t.ci_low <= t.pref_a <= t.ci_high
