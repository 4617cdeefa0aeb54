"""Reading results.csv / battles CSVs: bad files give precise errors (file, line, column, value)."""
import pandas as pd
import pytest

from evalsuite.analysis.io import detect_format, read_any, read_battles, read_results
from evalsuite.errors import InputError

HEADER = ("study,participant,platform,session,session_status,page,page_type,trial,question,scale,segment,"
          "condition,condition_a,condition_b,position_a,answer,strength,role,rt_ms,is_training,"
          "is_attention_check,attention_expected,attention_passed,shown_at,answered_at")
GOOD = [
    "s1,P1,prolific,S1,finished,p1,pairwise,0,hl,,seg1,,A,B,left,a,,,1200,0,0,,,2026-01-01T10:00:00Z,",
    "s1,P1,prolific,S1,finished,p2,pairwise,1,app,,seg1,,A,A:mismatched,right,b,strong,,900,0,0,,,,",
    "s1,P1,prolific,S1,finished,p3,mushra,2,hl_rating,,seg2,NA,,,0,95,,reference,,0,0,,,,",
    "s1,P1,prolific,S1,finished,p3,mushra,2,hl_rating,,seg2,A,,,1,62.5,,,,0,0,,,,",
    "s1,P1,prolific,S1,finished,p4,likert,3,nat1,naturalness,seg3,A,,,,5,,,,0,0,,,,",
    "s1,P1,prolific,S1,finished,p5,pairwise,4,hl,,seg4,,A,B,left,b,,,,0,1,b,1,,",
]


def write(tmp_path, lines, header=HEADER, name="results.csv"):
    p = tmp_path / name
    p.write_text("\n".join([header] + lines) + "\n", encoding="utf-8")
    return p


def replace(line, col, value, header=HEADER):
    cells = line.split(",")
    cells[header.split(",").index(col)] = value
    return ",".join(cells)


def err(tmp_path, lines, **kw):
    with pytest.raises(InputError) as info:
        read_results(write(tmp_path, lines, **kw))
    return info.value


def test_good_file_reads_with_lines_and_values(tmp_path):
    df = read_results(write(tmp_path, GOOD))
    assert len(df) == 6
    assert list(df["line"]) == [2, 3, 4, 5, 6, 7]
    assert df.loc[3, "value"] == 62.5
    assert pd.isna(df.loc[0, "value"])
    assert df.attrs["study"] == "s1"
    assert detect_format(write(tmp_path, GOOD)) == "results"


def test_extra_columns_ignored_and_na_stays_a_name(tmp_path):
    header = HEADER + ",comment"
    df = read_results(write(tmp_path, [g + ",x" for g in GOOD], header=header))
    assert "NA" in set(df["condition"])


def test_missing_column(tmp_path):
    header = HEADER.replace(",answer,", ",")
    lines = [",".join(c for i, c in enumerate(g.split(",")) if i != HEADER.split(",").index("answer")) for g in GOOD]
    e = err(tmp_path, lines, header=header)
    assert e.line == 1
    assert "missing required column(s): answer" in str(e)


def test_unknown_pairwise_answer_names_row_column_value(tmp_path):
    lines = GOOD.copy()
    lines[0] = replace(lines[0], "answer", "left")
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (2, "answer")
    assert "'left'" in str(e)
    assert "'a', 'b', 'tie'" in str(e)
    assert "results.csv:2: answer:" in str(e)


@pytest.mark.parametrize("row,col,value,expect", [
    (2, "answer", "101", "expected a number in 0..100"),
    (2, "answer", "abc", "expected a number in 0..100"),
    (4, "answer", "0", "expected an integer 1..k"),
    (4, "answer", "3.5", "expected an integer 1..k"),
    (0, "page_type", "ranking", "'pairwise', 'mushra', 'likert'"),
    (0, "session_status", "done", "'finished', 'failed', 'incomplete'"),
    (0, "is_training", "yes", "'0', '1'"),
    (1, "strength", "medium", "'weak', 'strong'"),
    (2, "role", "ref", "'reference', 'anchor'"),
    (0, "condition_b", "", "empty value"),
    (0, "condition_b", "A", "both 'A'"),
    (3, "condition", "", "empty value"),
    (4, "scale", "", "empty value"),
    (0, "trial", "-1", "expected an integer >= 0"),
    (0, "participant", "", "empty value"),
])
def test_bad_values(tmp_path, row, col, value, expect):
    lines = GOOD.copy()
    lines[row] = replace(lines[row], col, value)
    e = err(tmp_path, lines)
    assert e.line == row + 2
    assert e.field == col
    assert expect in str(e)
    if value:
        assert repr(value) in str(e)


def test_tie_with_strength(tmp_path):
    lines = GOOD.copy()
    lines[1] = replace(replace(lines[1], "answer", "tie"), "strength", "weak")
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (3, "strength")


def test_mixed_studies_and_study_selection(tmp_path):
    lines = GOOD + [replace(GOOD[0], "study", "s2").replace("S1", "S9")]
    e = err(tmp_path, lines)
    assert e.line == 8
    assert e.field == "study"
    assert "mixed studies" in str(e)
    assert "--study" in str(e)
    df = read_results(write(tmp_path, lines), study="s2")
    assert list(df["line"]) == [8]
    with pytest.raises(InputError, match="study 'nope' not in the file"):
        read_results(write(tmp_path, lines), study="nope")


def test_session_shared_by_two_participants(tmp_path):
    lines = GOOD.copy()
    lines[3] = replace(lines[3], "participant", "P2")
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (5, "participant")
    assert "'S1'" in str(e)


def test_attention_check_without_outcome(tmp_path):
    lines = GOOD.copy()
    lines[5] = replace(replace(lines[5], "attention_passed", ""), "attention_expected", "")
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (7, "attention_passed")


def test_statement_in_two_scales(tmp_path):
    lines = GOOD + [replace(replace(GOOD[4], "scale", "other"), "page", "p9")]
    e = err(tmp_path, lines)
    assert (e.line, e.field) == (8, "scale")


def test_unreadable_files(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        read_any(tmp_path / "nope.csv")
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(InputError, match="unrecognised header"):
        read_any(empty)
    only_header = write(tmp_path, [])
    with pytest.raises(InputError, match="no data rows"):
        read_results(only_header)
    latin = tmp_path / "latin.csv"
    latin.write_bytes((HEADER + "\n" + GOOD[0].replace("P1", "P\xe9")).encode("latin-1"))
    with pytest.raises(InputError, match="not UTF-8"):
        read_results(latin)
    ragged = write(tmp_path, [GOOD[0] + ",x,y,z"], name="ragged.csv")
    with pytest.raises(InputError, match="not a well-formed CSV"):
        read_results(ragged)


BATTLE_HEADER = "participant,item,condition_a,condition_b,winner,strength"


def test_battles_detected_and_converted(tmp_path):
    p = write(tmp_path, ["u1,clip1,A,B,a,strong", "u1,clip2,B,C,tie,", "u2,clip1,A,C,b,weak"],
              header=BATTLE_HEADER, name="battles.csv")
    assert detect_format(p) == "battles"
    df = read_any(p)
    assert set(df["page_type"]) == {"pairwise"}
    assert set(df["question"]) == {"preference"}
    assert list(df["answer"]) == ["a", "tie", "b"]
    assert list(df["strength"]) == ["strong", "", "weak"]


def test_battles_leaderboard_aliases(tmp_path):
    p = write(tmp_path, ["u1,c1,A,B,model_a,True", "u1,c2,A,B,tie,False", "u2,c1,A,B,model_b,False"],
              header="user,input_code,model_a,model_b,winner,is_strong", name="lb.csv")
    df = read_battles(p)
    assert list(df["answer"]) == ["a", "tie", "b"]
    assert list(df["strength"]) == ["strong", "", "weak"]


def test_battles_bad_winner(tmp_path):
    p = write(tmp_path, ["u1,clip1,A,B,a,", "u1,clip2,A,B,draw,"], header=BATTLE_HEADER, name="b.csv")
    with pytest.raises(InputError) as info:
        read_any(p)
    assert (info.value.line, info.value.field) == (3, "winner")
    assert "'draw'" in str(info.value)


def test_playback_implausible_column_is_optional_and_checked(tmp_path):
    header = HEADER + ",playback_implausible"
    lines = [line + (",1" if i == 0 else ",0" if i < 5 else ",") for i, line in enumerate(GOOD)]
    df = read_results(write(tmp_path, lines, header=header))
    assert list(df["playback_implausible"]) == ["1", "0", "0", "0", "0", ""]
    assert set(read_results(write(tmp_path, GOOD, name="old.csv"))["playback_implausible"]) == {""}
    lines[2] = lines[2][:-1] + "yes"
    e = err(tmp_path, lines, header=header)
    assert (e.line, e.field) == (4, "playback_implausible")
    assert "'yes'" in str(e)


def test_an_unterminated_quote_names_the_line_where_it_starts(tmp_path):
    # pandas' parser would raise "EOF inside string"; the reader says where the open quote is.
    lines = GOOD[:3] + [replace(GOOD[3], "question", '"hl_rating')] + GOOD[4:]
    e = err(tmp_path, lines)
    assert e.line == 5, str(e)
    assert "never closed" in str(e)


@pytest.mark.parametrize("quoted", [False, True], ids=["plain", "quoted-multiline"])
def test_a_field_over_the_csv_module_limit_is_refused_with_its_line(tmp_path, quoted):
    from evalsuite.analysis.csvtext import MAX_FIELD_CHARS

    giant = "x" * (MAX_FIELD_CHARS + 1)
    lines = list(GOOD)
    lines[2] = replace(GOOD[2], "strength", f'"{giant}"' if quoted else giant)
    if quoted:  # a quoted line break sends the file to the csv module's path
        lines[0] = replace(GOOD[0], "answered_at", '"2026-01-01T10:00:05Z\n"')
    e = err(tmp_path, lines)
    assert e.line == (5 if quoted else 4), str(e)
    assert f"{MAX_FIELD_CHARS:,}" in str(e)


def test_many_repeated_rows_are_counted_and_their_record_copies_for_free(tmp_path):
    import copy
    import time

    df = read_results(write(tmp_path, GOOD + [GOOD[0]] * 20_000))
    rows = df.attrs["rows_excluded"]
    assert len(rows) == 20_000
    assert {r[1] for r in rows} == {"duplicate_row"}
    # pandas deep-copies attrs on every operation: a plain tuple of 20,000 rows made the analysis hang.
    t0 = time.perf_counter()
    for _ in range(100):
        assert copy.deepcopy(rows) is rows
    frozen = time.perf_counter() - t0
    t0 = time.perf_counter()
    copy.deepcopy(tuple(rows))
    assert frozen < time.perf_counter() - t0


def test_more_conditions_or_questions_than_the_limit_are_refused(tmp_path):
    from evalsuite.analysis.validate import MAX_CONDITIONS, MAX_QUESTIONS

    many = [replace(replace(GOOD[0], "condition_a", f"C{i}"), "page", f"p{i}") for i in range(MAX_CONDITIONS + 1)]
    e = err(tmp_path, many)
    assert (e.field, e.line) == ("condition_a", MAX_CONDITIONS + 2), str(e)
    assert f"more than {MAX_CONDITIONS} distinct conditions" in str(e)
    many = [replace(replace(GOOD[0], "question", f"q{i}"), "page", f"p{i}") for i in range(MAX_QUESTIONS + 1)]
    e = err(tmp_path, many)
    assert (e.field, e.line) == ("question", MAX_QUESTIONS + 2), str(e)
    battles = "participant,item,condition_a,condition_b,winner"
    with pytest.raises(InputError, match=f"more than {MAX_CONDITIONS} distinct conditions"):
        read_battles(write(tmp_path, [f"P1,i{i},C{i},D{i},a" for i in range(60)], header=battles))


def test_a_long_bad_value_is_shown_cut_in_a_short_message(tmp_path):
    e = err(tmp_path, [replace(GOOD[0], "page_type", "p" * 5000)] + GOOD[1:])
    assert (e.line, e.field) == (2, "page_type")
    assert len(e.reason) < 300, e.reason
