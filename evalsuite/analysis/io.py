"""Reading and validating study results: the long ``results.csv`` and the "battles" CSV.

Both readers return a :class:`pandas.DataFrame` in one internal long layout (the
``results.csv`` columns of ``docs/results_format.md`` plus ``line``, the 1-based line of
the row in the file, and ``value``, the numeric answer of rating pages). Every problem is
reported as :class:`~evalsuite.errors.InputError` naming the file, the line, the column and
the offending value, so a researcher can fix the CSV without reading a traceback.
"""
from __future__ import annotations

import csv
import os
import pathlib
from typing import NoReturn

import numpy as np
import pandas as pd

from evalsuite.analysis import csvtext, validate
from evalsuite.contracts import results as results_contract
from evalsuite.errors import InputError

RESULTS_COLUMNS = results_contract.COLUMNS
# Columns the analysis cannot do without; the others default to empty when absent.
RESULTS_REQUIRED = results_contract.REQUIRED
BATTLES_REQUIRED = ("participant", "item", "condition_a", "condition_b", "winner")
# The GENEA Leaderboard's own export uses these names; accepted as aliases.
BATTLES_ALIASES = {"user": "participant", "input_code": "item", "model_a": "condition_a",
                   "model_b": "condition_b"}

PAGE_TYPES = ("pairwise", "mushra", "likert")
SESSION_STATUSES = ("finished", "failed", "incomplete")
PAIRWISE_ANSWERS = ("a", "b", "tie")
STRENGTHS = ("", "weak", "strong")
ROLES = ("", "reference", "anchor")


def _fail(message, path, line=None, field=None) -> NoReturn:
    raise InputError(message, path=path, line=line, field=field)


def _read_table(path) -> pd.DataFrame:
    path = pathlib.Path(path)
    if not path.is_file():
        _fail("file not found (expected a results.csv or battles CSV)", path)
    return csvtext.read_cells(path)


def detect_format(path) -> str:
    """Return ``"results"`` or ``"battles"`` from the CSV header of ``path``."""
    path = pathlib.Path(path)
    if not path.is_file():
        _fail("file not found (expected a results.csv or battles CSV)", path)
    with open(path, newline="", encoding="utf-8", errors="replace") as fh:
        header = next(csv.reader(fh), [])
    cols = {c.strip() for c in header}
    if "page_type" in cols:
        return "results"
    if "winner" in cols:
        return "battles"
    _fail("unrecognised header: a results.csv has a 'page_type' column, a battles CSV a "
          f"'winner' column; got: {', '.join(sorted(cols)) or '(empty)'}", path, line=1)


def read_any(path, study: str | None = None) -> pd.DataFrame:
    """Read ``path`` as results.csv or battles CSV, whichever its header says."""
    if detect_format(path) == "battles":
        return read_battles(path)
    return read_results(path, study=study)


def _check_allowed(df, mask, col, allowed, path, what=None):
    bad = mask & ~df[col].isin(allowed)
    if bad.any():
        row = df[bad].iloc[0]
        shown = ", ".join(repr(a) for a in allowed if a != "") or "(empty)"
        extra = " or empty" if "" in allowed else ""
        _fail(f"unknown value {row[col][:60]!r}{' for ' + what if what else ''}; expected one of "
              f"{shown}{extra}", path, line=int(row["line"]), field=col)


def _check_nonempty(df, mask, col, path, what):
    bad = mask & (df[col] == "")
    if bad.any():
        row = df[bad].iloc[0]
        _fail(f"empty value; {what}", path, line=int(row["line"]), field=col)


def read_results(path, study: str | None = None) -> pd.DataFrame:
    """Read and validate a ``results.csv`` (format: ``docs/results_format.md``).

    Parameters
    ----------
    path : path of the CSV.
    study : keep only this study id. Without it, a file holding several studies is an
        error (mixing studies would silently pool unrelated judgements).

    Returns a DataFrame with all results columns (absent optional ones filled with ""),
    ``line`` (1-based file line), ``value`` (float answer of mushra/likert rows, NaN
    otherwise) and the flags ``is_training``/``is_attention_check`` as int.
    """
    df = _read_table(path)
    missing = [c for c in RESULTS_REQUIRED if c not in df.columns]
    if missing:
        _fail(f"missing required column(s): {', '.join(missing)} "
              "(see docs/results_format.md)", path, line=1)
    for col in RESULTS_COLUMNS:
        if col not in df.columns:
            df[col] = ""
    everything = pd.Series(True, index=df.index)

    _check_nonempty(df, everything, "study", path, "every row needs its study id")
    studies = list(dict.fromkeys(df["study"]))
    if study is not None:
        if study not in studies:
            _fail(f"study {study!r} not in the file; it holds: {', '.join(studies)}", path,
                  field="study")
        df = df[df["study"] == study].copy()
    elif len(studies) > 1:
        first_other = df[df["study"] != studies[0]].iloc[0]
        _fail(f"mixed studies: {', '.join(repr(s) for s in studies)} (first row of "
              f"{first_other['study']!r} here); analyse one at a time with --study",
              path, line=int(first_other["line"]), field="study")

    _check_nonempty(df, everything.loc[df.index], "participant", path,
                    "every row needs a participant id")
    _check_nonempty(df, everything.loc[df.index], "session", path,
                    "every row needs a session id")
    _check_nonempty(df, everything.loc[df.index], "question", path,
                    "every row needs a question id")
    all_rows = everything.loc[df.index]
    _check_allowed(df, all_rows, "session_status", SESSION_STATUSES, path)
    _check_allowed(df, all_rows, "page_type", PAGE_TYPES, path)
    for flag in ("is_training", "is_attention_check"):
        _check_allowed(df, all_rows, flag, ("0", "1"), path)
    _check_allowed(df, all_rows, "attention_passed", ("0", "1", ""), path)
    _check_allowed(df, all_rows, "playback_implausible", ("0", "1", ""), path)
    validate.normalise_times(df, path)

    # One session belongs to one participant: otherwise exclusions per participant break.
    owners = df.groupby("session")["participant"].nunique()
    if (owners > 1).any():
        sess = owners[owners > 1].index[0]
        rows = df[df["session"] == sess]
        first = rows["participant"].iloc[0]
        other = rows[rows["participant"] != first].iloc[0]
        _fail(f"session {sess!r} belongs to participant {first!r} on earlier rows but to "
              f"{other['participant']!r} here", path, line=int(other["line"]), field="participant")

    is_check = df["is_attention_check"] == "1"
    checks_unknown = is_check & (df["attention_passed"] == "") & (df["attention_expected"] == "")
    if checks_unknown.any():
        row = df[checks_unknown].iloc[0]
        _fail("attention-check row without outcome: fill attention_passed (0/1) or "
              "attention_expected", path, line=int(row["line"]), field="attention_passed")

    # Judgement rows (not attention checks) must hold a usable answer for their page type.
    judged = ~is_check
    pw = judged & (df["page_type"] == "pairwise")
    mu = judged & (df["page_type"] == "mushra")
    lk = judged & (df["page_type"] == "likert")
    _check_nonempty(df, pw, "condition_a", path, "pairwise rows name the condition shown as A")
    _check_nonempty(df, pw, "condition_b", path, "pairwise rows name the condition shown as B")
    same = pw & (df["condition_a"] == df["condition_b"])
    if same.any():
        row = df[same].iloc[0]
        _fail(f"condition_a and condition_b are both {row['condition_a']!r}; a pairwise row "
              "compares two different conditions (name the mismatched stimulus e.g. "
              f"'{row['condition_a']}:mismatched')", path, line=int(row["line"]), field="condition_b")
    _check_allowed(df, pw, "answer", PAIRWISE_ANSWERS, path, "a pairwise answer")
    _check_allowed(df, pw, "strength", STRENGTHS, path)
    tie_strength = pw & (df["answer"] == "tie") & (df["strength"] != "")
    if tie_strength.any():
        row = df[tie_strength].iloc[0]
        _fail(f"strength {row['strength']!r} given for a tie; ties have no strength", path,
              line=int(row["line"]), field="strength")
    _check_nonempty(df, mu | lk, "condition", path, "rating rows (mushra, likert) name the rated condition")
    _check_allowed(df, mu, "role", ROLES, path)
    validate.check_numbers(df, path, mu, lk)
    value = pd.to_numeric(df["answer"].where(mu | lk), errors="coerce")
    bad_mu = mu & ~((value >= 0) & (value <= 100))
    if bad_mu.any():
        row = df[bad_mu].iloc[0]
        _fail(f"invalid rating {row['answer']!r}; expected a number in 0..100", path,
              line=int(row["line"]), field="answer")
    bad_lk = lk & ~((value >= 1) & (value == np.floor(value)))
    if bad_lk.any():
        row = df[bad_lk].iloc[0]
        _fail(f"invalid Likert answer {row['answer']!r}; expected an integer 1..k", path,
              line=int(row["line"]), field="answer")
    validate.check_likert_points(df, lk, value, path)
    _check_nonempty(df, lk, "scale", path, "likert rows name the scale the statement belongs to")
    # A statement belongs to one scale; a statement listed under two scales is a typo.
    lk_rows = df[lk]
    scales_per_q = lk_rows.groupby("question")["scale"].nunique()
    if (scales_per_q > 1).any():
        q = scales_per_q[scales_per_q > 1].index[0]
        rows = lk_rows[lk_rows["question"] == q]
        other = rows[rows["scale"] != rows["scale"].iloc[0]].iloc[0]
        _fail(f"statement {q!r} is in scale {rows['scale'].iloc[0]!r} on earlier rows but in "
              f"{other['scale']!r} here", path, line=int(other["line"]), field="scale")

    validate.check_sizes(df, path)
    df = df.copy()
    df["value"] = value.where(mu | lk)
    df, excluded = validate.duplicate_rows(df, path)
    df["is_training"] = df["is_training"].astype(int)
    df["is_attention_check"] = df["is_attention_check"].astype(int)
    df.attrs["source"] = os.fspath(path)
    df.attrs["format"] = "results"
    df.attrs["study"] = studies[0] if study is None else study
    # (line, reason, detail) of rows excluded by the reader; pandas deep-copies attrs on every operation, so
    # they are held in a tuple that is its own deep copy (20,000 repeated rows made the analysis hang).
    df.attrs["rows_excluded"] = validate.Frozen(excluded.itertuples(index=False, name=None))
    return df.reset_index(drop=True)


def read_battles(path) -> pd.DataFrame:
    """Read a battles CSV (``participant, item, condition_a, condition_b, winner[, strength]``).

    The GENEA Leaderboard export names (``user, input_code, model_a, model_b`` with winner
    ``model_a``/``model_b``/``tie`` and a boolean ``is_strong``) are accepted as aliases. An
    optional ``question`` column splits the battles by question (default ``preference``).
    The result uses the results.csv layout: every battle is a finished, non-training
    pairwise judgement.
    """
    df = _read_table(path)
    df = df.rename(columns={k: v for k, v in BATTLES_ALIASES.items()
                            if k in df.columns and v not in df.columns})
    missing = [c for c in BATTLES_REQUIRED if c not in df.columns]
    if missing:
        _fail(f"missing required column(s) of a battles CSV: {', '.join(missing)}", path, line=1)
    df["winner"] = df["winner"].replace({"model_a": "a", "model_b": "b"}).str.lower()
    if "strength" not in df.columns:
        if "is_strong" in df.columns:
            strong = df["is_strong"].str.lower()
            _check_allowed(df.assign(is_strong=strong), pd.Series(True, index=df.index),
                           "is_strong", ("true", "false", "1", "0", ""), path)
            df["strength"] = np.where(strong.isin(["true", "1"]), "strong", "weak")
            df.loc[df["winner"] == "tie", "strength"] = ""
        else:
            df["strength"] = ""
    everything = pd.Series(True, index=df.index)
    for col, what in (("participant", "every battle needs its participant"),
                      ("item", "every battle needs its item (speech segment)"),
                      ("condition_a", "every battle names condition A"),
                      ("condition_b", "every battle names condition B")):
        _check_nonempty(df, everything, col, path, what)
    same = df["condition_a"] == df["condition_b"]
    if same.any():
        row = df[same].iloc[0]
        _fail(f"condition_a and condition_b are both {row['condition_a']!r}", path,
              line=int(row["line"]), field="condition_b")
    _check_allowed(df, everything, "winner", PAIRWISE_ANSWERS, path)
    _check_allowed(df, everything, "strength", STRENGTHS, path)
    tie_strength = (df["winner"] == "tie") & (df["strength"] != "")
    if tie_strength.any():
        row = df[tie_strength].iloc[0]
        _fail(f"strength {row['strength']!r} given for a tie; ties have no strength", path,
              line=int(row["line"]), field="strength")
    out = pd.DataFrame({
        "line": df["line"],
        "study": "battles",
        "participant": df["participant"],
        "platform": "",
        # Battles carry no session: one pseudo-session per participant.
        "session": df["participant"],
        "session_status": "finished",
        "page": df["item"],
        "page_type": "pairwise",
        "trial": "",
        "question": df["question"] if "question" in df.columns else "preference",
        "scale": "",
        "segment": df["item"],
        "condition": "",
        "condition_a": df["condition_a"],
        "condition_b": df["condition_b"],
        "position_a": "",
        "answer": df["winner"],
        "strength": df["strength"],
        "role": "",
        "rt_ms": "",
        "is_training": 0,
        "is_attention_check": 0,
        "attention_expected": "",
        "attention_passed": "",
        "playback_implausible": "",
        "playback_reason": "",
        "shown_at": "",
        "answered_at": "",
        "value": np.nan,
    })
    if (out["question"] == "").any():
        row = out[out["question"] == ""].iloc[0]
        _fail("empty value; the optional question column must be filled when present", path,
              line=int(row["line"]), field="question")
    validate.check_sizes(out, path)
    out.attrs["source"] = os.fspath(path)
    out.attrs["format"] = "battles"
    out.attrs["study"] = "battles"
    return out.reset_index(drop=True)
