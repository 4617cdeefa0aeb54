"""results.csv rows that are invalid although every column holds an allowed kind of value: refused with
file, line and column, or (exact repeats) excluded and counted in the report."""
import json

import pandas as pd
import pytest
from click.testing import CliRunner

from evalsuite.analysis.io import read_results
from evalsuite.cli import main
from evalsuite.errors import InputError
from tests.test_analysis_io import GOOD, HEADER, replace, write


def err(tmp_path, lines, **kw):
    with pytest.raises(InputError) as info:
        read_results(write(tmp_path, lines, **kw))
    return info.value


@pytest.mark.parametrize("value", ["yesterday", "2026-13-45T99:00:00Z", "1700000000", "2026-01-01T10:00:00Zjunk",
                                   "0000-00-00"])
def test_garbage_shown_at_is_refused(tmp_path, value):
    lines = list(GOOD)
    lines[2] = replace(lines[2], "shown_at", value)
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (4, "shown_at")
    assert "ISO 8601" in str(e) and repr(value) in str(e)


def test_answered_at_checked_too_and_times_normalised_to_utc(tmp_path):
    lines = list(GOOD)
    lines[1] = replace(lines[1], "answered_at", "soon")
    assert err(tmp_path, lines).field == "answered_at"
    lines = list(GOOD)
    lines[0] = replace(lines[0], "shown_at", "2026-01-01T10:30:00+01:00")   # 09:30 UTC
    lines[1] = replace(lines[1], "shown_at", "2026-01-01T09:45:00Z")
    df = read_results(write(tmp_path, lines))
    assert df.loc[0, "shown_at"] == "2026-01-01T09:30:00.000000Z"
    assert df.loc[0, "shown_at"] < df.loc[1, "shown_at"]                  # text order = time order


@pytest.mark.parametrize("col,value", [("rt_ms", "1e308"), ("rt_ms", "inf"), ("rt_ms", "99999999999999"),
                                       ("rt_ms", "1_0"), ("rt_ms", "+5"), ("trial", "1e3"), ("rt_ms", "１２")])
def test_numbers_in_other_spellings_are_refused(tmp_path, col, value):
    lines = list(GOOD)
    lines[0] = replace(lines[0], col, value)
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (2, col)
    assert repr(value) in str(e)


@pytest.mark.parametrize("value", ["5e1", "nan", "0x10", " 1_0", "٥٠"])
def test_mushra_rating_spellings(tmp_path, value):
    lines = list(GOOD)
    lines[3] = replace(lines[3], "answer", value)
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (5, "answer")


def test_likert_answer_outside_its_scale(tmp_path):
    lines = list(GOOD)
    lines[4] = replace(lines[4], "answer", "99")
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (6, "answer")
    assert "outside any Likert scale" in str(e)
    # With the scale's size in a points column the check is exact: 8 on a 7-point scale.
    header = HEADER + ",points"
    lines = [g + ("," + ("7" if ",likert," in g else "")) for g in GOOD]
    lines[4] = replace(lines[4], "answer", "8", header=header)
    e = err(tmp_path, lines, header=header)
    assert (e.line, e.field) == (6, "answer")
    assert "outside its 7-point scale" in str(e)
    lines[4] = replace(lines[4], "answer", "7", header=header)
    assert read_results(write(tmp_path, lines, header=header)).loc[4, "value"] == 7


@pytest.mark.parametrize("char", ["\x00", "\x01", "\x1b", "\x7f"])
def test_control_characters_are_refused_with_line_and_column(tmp_path, char):
    lines = list(GOOD)
    lines[1] = replace(lines[1], "segment", "seg" + char + "1")
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (3, "segment")
    assert f"U+{ord(char):04X}" in str(e)


def test_conflicting_duplicate_judgement_is_refused(tmp_path):
    lines = list(GOOD)
    lines.append(replace(lines[3], "answer", "20"))          # the same MUSHRA slot rated twice
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (8, "answer")
    assert "line 5" in str(e)
    lines = list(GOOD)
    flipped = replace(replace(replace(lines[0], "condition_a", "B"), "condition_b", "A"), "answer", "a")
    lines.append(flipped)                                      # the same pair on the same page, swapped
    assert err(tmp_path, lines).line == 8


def test_exact_duplicate_rows_are_excluded_and_reported(tmp_path):
    from evalsuite.analysis.demo import sample_results_path

    src = pd.read_csv(sample_results_path(), dtype=str, keep_default_na=False)
    judged = src[(src["is_training"] == "0") & (src["page_type"] != "likert")]
    dup = pd.concat([src, judged.iloc[[3, 40, 41]]], ignore_index=True)
    dup.to_csv(tmp_path / "dup.csv", index=False)
    src.to_csv(tmp_path / "clean.csv", index=False)
    runs = {}
    for name in ("dup", "clean"):
        r = CliRunner().invoke(main, ["analyze", str(tmp_path / f"{name}.csv"), "-o", str(tmp_path / name),
                                      "--bootstrap", "20", "--no-figures"], catch_exceptions=False)
        assert r.exit_code == 0, r.output
        runs[name] = r.output
    assert "3 duplicate_row" in runs["dup"]
    excluded = pd.read_csv(tmp_path / "dup" / "rows_excluded.csv")
    assert list(excluded["line"]) == [len(src) + 2, len(src) + 3, len(src) + 4]
    assert (excluded["reason"] == "duplicate_row").all()
    assert json.loads((tmp_path / "dup" / "summary.json").read_text())["rows_excluded"] == {"duplicate_row": 3}
    assert "duplicate_row" in (tmp_path / "dup" / "report.html").read_text()
    for table in ("pairwise", "ratings_pairwise", "ratings"):
        pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "dup" / f"{table}.csv"),
                                      pd.read_csv(tmp_path / "clean" / f"{table}.csv"))


def test_cli_error_is_one_line_naming_file_line_and_column(tmp_path):
    lines = list(GOOD)
    lines[0] = replace(lines[0], "rt_ms", "1e308")
    r = CliRunner().invoke(main, ["analyze", str(write(tmp_path, lines)), "-o", str(tmp_path / "o")])
    assert r.exit_code != 0
    msg = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(msg) == 1 and "results.csv:2" in msg[0] and "rt_ms" in msg[0] and "Traceback" not in r.output


def test_fast_reader_keeps_file_lines_with_quotes_blank_lines_and_crlf(tmp_path):
    header = HEADER + ",comment"
    lines = [GOOD[0] + ',"a, b"', "", GOOD[1] + ',"say ""hi"""', "   ", GOOD[2] + ",plain"]
    df = read_results(write(tmp_path, lines, header=header))
    assert list(df["line"]) == [2, 4, 6]
    assert list(df["comment"]) == ["a, b", 'say "hi"', "plain"]
    multi = [GOOD[0] + ',"two\nlines"', GOOD[1] + ",x"]          # a quoted newline: the record-by-record path
    df = read_results(write(tmp_path, multi, header=header))
    assert list(df["line"]) == [3, 4]
    crlf = tmp_path / "crlf.csv"
    crlf.write_bytes(("\r\n".join([HEADER] + GOOD[:2]) + "\r\n").encode())
    df = read_results(crlf)
    assert list(df["line"]) == [2, 3] and df.loc[1, "answered_at"] == ""
    short = [GOOD[0], ",".join(GOOD[1].split(",")[:-1])]
    e = err(tmp_path, short)
    assert e.line == 3 and "24 fields but the header has 25" in str(e)
