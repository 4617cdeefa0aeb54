"""Bradley-Terry / Elo against a direct likelihood maximisation, and the participant bootstrap."""
import math

import numpy as np
import pandas as pd
import pytest
from scipy import optimize

from evalsuite.analysis.ranking import PLAIN_WEIGHTS, bradley_terry, elo_table, win_counts, win_matrices


def battles(spec):
    """spec: list of (participant, condition_a, condition_b, answer, strength, count)."""
    rows = []
    for p, a, b, ans, st, n in spec:
        rows += [{"question": "q", "participant": p, "condition_a": a, "condition_b": b,
                  "answer": ans, "strength": st}] * n
    return pd.DataFrame(rows)


def bt_by_optimizer(W):
    """Maximise sum_ij W_ij log(p_i / (p_i + p_j)) over log-strengths directly."""
    C = W.shape[0]

    def nll(theta):
        d = theta[:, None] - theta[None, :]
        return -(W * -np.logaddexp(0, -d)).sum()
    th = optimize.minimize(nll, np.zeros(C), method="BFGS", options={"gtol": 1e-10}).x
    th = th / math.log(10)
    return th - th.mean()


def test_mm_matches_likelihood_maximum():
    W = np.array([[0, 7, 3, 5], [4, 0, 6, 2], [2, 5, 0, 8], [1, 3, 4, 0]], float)
    assert bradley_terry(W, prior=0) == pytest.approx(bt_by_optimizer(W), abs=1e-5)


def test_elo_200_points_is_76_percent():
    df = battles([("p1", "A", "B", "a", "", 76), ("p1", "A", "B", "b", "", 24)])
    e = elo_table(df, n_boot=0).set_index("condition")["elo"]
    assert e["A"] - e["B"] == pytest.approx(400 * math.log10(76 / 24), abs=0.5)  # prior moves it < 0.5
    assert (e["A"] + e["B"]) / 2 == pytest.approx(1000)


def test_weights_strong_weak_tie():
    df = battles([("p1", "A", "B", "a", "strong", 1), ("p1", "B", "A", "a", "weak", 1),
                  ("p2", "A", "B", "tie", "", 1)])
    parts, W = win_matrices(df, ["A", "B"])
    assert parts == ["p1", "p2"]
    assert W[0].tolist() == [[0, 4], [2, 0]]
    assert W[1].tolist() == [[0, 1], [1, 0]]


def test_plain_win_counts_give_elo_tables_win_rate():
    """With PLAIN_WEIGHTS a strong, a weak and a plain win each count 1 and a tie half a win each way; elo.csv's
    win_rate is wins / judgements of these counts (A: 3 of 5, B: 2.5 of 5, C: a tie and a loss, 0.5 of 2)."""
    df = battles([("p1", "A", "B", "a", "strong", 1), ("p1", "B", "A", "a", "weak", 1),
                  ("p2", "A", "B", "tie", "", 1), ("p2", "A", "B", "a", "", 1),
                  ("p2", "C", "A", "tie", "", 1), ("p1", "C", "B", "b", "", 1)])
    parts, W = win_matrices(df, ["A", "B", "C"], PLAIN_WEIGHTS)
    assert parts == ["p1", "p2"]
    assert W[0].tolist() == [[0, 1, 0], [1, 0, 1], [0, 0, 0]]
    assert W[1].tolist() == [[0, 1.5, 0.5], [0.5, 0, 0], [0.5, 0, 0]]
    wins, judged = win_counts(W)
    assert wins.tolist() == [[1, 2, 0], [2, 0.5, 0.5]] and judged.tolist() == [[2, 3, 1], [3, 2, 1]]
    total_wins, total = win_counts(W.sum(axis=0))
    assert total_wins.tolist() == [3, 2.5, 0.5] and total.tolist() == [5, 5, 2]
    table = elo_table(df, n_boot=0).set_index("condition")
    assert table["win_rate"].to_dict() == {"A": 3 / 5, "B": 2.5 / 5, "C": 0.5 / 2}
    assert table["n_judgements"].to_dict() == {"A": 5, "B": 5, "C": 2}


def test_bootstrap_resamples_participants_seeded():
    # p1 always prefers A, p2 always B: only participant resampling shows the disagreement.
    df = battles([("p1", "A", "B", "a", "", 10), ("p2", "A", "B", "b", "", 10)])
    t1 = elo_table(df, n_boot=400, seed=7).set_index("condition")
    t2 = elo_table(df, n_boot=400, seed=7).set_index("condition")
    pd.testing.assert_frame_equal(t1, t2)
    a = t1.loc["A"]
    assert a.elo == pytest.approx(1000)
    assert a.ci_low < 900
    assert a.ci_high > 1100


def test_single_participant_and_disconnected_graph_notes():
    one = elo_table(battles([("p1", "A", "B", "a", "", 3), ("p1", "A", "B", "b", "", 1)]), n_boot=100)
    assert one["note"].str.contains("single participant").all()
    assert one["elo"].notna().all()
    assert one["ci_low"].isna().all()
    disc = elo_table(battles([("p1", "A", "B", "a", "", 3), ("p2", "C", "D", "a", "", 3)]), n_boot=10)
    assert disc["note"].str.contains("not connected").all()
    assert disc["elo"].isna().all()


def test_never_winning_condition_stays_finite():
    df = battles([(f"p{i}", "A", "B", "a", "", 3) for i in range(4)] + [("p0", "B", "C", "a", "", 2)])
    t = elo_table(df, n_boot=200, seed=1)
    assert np.isfinite(t[["elo", "ci_low", "ci_high"]].to_numpy(float)).all()
    e = t.set_index("condition")["elo"]
    assert e["A"] > e["B"] > e["C"]
