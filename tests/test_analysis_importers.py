"""evalsuite.analysis.importers: each source's format read into a results.csv that `evalsuite analyze` reads."""
from __future__ import annotations

import json

import pandas as pd
import pytest
from click.testing import CliRunner

from evalsuite.analysis.importers import IMPORTERS, Importer, import_judgements, write_results
from evalsuite.analysis.importers.cli import import_judgements_command
from evalsuite.analysis.io import read_results
from evalsuite.errors import InputError


def _roundtrip(tmp_path, fmt, name, text, **kw):
    src = tmp_path / name
    src.write_text(text, encoding="utf-8")
    out = write_results(import_judgements(fmt, src, **kw), tmp_path / "results.csv")
    return read_results(out)


def test_battles_leaderboard_names(tmp_path):
    df = _roundtrip(tmp_path, "battles", "b.csv",
                    "user,input_code,model_a,model_b,winner,is_strong\n"
                    "u1,c1,SA,SB,model_a,true\nu1,c2,SB,SA,tie,false\nu2,c1,SA,SB,model_b,false\n")
    assert list(df["answer"]) == ["a", "tie", "b"]
    assert list(df["strength"]) == ["strong", "", "weak"]
    assert set(df["page_type"]) == {"pairwise"} and list(df["segment"]) == ["c1", "c2", "c1"]


def test_genea_ratings(tmp_path):
    df = _roundtrip(tmp_path, "genea-ratings", "hl.csv",
                    "rater,system,segment,rating\nr1,SA,s1,80\nr1,NA,s1,95.5\nr2,SA,s1,10\n", study="g23")
    assert list(df["value"]) == [80, 95.5, 10]
    assert list(df["condition"]) == ["SA", "NA", "SA"]
    assert set(df["question"]) == {"human-likeness"} and set(df["study"]) == {"g23"}
    assert df.loc[0, "page"] == df.loc[1, "page"] != df.loc[2, "page"]   # rated together on one screen
    df = _roundtrip(tmp_path, "genea-ratings", "q.csv", "rater,system,segment,rating,question\n"
                    "r1,SA,s1,80,appropriateness\nr1,SB,s1,20,\n")
    assert list(df["question"]) == ["appropriateness", "human-likeness"]     # an empty cell takes the default


def test_genea_ratings_errors(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("rater,system,segment,rating\nr1,SA,s1,101\n")
    with pytest.raises(InputError, match=r"bad.csv:2: rating: invalid rating '101'"):
        import_judgements("genea-ratings", bad)
    bad.write_text("rater,segment,rating\nr1,s1,50\n")
    with pytest.raises(InputError, match="no condition column: expected one of condition, system"):
        import_judgements("genea-ratings", bad)


def test_genea_pairwise_levels_words_and_mismatch(tmp_path):
    df = _roundtrip(tmp_path, "genea-pairwise", "app.csv",
                    "rater,segment,system_1,system_2,preference,mismatched\n"
                    "r1,s1,SA,SB,2,\nr1,s2,SA,SB,Right is slightly better,\nr2,s1,SA,SA,0,b\nr2,s2,SB,SB,-2,a\n",
                    question="appropriateness")
    assert list(df["answer"]) == ["a", "b", "tie", "b"]
    assert list(df["strength"]) == ["strong", "weak", "", "strong"]
    assert list(df["condition_b"])[2] == "SA:mismatched" and list(df["condition_a"])[3] == "SB:mismatched"
    assert set(df["question"]) == {"appropriateness"}
    bad = tmp_path / "bad.csv"
    bad.write_text("rater,segment,system_1,system_2,preference\nr1,s1,SA,SB,3\n")
    with pytest.raises(InputError, match="invalid preference '3'"):
        import_judgements("genea-pairwise", bad)


HEMVIP = [
    {"_id": "64b0", "userId": "u1", "testId": "genea2022_hl", "trials": [
        {"id": "seg1", "type": "video", "responses": [{"stimulus": "SA", "score": 70}, {"stimulus": "SB", "score": 20},
                                                       {"stimulus": "attn_check_55", "score": 55}]},
        {"id": "seg2", "type": "videopc", "responses": [{"stimulus": "SA", "score": -2}, {"stimulus": "SB", "score": 2}]},
        {"id": "seg3", "type": "videopc", "responses": [{"stimulus": "SA", "score": 99}, {"stimulus": "SB", "score": 99}]},
        {"id": "intro", "type": "generic"}]},
    {"sessionJSON": json.dumps({"participant": {"name": ["id"], "response": ["u2"]}, "trials": [
        {"id": "seg4", "type": "videopc", "responses": [{"stimulus": "SB", "score": False},
                                                        {"stimulus": "SA", "score": False}]}]})},
]


def test_hemvip_export(tmp_path):
    df = _roundtrip(tmp_path, "hemvip", "output.json", json.dumps(HEMVIP))
    mu = df[df["page_type"] == "mushra"]
    assert list(mu["condition"]) == ["SA", "SB"] and list(mu["value"]) == [70, 20]   # the check left out
    pw = df[df["page_type"] == "pairwise"]
    assert list(pw["participant"]) == ["u1", "u2"]          # the broken report (99) left out
    assert list(pw["answer"]) == ["b", "tie"] and list(pw["strength"]) == ["strong", ""]
    assert set(df["study"]) == {"genea2022_hl"}          # the export's testId


def test_hemvip_errors(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text(json.dumps([{"trials": [{"id": "p", "type": "video", "responses": [{"stimulus": "S", "score": 300}]}]}]))
    with pytest.raises(InputError, match="score 300 of 'S'; expected a number in 0..100"):
        import_judgements("hemvip", bad)
    bad.write_text(json.dumps({"pages": []}))
    with pytest.raises(InputError, match="no 'trials' list"):
        import_judgements("hemvip", bad)


def test_evalsuite_export_and_cli(tmp_path):
    first = _roundtrip(tmp_path, "genea-ratings", "hl.csv", "rater,system,segment,rating\nr1,SA,s1,80\nr1,SB,s1,20\n")
    again = tmp_path / "again.csv"
    res = CliRunner().invoke(import_judgements_command, ["evalsuite", str(tmp_path / "results.csv"), "-o", str(again),
                                                         "--question", "hl"])
    assert res.exit_code == 0, res.output
    assert "2 judgements (2 mushra) from 1 participants" in res.output
    df = read_results(again)
    assert list(df["value"]) == list(first["value"]) and set(df["question"]) == {"hl"}
    res = CliRunner().invoke(import_judgements_command, ["nope", str(again)])
    assert res.exit_code != 0 and "known: battles" in str(res.exception)


def test_registry_takes_a_plugin(tmp_path):
    def read(path, *, study=None, question=None):
        return import_judgements("genea-ratings", path, study=study, question=question)

    IMPORTERS.register("test-ratings", Importer("test-ratings", "ratings again", read))
    try:
        src = tmp_path / "r.csv"
        src.write_text("rater,system,segment,rating\nr1,SA,s1,80\n")
        assert list(import_judgements("test-ratings", src)["answer"]) == ["80"]
    finally:
        IMPORTERS.unregister("test-ratings")


def test_imported_ratings_go_through_analyze_and_correlate(tmp_path):
    from evalsuite.cli import main

    lines = ["rater,system,segment,rating"]
    for r in range(6):
        for s in range(3):
            for i, c in enumerate(["SA", "SB", "SC", "NA"]):
                lines.append(f"r{r},{c},seg{s},{min(100, 15 + 20 * i + (r + s) % 5)}")
    (tmp_path / "hl.csv").write_text("\n".join(lines) + "\n")
    run = CliRunner().invoke
    assert run(main, ["import-judgements", "genea-ratings", str(tmp_path / "hl.csv"), "-o",
                      str(tmp_path / "results.csv")]).exit_code == 0
    r = run(main, ["analyze", str(tmp_path / "results.csv"), "-o", str(tmp_path / "an")])
    assert r.exit_code == 0, r.output
    (tmp_path / "scores.csv").write_text("condition,value\nSA,4\nSB,3\nSC,2\nNA,1\n")
    r = run(main, ["correlate", str(tmp_path / "scores.csv"), str(tmp_path / "an" / "ratings.csv"), "--metric", "m",
                   "--results", str(tmp_path / "results.csv"), "--measure", "mean", "--bootstrap", "100",
                   "--no-figures", "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    row = pd.read_csv(tmp_path / "c" / "correlations.csv").iloc[0]
    assert row["spearman_rho"] == -1.0 and row["n"] == 4
    assert row["spearman_ci_low_both"] == -1.0 and -1.0 <= row["spearman_ci_high_both"] < 1   # systems+raters CI
