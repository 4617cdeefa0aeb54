"""Exclusion rules: attention checks, training, incomplete/failed sessions, duplicates, BS.1534-3."""
import pandas as pd
import pytest

from evalsuite.analysis.exclusions import apply_exclusions, mushra_post_screening

BASE = {"study": "s", "platform": "anonymous", "session_status": "finished", "page_type": "pairwise",
        "question": "q", "scale": "", "segment": "g", "condition": "", "condition_a": "A", "condition_b": "B",
        "answer": "a", "strength": "", "role": "", "is_training": 0, "is_attention_check": 0,
        "attention_expected": "", "attention_passed": "", "shown_at": "", "value": float("nan")}


def session(part, sess, n=3, status="finished", failed_checks=0, passed_checks=0, training=1, shown_at=""):
    rows = []
    for i in range(training):
        rows.append({**BASE, "page": f"t{i}", "is_training": 1})
    for i in range(n):
        rows.append({**BASE, "page": f"p{i}"})
    for i in range(failed_checks):
        rows.append({**BASE, "page": f"cf{i}", "is_attention_check": 1, "attention_expected": "a",
                     "answer": "b", "attention_passed": "0" if i % 2 else ""})  # "" -> decided by answer
    for i in range(passed_checks):
        rows.append({**BASE, "page": f"cp{i}", "is_attention_check": 1, "attention_expected": "a",
                     "answer": "a", "attention_passed": "1"})
    for r in rows:
        r.update(participant=part, session=sess, session_status=status, shown_at=shown_at)
    return rows


def frame(*sessions):
    df = pd.DataFrame([r for s in sessions for r in s])
    df.insert(0, "line", range(2, len(df) + 2))
    return df


def test_attention_rule_default_two_and_any():
    df = frame(session("P1", "S1", failed_checks=1, passed_checks=1), session("P2", "S2", failed_checks=2),
               session("P3", "S3", passed_checks=2))
    r = apply_exclusions(df)
    assert list(r.table["session"]) == ["S2"]
    assert r.table["reason"].iloc[0] == "attention_checks"
    assert "failed 2 of 2" in r.table["detail"].iloc[0]
    strict = apply_exclusions(df, attention_fails=1)
    assert list(strict.table["session"]) == ["S1", "S2"]


def test_training_and_check_rows_removed_not_people():
    df = frame(session("P1", "S1", n=4, training=2, passed_checks=2))
    r = apply_exclusions(df)
    assert r.table.empty
    assert len(r.data) == 4
    assert (r.data["is_training"] == 0).all()
    assert (r.data["is_attention_check"] == 0).all()
    assert r.summary["training_rows_removed"] == 2
    assert r.summary["attention_check_rows_removed"] == 2


def test_incomplete_and_failed_sessions():
    df = frame(session("P1", "S1"), session("P2", "S2", status="incomplete"), session("P3", "S3", status="failed"))
    r = apply_exclusions(df)
    assert dict(zip(r.table["session"], r.table["reason"])) == {"S2": "session_incomplete", "S3": "session_failed"}
    keep = apply_exclusions(df, keep_incomplete=True)
    assert list(keep.table["session"]) == ["S3"]
    assert set(keep.data["session"]) == {"S1", "S2"}


def test_duplicate_participant_keep_first_by_time_or_drop_all():
    df = frame(session("P1", "S_late", shown_at="2026-01-02T10:00:00Z"),
               session("P1", "S_early", shown_at="2026-01-01T10:00:00Z"),
               session("P2", "S2", shown_at="2026-01-01T11:00:00Z"))
    r = apply_exclusions(df)
    assert list(r.table["session"]) == ["S_late"]
    assert r.table["reason"].iloc[0] == "duplicate_participant"
    assert "'S_early'" in r.table["detail"].iloc[0]
    allx = apply_exclusions(df, duplicates="drop-all")
    assert set(allx.table["session"]) == {"S_late", "S_early"}
    assert allx.summary["participants_included"] == 1


def mushra_session(part, ref_values):
    rows = []
    for i, v in enumerate(ref_values):
        for cond, role, val in (("REF", "reference", v), ("X", "", 50.0)):
            rows.append({**BASE, "participant": part, "session": "S" + part, "page": f"m{i}",
                         "page_type": "mushra", "condition": cond, "condition_a": "", "condition_b": "",
                         "answer": str(val), "role": role, "value": float(val)})
    return rows


def test_bs1534_post_screening_counts_items_not_single_ratings():
    ok_one_low = [85] + [100] * 9            # 10 % of items low -> kept
    bad_two_low = [85, 70] + [100] * 8       # 20 % -> excluded
    exactly_15 = [80, 80, 80] + [95] * 17    # 15 % is not "more than 15 %" -> kept
    boundary_90 = [90] * 10                  # 90 is not below 90 -> kept
    df = frame(mushra_session("A", ok_one_low), mushra_session("B", bad_two_low),
               mushra_session("C", exactly_15), mushra_session("D", boundary_90))
    s = mushra_post_screening(df).set_index("participant")
    assert s.loc["B", "excluded"]
    assert not s.loc[["A", "C", "D"], "excluded"].any()
    assert (s.loc["B", "n_low"], s.loc["B", "n_items"]) == (2, 10)
    r = apply_exclusions(df, mushra_screening=True)
    # pymushra drops everyone with any low reference rating (A, B and C); the rule drops only B.
    assert list(r.table["participant"]) == ["B"]
    assert r.table["reason"].iloc[0] == "mushra_post_screening"
    assert "2 of 10 items" in r.table["detail"].iloc[0]
    # Off by default (a listening-test rule; natural motion is no ceiling), counted either way.
    off = apply_exclusions(df)
    assert off.table.empty
    assert off.summary["mushra_screening_would_exclude"] == r.summary["mushra_screening_would_exclude"] == 1


def test_everyone_excluded_leaves_empty_data():
    df = frame(session("P1", "S1", status="failed"))
    r = apply_exclusions(df)
    assert r.data.empty
    assert r.summary["sessions_included"] == 0


def test_bad_options():
    df = frame(session("P1", "S1"))
    with pytest.raises(ValueError):
        apply_exclusions(df, attention_fails=0)
    with pytest.raises(ValueError):
        apply_exclusions(df, duplicates="newest")


def _flag(rows, pages):
    """Mark ``playback_implausible`` on the rows of the given pages (0 on the others)."""
    for r in rows:
        r["playback_implausible"] = "1" if r["page"] in pages else "0"
    return rows


def test_implausible_playback_rule_counts_pages_and_can_be_off():
    two_rows = session("P1", "S1", n=2) + [{**session("P1", "S1", n=1, training=0)[0], "question": "q2"}]
    df = frame(_flag(two_rows, {"p0"}),                        # one page, two rows of it flagged
               _flag(session("P2", "S2", n=3), {"p0", "p1", "t0"}),   # training pages count too
               _flag(session("P3", "S3", n=3), set()))
    r = apply_exclusions(df)
    assert list(r.table["session"]) == ["S1", "S2"]
    assert set(r.table["reason"]) == {"implausible_playback"}
    assert r.table["detail"].iloc[0].startswith("1 of 3 pages")
    assert r.table["detail"].iloc[1].startswith("3 of 4 pages")
    assert r.summary["sessions_with_implausible_playback"] == 2
    assert list(apply_exclusions(df, implausible_playback=2).table["session"]) == ["S2"]
    off = apply_exclusions(df, implausible_playback=0)
    assert off.table.empty
    assert off.summary["sessions_with_implausible_playback"] == 2       # still reported
    with pytest.raises(ValueError, match="implausible_playback"):
        apply_exclusions(df, implausible_playback=-1)


def test_implausible_playback_without_the_column_excludes_nobody():
    r = apply_exclusions(frame(session("P1", "S1")))
    assert r.table.empty
    assert r.summary["sessions_with_implausible_playback"] == 0
