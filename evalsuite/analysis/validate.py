"""Checks of a results.csv beyond its column sets (``docs/results_format.md``, "What the reader
refuses or excludes").

Refused (one-line :class:`~evalsuite.errors.InputError` naming file, line, column and what was
expected), because the file is corrupt or was not written as the format says and no analysis
of it can be trusted:

- control characters (NUL and the other C0 controls except tab, and DEL) in any field;
- numbers in other spellings than plain decimal digits: ``trial`` and ``rt_ms`` are whole
  numbers (``rt_ms`` at most :data:`MAX_RT_MS`, about 115 days), MUSHRA ratings ``0..100`` as
  digits with an optional decimal part, Likert answers whole numbers; ``1e308``, ``inf``,
  ``nan``, ``+5``, ``1_0`` and non-ASCII digits are refused;
- a Likert answer outside its scale: above the ``points`` column when the file has one, and
  above :data:`MAX_LIKERT_POINTS` (the largest scale the study app offers) in any case;
- ``shown_at`` / ``answered_at`` that are not ISO 8601 times (empty is allowed); valid ones are
  rewritten as UTC ``YYYY-MM-DDTHH:MM:SS.ffffffZ`` so that sorting them as text is chronological;
- two rows for the same judgement (same session, page, question, condition or pair, MUSHRA
  slot) with different answers: which one the participant gave cannot be known.

- more than :data:`MAX_CONDITIONS` distinct conditions or :data:`MAX_QUESTIONS` distinct questions (real
  studies have a few dozen at most; the tests run on every pair of conditions, so far more would take
  hours), refused before any statistic with the row where the limit is passed;

Excluded and counted (the report says how many, ``rows_excluded.csv`` lists them): exact
repeats of a judgement row (same judgement, same answer), as when an export is appended twice.
"""
from __future__ import annotations

import re
from typing import NoReturn

import numpy as np
import pandas as pd

from evalsuite.errors import InputError

CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")
MAX_RT_MS = 10_000_000_000
MAX_LIKERT_POINTS = 11
MAX_CONDITIONS = 100
MAX_QUESTIONS = 200
DIGITS = r"[0-9]+"
DECIMAL = r"[0-9]+(?:\.[0-9]+)?"
JUDGEMENT_KEY = ["session", "page", "question", "condition", "pair", "position_a"]
EXCLUDED_COLUMNS = ["line", "reason", "detail"]


class Frozen(tuple):
    """A tuple of immutable rows that ``copy.deepcopy`` returns as it is: pandas deep-copies a DataFrame's
    ``attrs`` on every operation, which for thousands of rows costs more than the analysis."""

    def __deepcopy__(self, memo) -> Frozen:
        return self


def _fail(message, path, line=None, field=None) -> NoReturn:
    raise InputError(message, path=path, line=line, field=field)


def check_control_characters(text: str, path) -> None:
    """Refuse control characters anywhere in the file's text (line and column of the first)."""
    m = CONTROL.search(text)
    if m is None:
        return
    line = text.count("\n", 0, m.start()) + 1
    start = text.rfind("\n", 0, m.start()) + 1
    header = text[:text.find("\n")].split(",") if "\n" in text else []
    field = None
    if line > 1 and header:
        # The column of the character: count the commas before it on its line (good enough to
        # point at it; quoted commas are rare in results files).
        k = text.count(",", start, m.start())
        field = header[k].strip() if k < len(header) else None
    _fail(f"control character U+{ord(m.group()):04X} in the data; a results file holds text only "
          "(a NUL usually means a truncated or binary file)", path, line=line, field=field)


def check_spelling(df: pd.DataFrame, mask, col: str, pattern: str, path, expected: str) -> None:
    """Refuse values of ``col`` (rows in ``mask``, non-empty) that do not match ``pattern``."""
    vals = df.loc[mask, col]
    uniq = pd.unique(vals)                            # each distinct spelling checked once
    rx = re.compile(pattern)
    wrong = {u for u in uniq if u != "" and not rx.fullmatch(u)}
    if wrong:
        bad = vals.isin(wrong)
        idx = bad[bad].index[0]
        _fail(f"invalid value {df.at[idx, col][:60]!r}; expected {expected}", path, line=int(df.at[idx, "line"]),
              field=col)


def check_numbers(df: pd.DataFrame, path, mushra, likert) -> None:
    """Plain-digit spellings and ranges of trial, rt_ms, MUSHRA and Likert answers."""
    every = pd.Series(True, index=df.index)
    check_spelling(df, every, "trial", DIGITS, path, "an integer >= 0 written in digits")
    check_spelling(df, every, "rt_ms", DIGITS, path,
                   f"a whole number of milliseconds 0..{MAX_RT_MS} written in digits")
    rt = pd.to_numeric(df["rt_ms"].where(df["rt_ms"] != ""), errors="coerce")
    if (rt > MAX_RT_MS).any():
        idx = rt[rt > MAX_RT_MS].index[0]
        _fail(f"invalid value {df.at[idx, 'rt_ms']!r}; expected a response time 0..{MAX_RT_MS} ms (about "
              "115 days)", path, line=int(df.at[idx, "line"]), field="rt_ms")
    check_spelling(df, mushra & (df["answer"] != ""), "answer", DECIMAL, path,
                   "a number in 0..100 (a MUSHRA rating) written in digits, e.g. 73 or 72.5")
    check_spelling(df, likert & (df["answer"] != ""), "answer", DIGITS, path,
                   "an integer 1..k (a Likert answer) written in digits")


def check_likert_points(df: pd.DataFrame, likert, value, path) -> None:
    """A Likert answer must lie on its scale: ``1..points`` (``points`` column, optional) and never
    above :data:`MAX_LIKERT_POINTS`."""
    points = None
    if "points" in df.columns:
        has = likert & (df["points"] != "")
        check_spelling(df, has, "points", DIGITS, path, f"the number of scale points, 2..{MAX_LIKERT_POINTS}")
        points = pd.to_numeric(df["points"].where(has), errors="coerce")
        bad = has & ~points.between(2, MAX_LIKERT_POINTS)
        if bad.any():
            idx = bad[bad].index[0]
            _fail(f"invalid value {df.at[idx, 'points']!r}; expected 2..{MAX_LIKERT_POINTS} scale points", path,
                  line=int(df.at[idx, "line"]), field="points")
        over = has & (value > points)
        if over.any():
            idx = over[over].index[0]
            _fail(f"Likert answer {df.at[idx, 'answer']!r} is outside its {int(points[idx])}-point scale "
                  f"(expected 1..{int(points[idx])})", path, line=int(df.at[idx, "line"]), field="answer")
    over = likert & (value > MAX_LIKERT_POINTS)
    if over.any():
        idx = over[over].index[0]
        _fail(f"Likert answer {df.at[idx, 'answer']!r} is outside any Likert scale (expected 1..k with k <= "
              f"{MAX_LIKERT_POINTS}; a 'points' column checks each scale exactly)", path,
              line=int(df.at[idx, "line"]), field="answer")


def normalise_times(df: pd.DataFrame, path) -> None:
    """Refuse ``shown_at`` / ``answered_at`` that are not ISO 8601; rewrite valid ones in UTC."""
    for col in ("shown_at", "answered_at"):
        vals = df[col]
        uniq = pd.unique(vals[vals != ""])
        if len(uniq) == 0:
            continue
        ok = pd.Series(uniq).str.match(r"[0-9]{4}-[0-9]{2}-[0-9]{2}[T ][0-9]{2}:[0-9]{2}")
        parsed = pd.to_datetime(pd.Series(uniq).where(ok), format="ISO8601", utc=True, errors="coerce")
        if parsed.isna().any():
            bad = uniq[int(np.flatnonzero(parsed.isna().to_numpy())[0])]
            first = df.index[vals == bad][0]
            _fail(f"invalid time {bad[:60]!r}; expected an ISO 8601 time such as 2026-03-02T09:00:00Z (UTC when "
                  "no offset is given) or an empty cell", path, line=int(df.at[first, "line"]), field=col)
        stamps = np.datetime_as_string(parsed.dt.tz_localize(None).to_numpy("datetime64[us]"), unit="us")
        canon = dict(zip(uniq, np.char.add(stamps, "Z").tolist()))
        canon[""] = ""
        df[col] = vals.map(canon)


def duplicate_rows(df: pd.DataFrame, path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Drop exact repeats of a judgement row (kept: the first); refuse conflicting repeats.

    Returns ``(rows kept, excluded)`` with ``excluded`` = :data:`EXCLUDED_COLUMNS`."""
    a, b = df["condition_a"], df["condition_b"]
    pair = np.where(a <= b, a + "\x1f" + b, b + "\x1f" + a)
    keyed = df.assign(pair=pair)
    dup = keyed.duplicated(JUDGEMENT_KEY, keep=False)
    if not dup.any():
        return df, pd.DataFrame(columns=EXCLUDED_COLUMNS)
    sub = keyed[dup]
    same = ["condition_a", "condition_b", "answer", "strength"]
    variants = sub.groupby(JUDGEMENT_KEY, sort=False)[same].nunique().max(axis=1)
    if (variants > 1).any():
        key = variants[variants > 1].index[0]
        rows = sub.set_index(JUDGEMENT_KEY).loc[[key]]
        first, other = rows.iloc[0], rows[(rows[same] != rows.iloc[0][same]).any(axis=1)].iloc[0]
        _fail(f"a second, different answer to the same judgement as line {int(first['line'])} (session "
              f"{key[0]!r}, page {key[1]!r}, question {key[2]!r}): {first['answer']!r} there, "
              f"{other['answer']!r} here; each judgement is answered once", path, line=int(other["line"]),
              field="answer")
    repeat = keyed.duplicated(JUDGEMENT_KEY, keep="first")
    first_line = sub.groupby(JUDGEMENT_KEY, sort=False)["line"].transform("min")
    excluded = pd.DataFrame({"line": df.loc[repeat, "line"].to_numpy(), "reason": "duplicate_row",
                             "detail": [f"repeats line {int(v)} (same session, page, question, condition and "
                                        "answer)" for v in first_line[repeat[dup]].to_numpy()]})
    return df[~repeat], excluded


def check_sizes(df: pd.DataFrame, path) -> None:
    """Refuse more than :data:`MAX_CONDITIONS` distinct conditions or :data:`MAX_QUESTIONS` distinct questions,
    naming a row that holds one beyond the limit."""
    names = pd.concat([df["condition"], df["condition_a"], df["condition_b"]], keys=["condition", "condition_a",
                                                                                   "condition_b"])
    names = names[names != ""]
    for values, limit, what in ((names, MAX_CONDITIONS, "conditions"), (df["question"], MAX_QUESTIONS, "questions")):
        uniq = pd.unique(values)
        if len(uniq) <= limit:
            continue
        over = values[values == uniq[limit]]
        col, idx = over.index[0] if isinstance(over.index, pd.MultiIndex) else ("question", over.index[0])
        _fail(f"more than {limit} distinct {what} ({uniq[limit][:60]!r} here is one of {len(uniq)}); expected at most "
              f"{limit} in one study (far above real studies; the tests run per question and per pair of conditions)",
              path, line=int(df.at[idx, "line"]), field=col)
