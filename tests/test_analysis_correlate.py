"""`evalsuite correlate`: metrics against human judgements, checked against scipy and by hand."""
import itertools
import math
import re

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from scipy import stats

from evalsuite.analysis import correlate as corr
from evalsuite.analysis.correlate import (
    COLUMNS,
    ParticipantResampler,
    correlate,
    kendall_b_rows,
    rank_correlations,
    read_human,
    read_scores,
    spearman_rows,
)
from evalsuite.analysis.demo import sample_results_path
from evalsuite.cli import main
from evalsuite.errors import InputError

SAMPLE = sample_results_path()
STUDY = ["BL", "Jitter", "NA", "SysA", "SysB"]   # the conditions of the bundled simulated study


def scores_frame(values, metric="ape", conds=None):
    conds = conds or [f"c{i}" for i in range(len(values))]
    return pd.DataFrame({"condition": conds, "metric": metric, "value": values})


def human_frame(values, conds=None, measure="median", question="q"):
    conds = conds or [f"c{i}" for i in range(len(values))]
    return pd.DataFrame({"condition": conds, "value": values, "measure": measure, "question": question})


def tau_by_hand(x, y):
    """(tau_a, tau_b) from the pair counts: tau_b = (nc - nd) / sqrt((n0 - n1)(n0 - n2))."""
    nc = nd = tx = ty = 0
    for i, j in itertools.combinations(range(len(x)), 2):
        s = np.sign(x[i] - x[j]) * np.sign(y[i] - y[j])
        nc += s > 0
        nd += s < 0
        tx += x[i] == x[j]
        ty += y[i] == y[j]
    n0 = len(x) * (len(x) - 1) / 2
    return (nc - nd) / n0, (nc - nd) / math.sqrt((n0 - tx) * (n0 - ty))


def p_by_enumeration(x, y, rows_statistic):
    """Two-sided permutation p-value over every ordering of y, by hand: min(1, 2 min(P(T* >= T), P(T* <= T)))."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    perms = np.array(list(itertools.permutations(range(len(y)))))
    null = rows_statistic(np.broadcast_to(x, perms.shape), y[perms])
    t = rows_statistic(x[None], y[None])[0]
    return min(1.0, 2 * min((null >= t - 1e-9).mean(), (null <= t + 1e-9).mean()))


# --- point estimates and p-values ----------------------------------------------------------------

TIED_X = [1.0, 2.0, 2.0, 3.0, 4.0, 4.0, 5.0, 6.0]
TIED_Y = [10.0, 20.0, 20.0, 20.0, 40.0, 30.0, 40.0, 50.0]


def test_point_estimates_are_scipys_and_p_values_exact_with_ties():
    t = correlate(scores_frame(TIED_X), human_frame(TIED_Y), n_boot=0)
    assert len(t) == 1 and list(t.columns) == COLUMNS
    r = t.iloc[0]
    s = stats.spearmanr(TIED_X, TIED_Y)
    k = stats.kendalltau(TIED_X, TIED_Y, variant="b")
    assert r.n == 8 == corr.EXACT_MAX_N
    assert r.spearman_rho == s.statistic and r.kendall_tau_b == k.statistic
    # p over all 8! orderings, ties kept (scipy's defaults would give the t / normal approximations)
    assert r.spearman_p == pytest.approx(p_by_enumeration(TIED_X, TIED_Y, spearman_rows), rel=1e-9)
    assert r.kendall_p == pytest.approx(p_by_enumeration(TIED_X, TIED_Y, kendall_b_rows), rel=1e-9)
    assert r.spearman_p != pytest.approx(s.pvalue, rel=0.1) and r.kendall_p != pytest.approx(k.pvalue, rel=0.1)
    assert r.spearman_p_method == r.kendall_p_method == "exact"
    # tau-b, not tau-a: with ties they differ, and the table has tau-b
    tau_a, tau_b = tau_by_hand(TIED_X, TIED_Y)
    assert abs(tau_a - tau_b) > 0.05
    assert r.kendall_tau_b == pytest.approx(tau_b, abs=1e-12)
    assert r.kendall_tau_b != pytest.approx(tau_a, abs=1e-3)
    # Spearman = Pearson of average ranks
    assert r.spearman_rho == pytest.approx(np.corrcoef(stats.rankdata(TIED_X), stats.rankdata(TIED_Y))[0, 1])


def test_rank_correlations_without_ties_use_exact_p_values():
    x, y = [3.0, 1.0, 4.0, 1.5, 5.0, 9.0, 2.0], [2.0, 1.0, 3.0, 5.0, 4.0, 7.0, 6.0]
    rho, p_rho, tau, p_tau = rank_correlations(x, y)
    assert rho == stats.spearmanr(x, y).statistic
    assert p_rho == pytest.approx(p_by_enumeration(x, y, spearman_rows), rel=1e-9)
    assert (tau, p_tau) == tuple(stats.kendalltau(x, y, variant="b", method="exact"))
    assert p_tau == pytest.approx(p_by_enumeration(x, y, kendall_b_rows), rel=1e-9)


def test_four_conditions_in_perfect_order_are_not_significant():
    """The issue: n = 4, rho = 1 was reported as p < 0.0001 (t approximation); exactly, 2 of the 24 orderings
    are as extreme, p = 1/12."""
    assert stats.spearmanr([1, 2, 3, 4], [1, 2, 3, 4]).pvalue < 1e-4
    assert corr.rank_p_values([1, 2, 3, 4], [10, 20, 30, 40]) == pytest.approx((1 / 12, "exact", 1 / 12, "exact"))
    assert corr.rank_p_values([1, 2, 3, 4], [40, 30, 20, 10])[0] == pytest.approx(1 / 12)


def test_above_the_threshold_p_values_are_scipys_approximations():
    x = np.arange(corr.EXACT_MAX_N + 1, dtype=float)
    y = np.array([2, 1, 4, 3, 6, 5, 8, 9, 7], dtype=float)
    p_rho, m_rho, p_tau, m_tau = corr.rank_p_values(x, y)
    assert (p_rho, m_rho) == (stats.spearmanr(x, y).pvalue, "t approximation")
    assert (p_tau, m_tau) == (stats.kendalltau(x, y, method="exact").pvalue, "exact")  # no ties: exact to n = 33
    y[0] = y[1]  # a tie: tau-b's exact distribution is scipy's only without ties
    assert corr.rank_p_values(x, y)[2:] == (stats.kendalltau(x, y, method="asymptotic").pvalue, "normal approximation")


def test_vectorised_replicates_equal_scipy_row_by_row():
    rng = np.random.default_rng(0)
    X = rng.integers(0, 4, size=(300, 7)).astype(float)
    Y = rng.integers(0, 3, size=(300, 7)).astype(float)
    rho, tau = spearman_rows(X, Y), kendall_b_rows(X, Y)
    for i in range(300):
        if np.ptp(X[i]) == 0 or np.ptp(Y[i]) == 0:
            assert np.isnan(rho[i]) and np.isnan(tau[i])
            continue
        assert rho[i] == pytest.approx(stats.spearmanr(X[i], Y[i]).statistic, abs=1e-12)
        assert tau[i] == pytest.approx(stats.kendalltau(X[i], Y[i]).statistic, abs=1e-12)


def test_direction_and_agrees():
    x = [1.0, 2.0, 3.0, 4.0]
    down = [40.0, 30.0, 20.0, 10.0]
    frame = pd.concat([scores_frame(x, "ape"), scores_frame(x, "speed"), scores_frame(x, "cca"),
                       scores_frame(x, "hellinger_speed[wrists]"),
                       scores_frame(x, "mystery").assign(better="higher"), scores_frame(x, "unknown")])
    t = correlate(frame, human_frame(down), n_boot=0).set_index("metric")
    assert t.loc["ape", "better"] == "lower" and t.loc["ape", "agrees"] is True           # lower & rho < 0
    assert t.loc["cca", "better"] == "higher" and t.loc["cca", "agrees"] is False         # higher & rho < 0
    assert t.loc["hellinger_speed[wrists]", "better"] == "lower"                          # a joint group
    assert t.loc["speed", "better"] == "closer to natural" and t.loc["speed", "agrees"] is None
    assert "no expected sign" in t.loc["speed", "note"]
    assert t.loc["mystery", "better"] == "higher" and t.loc["mystery", "agrees"] is False  # summary's column
    assert t.loc["unknown", "better"] == "" and t.loc["unknown", "agrees"] is None
    flipped = correlate(frame, human_frame(down), n_boot=0, human_higher=False).set_index("metric")
    assert flipped.loc["ape", "agrees"] is False


def test_distance_to_natural_gives_closer_to_natural_metrics_a_sign():
    conds = ["NA", "A", "B", "C"]
    speed = scores_frame([10.0, 12.0, 4.0, 30.0], "speed", conds)      # |speed - NA| = 0, 2, 6, 20
    human = human_frame([90.0, 70.0, 50.0, 20.0], conds)
    t = correlate(speed, human, n_boot=0, natural="NA").set_index("metric")
    d = t.loc["|speed - NA|"]
    assert d.better == "lower" and d.spearman_rho == pytest.approx(-1.0) and d.agrees is True
    assert t.loc["speed", "agrees"] is None
    with pytest.raises(InputError, match="--natural 'natural': no such condition in the scores"):
        correlate(speed, human, natural="natural")


# --- bootstrap -------------------------------------------------------------------------------------

def test_condition_bootstrap_is_seeded_and_contains_the_estimate():
    rng = np.random.default_rng(1)
    x = np.arange(10.0)
    y = x + rng.normal(0, 3, 10)
    a = correlate(scores_frame(x), human_frame(y), n_boot=500, seed=7)
    b = correlate(scores_frame(x), human_frame(y), n_boot=500, seed=7)
    c = correlate(scores_frame(x), human_frame(y), n_boot=500, seed=8)
    pd.testing.assert_frame_equal(a, b)
    assert a.spearman_ci_low.iloc[0] != c.spearman_ci_low.iloc[0] or a.kendall_ci_low.iloc[0] != c.kendall_ci_low.iloc[0]
    r = a.iloc[0]
    assert r.spearman_ci_low <= r.spearman_rho <= r.spearman_ci_high
    assert r.kendall_ci_low <= r.kendall_tau_b <= r.kendall_ci_high
    # a clean monotone example: every defined resample is a perfect correlation
    mono = correlate(scores_frame(x), human_frame(np.exp(x / 3)), n_boot=400, seed=3).iloc[0]
    assert mono.spearman_rho == pytest.approx(1.0) and mono.kendall_tau_b == pytest.approx(1.0)
    assert mono.spearman_ci_low <= mono.spearman_rho <= mono.spearman_ci_high
    assert mono.kendall_ci_low <= mono.kendall_tau_b <= mono.kendall_ci_high
    assert mono.spearman_ci_low == pytest.approx(1.0)


def test_percentiles_are_of_the_resampled_conditions():
    """The CI is the percentile interval of rho over resamples drawn as default_rng(seed).integers(0, n, (B, n))."""
    x, y = np.array(TIED_X), np.array(TIED_Y)
    idx = np.random.default_rng(11).integers(0, 8, size=(300, 8))
    rhos = []
    for row in idx:
        if np.ptp(x[row]) > 0 and np.ptp(y[row]) > 0:
            rhos.append(stats.spearmanr(x[row], y[row]).statistic)
    r = correlate(scores_frame(x), human_frame(y), n_boot=300, seed=11).iloc[0]
    lo, hi = np.percentile(rhos, [2.5, 97.5])
    assert (r.spearman_ci_low, r.spearman_ci_high) == (pytest.approx(lo, abs=1e-12), pytest.approx(hi, abs=1e-12))


# --- undefined and mismatched inputs ---------------------------------------------------------------

def test_constant_metric_gives_a_row_with_a_note():
    t = correlate(pd.concat([scores_frame([2.0, 2.0, 2.0, 2.0], "flat"), scores_frame([1.0, 2.0, 3.0, 4.0], "ape")]),
                  human_frame([1.0, 3.0, 2.0, 4.0]), n_boot=50)
    flat = t.set_index("metric").loc["flat"]
    assert math.isnan(flat.spearman_rho) and math.isnan(flat.kendall_tau_b) and math.isnan(flat.spearman_ci_low)
    assert "metric constant across conditions" in flat.note and flat.agrees is None
    assert np.isfinite(t.set_index("metric").loc["ape", "spearman_rho"])
    const_h = correlate(scores_frame([1.0, 2.0, 3.0]), human_frame([5.0, 5.0, 5.0]), n_boot=10).iloc[0]
    assert "human measure constant" in const_h.note


def test_missing_values_are_left_out_per_metric():
    t = correlate(scores_frame([1.0, np.nan, 3.0, 4.0]), human_frame([1.0, 2.0, 3.0, 5.0]), n_boot=0).iloc[0]
    assert t.n == 3 and t.conditions == "c0;c2;c3" and "no value for c1" in t.note
    few = correlate(scores_frame([1.0, np.nan, np.nan, 4.0]), human_frame([1.0, 2.0, 3.0, 5.0]), n_boot=0).iloc[0]
    assert few.n == 2 and math.isnan(few.spearman_rho) and "needs 3" in few.note


def test_condition_mismatch_names_conditions_and_files():
    s = scores_frame([1.0, 2.0, 3.0, 4.0], conds=["A", "B", "C", "natural"])
    s.attrs["path"] = "scores/summary.csv"
    h = human_frame([1.0, 2.0, 3.0, 4.0], conds=["A", "B", "C", "NA"])
    h.attrs["path"] = "analysis/ratings.csv"
    with pytest.raises(InputError) as err:
        correlate(s, h)
    msg = str(err.value)
    assert "scores (scores/summary.csv) but not the human judgements: natural" in msg
    assert "human judgements (analysis/ratings.csv) but not the scores: NA" in msg
    notes = []
    t = correlate(s, h, shared_only=True, notes=notes, n_boot=0)
    assert t.iloc[0].n == 3 and any("natural" in n for n in notes) and any("NA" in n for n in notes)


def test_fewer_than_three_shared_conditions():
    with pytest.raises(InputError, match="2 condition.*shared.*A, B.*at least 3"):
        correlate(scores_frame([1.0, 2.0], conds=["A", "B"]), human_frame([1.0, 2.0], conds=["A", "B"]))


@pytest.mark.parametrize("text, expected", [
    ("condition,metric,value\nA,ape,1\nB,ape,abc\n", r"s\.csv:3: value: 'abc' is not a number; expected a finite number"),
    ("condition,metric,value\nA,ape,1\nA,ape,2\n", r"s\.csv:3: condition: metric / condition 'ape / A' appears twice \(lines 2, 3\)"),
    ("condition,metric,value\nA,ape\n", r"s\.csv:2: row has 2 fields but the header has 3"),
    ("cond,val\nA,1\n", r"s\.csv:1: missing column\(s\) condition, value; expected the summary\.csv"),
    ("condition,metric,value\n,ape,1\n", r"s\.csv:2: condition: empty value; expected a condition name"),
    ("", r"s\.csv:1: empty file"),
])
def test_malformed_scores_name_file_line_column(tmp_path, text, expected):
    p = tmp_path / "s.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=expected):
        read_scores(p)


def test_malformed_human_files(tmp_path):
    p = tmp_path / "h.csv"
    p.write_text("question,condition,median,mean\nq,A,50,x\n")
    with pytest.raises(InputError, match=r"h\.csv:2: mean: 'x' is not a number"):
        read_human(p)
    p.write_text("who,what\nA,1\n")
    with pytest.raises(InputError, match=r"h\.csv:1: unrecognised header \(who, what\); expected ratings\.csv"):
        read_human(p)
    p.write_text("question,condition,median,mean\nq,A,50,40\n")
    with pytest.raises(InputError, match=r"no measure 'elo' in this ratings file; it has: median, mean"):
        read_human(p, measures=["elo"])
    with pytest.raises(InputError, match="results file: run `evalsuite analyze`"):
        read_human(SAMPLE)


def test_plain_files_keep_na_as_a_name(tmp_path):
    p = tmp_path / "mos.csv"
    p.write_text("condition,value\nNA,4.5\nA,3.1\nB,2.0\n")
    h = read_human(p)
    assert list(h["condition"]) == ["NA", "A", "B"] and set(h["measure"]) == {"mos"}
    s = read_scores(p)
    assert s.attrs["plain"] and set(s["metric"]) == {"mos"}


def test_pairwise_win_rates_by_hand(tmp_path):
    """(wins + ties / 2) / judgements over a condition's comparisons; matched-vs-mismatched rows left out; a
    comparison without judgements adds nothing (a condition with none has no value); ``line``: its first row."""
    p = tmp_path / "pairwise.csv"
    p.write_text("question,condition_a,condition_b,n_a,n_b,n_tie\n"
                 "q,A,B,3,1,2\n"
                 "q,A,A:mismatched,9,0,0\n"
                 "q,B,C,0,0,0\n"
                 "r,A,B,1,0,1\n")
    h = read_human(p)
    got = {(q, c): (v, line) for q, c, v, line in zip(h.question, h.condition, h.value, h.line)}
    assert set(got) == {("q", "A"), ("q", "B"), ("q", "C"), ("r", "A"), ("r", "B")}
    assert got[("q", "A")] == (4 / 6, 2) and got[("q", "B")] == (2 / 6, 2)
    assert math.isnan(got[("q", "C")][0]) and got[("q", "C")][1] == 4
    assert got[("r", "A")] == (1.5 / 2, 5) and got[("r", "B")] == (0.5 / 2, 5)
    assert set(h.measure) == {"win_rate"}
    kept = read_human(p, mismatch_suffix="")   # no suffix: X vs X:mismatched is a comparison like any other
    assert dict(zip(zip(kept.question, kept.condition), kept.value))[("q", "A")] == (4 + 9) / (6 + 9)


# --- the command on real `evalsuite score` and `evalsuite analyze` outputs -------------------------

def invoke(*args):
    return CliRunner().invoke(main, [*map(str, args)], catch_exceptions=False)


@pytest.fixture(scope="module")
def real(tmp_path_factory):
    """summary.csv of `evalsuite score` with the study's condition names, and `evalsuite analyze` of the
    bundled simulated results."""
    from evalsuite.metrics.demo import build_conditions

    root = tmp_path_factory.mktemp("correlate")
    f = build_conditions(root, seed=3)
    r = invoke("score", "-r", f"NA={f['natural']}", f"BL={f['mismatched']}", f"Jitter={f['jitter']}",
               f"SysA={f['smoothed']}", f"SysB={f['static']}", "--quiet", "--no-figures", "-o", root / "scores")
    assert r.exit_code == 0, r.output
    r = invoke("analyze", SAMPLE, "-o", root / "analysis", "--bootstrap", "100", "--no-figures")
    assert r.exit_code == 0, r.output
    return root


def test_cli_writes_every_output_from_real_score_and_analyze(real, tmp_path):
    summary, ratings = real / "scores" / "summary.csv", real / "analysis" / "ratings.csv"
    out = tmp_path / "corr"
    r = invoke("correlate", summary, ratings, "-o", out, "--results", SAMPLE, "--bootstrap", "200")
    assert r.exit_code == 0, r.output
    table = pd.read_csv(out / "correlations.csv", keep_default_na=False, na_values=[""])
    assert list(table.columns) == COLUMNS
    metrics = list(dict.fromkeys(pd.read_csv(summary)["metric"]))
    assert set(table["metric"]) == set(metrics) and set(table["measure"]) == {"median", "mean"}
    assert len(table) == 2 * len(metrics)
    for m in metrics:
        assert (out / "figures" / f"scatter_{re.sub(r'[^A-Za-z0-9_-]', '_', m)}.png").stat().st_size > 1000
    assert (out / "correlations.md").read_text().startswith("| metric | human measure | n | rho |")
    assert "\\begin{tabular}" in (out / "correlations.tex").read_text()
    # the numbers are scipy's on the two files
    s = pd.read_csv(summary, keep_default_na=False)
    h = pd.read_csv(ratings, keep_default_na=False)
    x = s[s.metric == "ape"].set_index("condition")["value"].astype(float)[STUDY]
    y = h.set_index("condition")["median"].astype(float)[STUDY]
    row = table[(table.metric == "ape") & (table.measure == "median")].iloc[0]
    assert row.spearman_rho == pytest.approx(stats.spearmanr(x, y).statistic, abs=1e-15)
    assert row.kendall_p == pytest.approx(p_by_enumeration(x, y, kendall_b_rows), abs=1e-12)
    assert row.spearman_p_method == row.kendall_p_method == "exact" and "| p from |" in (out / "correlations.md").read_text()
    assert row.conditions == ";".join(STUDY) and row.n == 5 and row.better == "lower"
    assert np.isfinite(row.spearman_ci_low_participants) and np.isfinite(row.kendall_ci_high_participants)
    assert "median (hl_rating)" in r.output and "Wrote" in r.output


def test_cli_elo_pairwise_and_participant_bootstrap(real, tmp_path):
    summary = real / "scores" / "summary.csv"
    elo = real / "analysis" / "elo.csv"
    r = invoke("correlate", summary, elo, "-o", tmp_path / "e", "--exclude", "Jitter", "--bootstrap", "100",
               "--results", SAMPLE, "--no-figures")
    assert r.exit_code == 0, r.output
    t = pd.read_csv(tmp_path / "e" / "correlations.csv")
    assert set(t["measure"]) == {"elo", "win_rate"} and (t["n"] == 4).all()
    # pairwise.csv -> win rates equal to elo.csv's (matched-vs-mismatched comparisons left out)
    pw = read_human(real / "analysis" / "pairwise.csv")
    el = read_human(elo, measures=["win_rate"])
    assert set(pw["question"]) == {"human_likeness"}
    assert dict(zip(pw.condition, pw.value)) == pytest.approx(dict(zip(el.condition, el.value)), abs=1e-12)
    # the participant bootstrap recomputes each measure exactly as `evalsuite analyze` did
    res = ParticipantResampler.from_results(SAMPLE)
    for name in ("ratings", "elo", "pairwise", "likert_means"):
        h = read_human(real / "analysis" / f"{name}.csv")
        for (q, m), g in h.groupby(["question", "measure"]):
            assert res.point(h.attrs["source"], q, m, list(g.condition)) == pytest.approx(g.value.to_numpy(), abs=1e-9)
            reps = res.replicates(h.attrs["source"], q, m, list(g.condition), 50, 1)
            assert reps.shape == (50, len(g)) and np.isfinite(reps).all()


def test_cli_results_recomputes_with_the_analysis_options(real, tmp_path):
    """--results reads the elo prior and the playback rule of the analysis beside HUMAN (its summary.json)."""
    out = tmp_path / "analysis"
    r = invoke("analyze", SAMPLE, "-o", out, "--bootstrap", "20", "--no-figures", "--elo-prior", "2",
               "--implausible-playback", "0")
    assert r.exit_code == 0, r.output
    r = invoke("correlate", real / "scores" / "summary.csv", out / "elo.csv", "--results", SAMPLE, "--shared-only",
               "--bootstrap", "20", "--no-figures", "-o", tmp_path / "c")
    assert r.exit_code == 0, r.output
    assert np.isfinite(pd.read_csv(tmp_path / "c" / "correlations.csv")["spearman_ci_low_participants"]).any()
    res = ParticipantResampler.from_results(SAMPLE, elo_prior=2.0)
    el = read_human(out / "elo.csv", measures=["elo"])
    assert res.point("elo", "human_likeness", "elo", list(el.condition)) == pytest.approx(el.value.to_numpy())


def test_cli_errors_are_one_line(real, tmp_path):
    summary, ratings = real / "scores" / "summary.csv", real / "analysis" / "ratings.csv"
    r = invoke("correlate", summary, real / "analysis" / "elo.csv", "-o", tmp_path / "x")
    assert r.exit_code == 1 and "Traceback" not in r.output
    assert f"human judgements ({real / 'analysis' / 'elo.csv'}) but not the scores" not in r.output
    assert f"in the scores ({summary}) but not the human judgements: Jitter" in r.output
    r = invoke("correlate", summary, ratings, "--rename", "NA=natural", "-o", tmp_path / "x")
    assert r.exit_code == 1 and "but not the scores: NA" in r.output and "but not the human judgements: natural" in r.output
    changed = tmp_path / "ratings.csv"
    changed.write_text(ratings.read_text().replace(",SysA,,40,10,67.5,", ",SysA,,40,10,60.0,"))
    r = invoke("correlate", summary, changed, "--results", SAMPLE, "-o", tmp_path / "x")
    assert r.exit_code == 1 and "median of 'SysA' is 60 here but 67.5 recomputed" in r.output
    r = invoke("correlate", summary, ratings, "--metric", "nope", "-o", tmp_path / "x")
    assert r.exit_code == 1 and "no metric 'nope'" in r.output


def test_cli_published_numbers_and_help(tmp_path):
    fgd = tmp_path / "fgd.csv"
    fgd.write_text("condition,value\nA,10.5\nB,22.0\nC,3.1\nD,40.0\n")
    mos = tmp_path / "human.csv"
    mos.write_text("condition,value\nA,3.9\nB,3.0\nC,4.2\nD,2.5\n")
    r = invoke("correlate", fgd, mos, "--metric", "fgd", "-o", tmp_path / "o", "--bootstrap", "100")
    assert r.exit_code == 0, r.output
    row = pd.read_csv(tmp_path / "o" / "correlations.csv").iloc[0]
    assert row.metric == "fgd" and row.human_measure == "human" and row.spearman_rho == -1.0 and bool(row.agrees)
    assert row.spearman_p == pytest.approx(1 / 12) and row.spearman_p_method == "exact"
    md = (tmp_path / "o" / "correlations.md").read_text()
    assert "0.0833" in md and "<0.0001" not in md and "exact" in md
    assert (tmp_path / "o" / "figures" / "scatter_fgd.png").is_file()
    r = invoke("correlate", "--help")
    assert r.exit_code == 0 and "Example:" in r.output and "evalsuite correlate scores/summary.csv" in r.output
    assert "correlate" in invoke("--help").output


def test_cli_groups_notes_by_kind_and_writes_them_all(tmp_path):
    rows = ["condition,metric,value"]
    for i in range(10):  # ten metrics constant across the conditions, one without a value for D
        rows += [f"{c},flat{i},1.0" for c in "ABCD"]
    rows += ["A,gappy,1", "B,gappy,2", "C,gappy,3", "A,ok,1", "B,ok,2", "C,ok,3", "D,ok,4"]
    scores = tmp_path / "scores.csv"
    scores.write_text("\n".join(rows) + "\n")
    human = tmp_path / "human.csv"
    human.write_text("condition,value\nA,3.9\nB,3.0\nC,4.2\nD,2.5\n")
    r = invoke("correlate", scores, human, "-o", tmp_path / "o", "--bootstrap", "0", "--no-figures")
    assert r.exit_code == 0, r.output
    lines = [ln for ln in r.output.splitlines() if ln.startswith("note:")]
    assert len(lines) == 2
    assert lines[0].startswith("note: metric constant (10 rows): flat0 / human: metric constant") and "and 7 more" in lines[0]
    assert lines[1].startswith("note: no value for some conditions (1 row): gappy / human: no value for D")
    notes = pd.read_csv(tmp_path / "o" / "notes.csv")
    assert list(notes.columns) == ["kind", "metric", "human_measure", "note"] and len(notes) == 11
    assert f"All 11 notes: {tmp_path / 'o' / 'notes.csv'}" in r.output
    r = invoke("correlate", scores, human, "-o", tmp_path / "o", "--bootstrap", "0", "--no-figures", "--verbose")
    assert sum(ln.startswith("note: flat") for ln in r.output.splitlines()) == 10
    # a later run without notes leaves no stale notes.csv behind
    r = invoke("correlate", scores, human, "-o", tmp_path / "o", "--metric", "ok", "--bootstrap", "0", "--no-figures")
    assert r.exit_code == 0 and "note:" not in r.output and not (tmp_path / "o" / "notes.csv").exists()


# --- the analysis report --------------------------------------------------------------------------

def test_analyze_scores_adds_the_report_section(real, tmp_path):
    out = tmp_path / "report"
    summary = pd.read_csv(real / "scores" / "summary.csv", keep_default_na=False)
    few = tmp_path / "summary.csv"   # three of the metrics: fewer figures to draw
    summary[summary.metric.isin(["ape", "speed", "cca"])].to_csv(few, index=False)
    r = invoke("analyze", SAMPLE, "-o", out, "--bootstrap", "100", "--scores", few)
    assert r.exit_code == 0, r.output
    page = (out / "report.html").read_text()
    assert "<h2>Metrics vs humans</h2>" in page and "median (hl_rating)" in page and "elo (human_likeness)" in page
    assert (out / "correlations.csv").is_file() and (out / "figures" / "scatter_ape.png").is_file()
    assert "only in the scores, left out: Jitter" in r.output    # the anchor is not in the pairwise study
    t = pd.read_csv(out / "correlations.csv")
    assert np.isfinite(t["spearman_ci_low_participants"]).any()


def test_report_resamples_elo_with_the_analysis_prior(real, tmp_path, monkeypatch):
    from evalsuite.analysis.correlate import output

    priors = []

    class Recording(ParticipantResampler):
        def __init__(self, data, mismatch_suffix=":mismatched", prior=0.1):
            priors.append(prior)
            super().__init__(data, mismatch_suffix, prior)

    monkeypatch.setattr(output, "ParticipantResampler", Recording)
    summary = pd.read_csv(real / "scores" / "summary.csv", keep_default_na=False)
    few = tmp_path / "summary.csv"
    summary[summary.metric.isin(["ape", "cca"])].to_csv(few, index=False)
    r = invoke("analyze", SAMPLE, "-o", tmp_path / "r", "--bootstrap", "20", "--no-figures", "--elo-prior", "2",
               "--scores", few)
    assert r.exit_code == 0, r.output
    assert priors == [2.0]


def test_blind_analysis_section_shows_no_real_names(real, tmp_path):
    out = tmp_path / "blind"
    r = invoke("analyze", SAMPLE, "-o", out, "--bootstrap", "50", "--no-figures", "--blind",
               "--scores", real / "scores" / "summary.csv")
    assert r.exit_code == 0, r.output
    page = (out / "report.html").read_text()
    assert "<h2>Metrics vs humans</h2>" in page
    section = page[page.index("<h2>Metrics vs humans</h2>"):]
    for name in ("SysA", "SysB", "Jitter"):
        assert name not in section and name not in r.output
    conds = pd.read_csv(out / "correlations.csv")["conditions"]
    assert all(re.fullmatch(r"(B\d\d;?)+", c) for c in conds)


def test_analyze_scores_malformed_stops_before_the_analysis(tmp_path):
    bad = tmp_path / "summary.csv"
    bad.write_text("condition,metric,value\nA,ape,x\n")
    r = invoke("analyze", SAMPLE, "-o", tmp_path / "r", "--scores", bad)
    assert r.exit_code == 1 and "summary.csv:2: value: 'x' is not a number" in r.output
    assert not (tmp_path / "r" / "report.html").exists()


def test_two_level_bootstrap_resamples_conditions_and_participants_together():
    from evalsuite.analysis.correlate.bootstrap import two_level_bootstrap

    x = np.arange(8.0)
    y = np.array([0.0, 2, 1, 3, 5, 4, 7, 6])
    R = 400
    # no rater uncertainty: the same as resampling the conditions with the documented generator
    lo, hi, tlo, thi, bad = two_level_bootstrap(x, np.tile(y, (R, 1)), seed=3)
    idx = np.random.default_rng([3, 2]).integers(0, 8, size=(R, 8))
    rho = np.array([stats.spearmanr(x[i], y[i]).statistic if np.ptp(x[i]) and np.ptp(y[i]) else np.nan for i in idx])
    assert bad == int(np.isnan(rho).sum())
    assert (lo, hi) == pytest.approx(tuple(np.nanpercentile(rho, [2.5, 97.5])), abs=1e-9)
    # with rater noise the interval is wider than either source alone gives
    H = y + np.random.default_rng(0).normal(0, 1.5, size=(R, 8))
    lo2, hi2, *_ = two_level_bootstrap(x, H, seed=3)
    rr = np.array([stats.spearmanr(x, h).statistic for h in H])
    p_lo, p_hi = np.percentile(rr, [2.5, 97.5])
    assert hi2 - lo2 > hi - lo and hi2 - lo2 > p_hi - p_lo


def test_correlate_reports_two_level_cis_with_results(tmp_path):
    rng = np.random.default_rng(1)
    conds = [f"S{i}" for i in range(6)]
    rows = []
    for p in range(12):
        for seg in range(3):
            for i, c in enumerate(conds):
                rows.append(dict(study="s", participant=f"p{p}", session=f"p{p}", session_status="finished",
                                 page=f"p{p}-{seg}", page_type="mushra", question="hl", condition=c, condition_a="",
                                 condition_b="", answer=str(int(np.clip(10 * i + rng.normal(0, 15) + 20, 0, 100))),
                                 is_training=0, is_attention_check=0, attention_passed="", segment=f"g{seg}"))
    pd.DataFrame(rows).to_csv(tmp_path / "results.csv", index=False)
    resampler = corr.ParticipantResampler.from_results(tmp_path / "results.csv")
    scores = pd.DataFrame({"condition": conds, "metric": "m", "value": [5.0, 4, 3.5, 3, 1, 0.5]})
    human = pd.DataFrame({"condition": conds, "question": "hl", "measure": "mean",
                          "value": resampler.point("ratings", "hl", "mean", conds)})
    human.attrs["source"] = "ratings"
    row = corr.correlate(scores, human, n_boot=300, participants=resampler).iloc[0]
    assert row.spearman_ci_low_both <= row.spearman_rho <= row.spearman_ci_high_both
    assert row.spearman_ci_high_both - row.spearman_ci_low_both >= (
        row.spearman_ci_high_participants - row.spearman_ci_low_participants)
    assert np.isfinite(row.kendall_ci_low_both) and np.isfinite(row.kendall_ci_high_both)


def _segment_study(tmp_path):
    """6 conditions rated on 4 segments: on g0..g2 the ratings follow the metric, on g3 they run against it."""
    rng = np.random.default_rng(2)
    conds = [f"S{i}" for i in range(6)]
    rows, seq = [], []
    for seg in range(4):
        sign = -1 if seg == 3 else 1
        for i, c in enumerate(conds):
            seq.append(dict(condition=c, sequence=f"g{seg}", metric="m", value=float(i) + 0.1 * seg, unit=""))
            for p in range(5):
                rows.append(dict(study="s", participant=f"p{p}", session=f"p{p}", session_status="finished",
                                 page=f"p{p}-{seg}", page_type="mushra", question="hl", condition=c, condition_a="",
                                 condition_b="", answer=str(int(50 + sign * 8 * i + rng.integers(-2, 3))),
                                 is_training=0, is_attention_check=0, attention_passed="", segment=f"g{seg}"))
    pd.DataFrame(rows).to_csv(tmp_path / "results.csv", index=False)
    pd.DataFrame(seq).to_csv(tmp_path / "per_sequence.csv", index=False)
    summary = pd.DataFrame({"condition": conds, "metric": "m", "value": np.arange(6.0)})
    summary.to_csv(tmp_path / "summary.csv", index=False)
    vals = pd.DataFrame(rows).assign(v=lambda d: d["answer"].astype(float)).groupby("condition")["v"]
    pd.DataFrame({"question": "hl", "condition": conds, "median": vals.median()[conds].to_numpy(),
                  "mean": vals.mean()[conds].to_numpy()}).to_csv(tmp_path / "human.csv", index=False)
    return rows, seq


def test_per_segment_correlations(tmp_path):
    from evalsuite.analysis.correlate.segments import human_by_segment, per_segment

    rows, seq = _segment_study(tmp_path)
    t = per_segment(pd.DataFrame(seq), human_by_segment(pd.DataFrame(rows).astype(str)), n_boot=200)
    by = t.set_index("segment")
    assert list(by.loc[["g0", "g1", "g2", "g3"], "spearman_rho"]) == [1.0, 1.0, 1.0, -1.0]
    assert by.loc["(mean)", "spearman_rho"] == pytest.approx(0.5) and by.loc["(mean)", "n"] == 4
    assert by.loc["(mean)", "spearman_ci_low"] <= 0.5 <= by.loc["(mean)", "spearman_ci_high"]


def test_cli_per_segment(tmp_path):
    _segment_study(tmp_path)
    r = CliRunner().invoke(main, ["correlate", str(tmp_path / "summary.csv"), str(tmp_path / "human.csv"),
                                  "--results", str(tmp_path / "results.csv"), "--per-segment",
                                  str(tmp_path / "per_sequence.csv"), "--no-figures", "--bootstrap", "100",
                                  "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    t = pd.read_csv(tmp_path / "c" / "correlations_per_segment.csv")
    assert set(t["segment"]) == {"g0", "g1", "g2", "g3", "(mean)"} and "mean rho 0.500 over 4 segments" in r.output
    r = CliRunner().invoke(main, ["correlate", str(tmp_path / "summary.csv"), str(tmp_path / "human.csv"),
                                  "--per-segment", str(tmp_path / "per_sequence.csv"), "-o", str(tmp_path / "d")])
    assert r.exit_code != 0 and "--per-segment needs --results" in r.output
