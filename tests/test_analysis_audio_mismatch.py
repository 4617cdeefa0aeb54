"""evalsuite.analysis.audio_mismatch: the Leaderboard's audio-mismatch design per system (share preferring the
video with its own speech, exact binomial test against 50 %, Clopper-Pearson CI, Holm, rank), against counts
and formulas written out here, and through `evalsuite analyze` (tables, ranking kept free of it, blinding)."""
from __future__ import annotations

import math

import pandas as pd
import pytest
from scipy import stats

from evalsuite.analysis.audio_mismatch import AUDIO_COLUMNS, audio_mismatch_tables
from evalsuite.analysis.blind import blind_codes
from evalsuite.analysis.pairwise import is_mismatch, pairwise_table
from evalsuite.analysis.pipeline import AnalysisOptions, analyze
from evalsuite.contracts.results import COLUMNS

# (system, matched wins, mismatched wins, ties) on question "alignment"
COUNTS = {"SYSA": (14, 4, 3), "SYSB": (9, 9, 2), "SYSC": (14, 4, 3), "GT": (19, 1, 0)}


def _judgements() -> pd.DataFrame:
    """Results rows: each system's matched clip (A) against its audio-mismatched clip (B), A shown left on
    even rows; plus a realism comparison between systems."""
    rows = []
    n = 0
    for system, (m, x, t) in COUNTS.items():
        for answer in ["a"] * m + ["b"] * x + ["tie"] * t:
            left = n % 2 == 0
            rows.append({"condition_a": system, "condition_b": f"{system}:audio_mismatched", "answer": answer,
                         "question": "alignment", "position_a": "left" if left else "right",
                         "participant": f"p{n % 6}", "session": f"s{n % 6}", "audio_a": "seg1",
                         "audio_b": "seg2"})
            n += 1
    for i in range(12):
        rows.append({"condition_a": "SYSA", "condition_b": "SYSB", "answer": "a" if i % 3 else "b",
                     "question": "realism", "position_a": "left", "participant": f"p{i % 6}", "session": f"s{i % 6}"})
    out = []
    for i, r in enumerate(rows):
        full = {c: "" for c in COLUMNS}
        full.update(study="align", platform="anonymous", session_status="finished", page=f"pg{i}",
                    page_type="pairwise", trial=i, segment="seg1", is_training=0, is_attention_check=0,
                    rt_ms=5000, **r)
        out.append(full)
    return pd.DataFrame(out, columns=list(COLUMNS))


def _split(m, x, t):
    half, odd = divmod(t, 2)
    return m + half + (odd if m < x else 0), m + x + t


def test_per_system_share_binomial_ci_holm_and_rank():
    pw = _judgements()
    per, between = audio_mismatch_tables(pairwise_table(pw), alpha=0.05)
    assert list(per.columns) == AUDIO_COLUMNS
    assert per["condition"].tolist() == ["GT", "SYSA", "SYSC", "SYSB"]          # ranked, ties by name
    assert per["rank"].tolist() == [1, 2, 2, 4]
    raw_p = {}
    for r in per.itertuples():
        m, x, t = COUNTS[r.condition]
        k, n = _split(m, x, t)
        assert (r.n_matched, r.n_mismatched, r.n_tie, r.n) == (m, x, t, m + x + t)
        assert r.pref_matched == pytest.approx(k / n)
        assert r.p_value == pytest.approx(stats.binomtest(k, n, 0.5).pvalue, rel=1e-12)
        lo = stats.beta.ppf(0.025, k, n - k + 1) if k else 0.0
        hi = stats.beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
        assert (r.ci_low, r.ci_high) == (pytest.approx(lo), pytest.approx(hi))
        raw_p[r.condition] = r.p_value
    # Holm over the four systems, by hand
    order = sorted(raw_p, key=raw_p.get)
    running, holm = 0.0, {}
    for i, c in enumerate(order):
        running = max(running, min(1.0, (4 - i) * raw_p[c]))
        holm[c] = running
    for r in per.itertuples():
        assert r.p_holm == pytest.approx(holm[r.condition]) and r.significant == (holm[r.condition] < 0.05)
    assert len(between) == 6 and set(between["condition_1"]) | set(between["condition_2"]) == set(COUNTS)


def test_leaderboard_win_rate_counts_strong_twice_and_ties_half():
    # SYSA: 3 strong + 2 weak matched, 1 strong + 1 weak mismatched, 2 ties (5-level)
    spec = ["a"] * 5 + ["b"] * 2 + ["tie"] * 2
    strength = ["strong"] * 3 + ["weak"] * 2 + ["strong", "weak"] + ["", ""]
    pw = pd.DataFrame({"question": "q", "condition_a": "SYSA", "condition_b": "SYSA:audio_mismatched", "answer": spec,
                       "strength": strength, "participant": [f"p{i}" for i in range(9)]})
    per, _ = audio_mismatch_tables(pairwise_table(pw))
    # written out as the Leaderboard's analysis sums it: wins 2 + 2*3 + 2/2, appearances 2 + 1 + 2*(3 + 1) + 2
    assert per["leaderboard_win_rate"].iloc[0] == pytest.approx((2 + 6 + 1) / (2 + 1 + 8 + 2))
    three = pw.assign(strength="")
    three.loc[three["answer"] == "tie", "strength"] = ""
    per3, _ = audio_mismatch_tables(pairwise_table(three))
    assert per3["leaderboard_win_rate"].iloc[0] == pytest.approx((5 + 1) / 9)


def test_no_audio_mismatch_comparisons_give_empty_tables():
    pw = _judgements()
    per, between = audio_mismatch_tables(pairwise_table(pw[pw["question"] == "realism"]))
    assert per.empty and list(per.columns) == AUDIO_COLUMNS and between.empty


def test_audio_mismatched_comparisons_are_not_system_comparisons():
    a = pd.Series(["X", "X:audio_mismatched", "X", "X"])
    b = pd.Series(["X:audio_mismatched", "X", "Y", "X:mismatched"])
    assert is_mismatch(a, b).tolist() == [True, True, False, True]
    assert is_mismatch(a, b, "").tolist() == [True, True, False, False]


def test_blind_codes_keep_the_audio_pairing():
    codes = blind_codes(["SYSA", "SYSA:audio_mismatched", "SYSB", "SYSB:mismatched"], "salt")
    assert codes["SYSA:audio_mismatched"] == codes["SYSA"] + ":audio_mismatched"
    assert codes["SYSB:mismatched"] == codes["SYSB"] + ":mismatched"
    assert sorted(v for k, v in codes.items() if ":" not in k) == ["B01", "B02"]


def test_analyze_writes_the_audio_mismatch_tables_and_ranks_only_systems(tmp_path):
    path = tmp_path / "results.csv"
    _judgements().to_csv(path, index=False)
    res = analyze(path, tmp_path / "out", AnalysisOptions(figures=False, n_boot=20), echo=lambda *a: None)
    for ext in ("csv", "md", "tex"):
        assert (tmp_path / "out" / f"audio_mismatch.{ext}").is_file()
    table = pd.read_csv(tmp_path / "out" / "audio_mismatch.csv", keep_default_na=False)
    assert dict(zip(table["condition"], table["n"])) == {c: sum(v) for c, v in COUNTS.items()}
    assert "audio_mismatch_barnard" in res.tables
    elo = res.tables["elo"]
    assert set(elo["condition"]) == {"SYSA", "SYSB"} and set(elo["question"]) == {"realism"}
    assert "Audio mismatch (speech-gesture alignment)" in (tmp_path / "out" / "report.html").read_text()
    assert "SYSA" in (tmp_path / "out" / "audio_mismatch.tex").read_text()
    assert not math.isnan(table["p_value"].iloc[0])
