"""Inputs of ``evalsuite correlate``: metric scores and human measures as long tables.

Scores (:func:`read_scores`): ``summary.csv`` of ``evalsuite score`` (``condition, metric, value``, ...; the
contract in :mod:`evalsuite.contracts.summary`), any ``condition, metric, value`` CSV, or a plain
``condition, value`` CSV (one metric, named after the file unless ``metric=`` says otherwise).

Human measures (:func:`read_human`), recognised by their header:

=================  =====================================================  =====================
file               per question and condition                             measures
=================  =====================================================  =====================
``ratings.csv``    MUSHRA / 0-100 ratings of ``evalsuite analyze``        ``median``, ``mean``
``likert_means``   Likert scale means (the scale is the question)         ``mean``
``elo.csv``        Bradley-Terry on the Elo scale; ties-half win rate     ``elo``, ``win_rate``
``pairwise.csv``   win rate: (wins + ties / 2) / judgements over every    ``win_rate``
                   comparison except matched-vs-mismatched ones
plain CSV          ``condition, value`` (optional ``question``)           the file's stem
=================  =====================================================  =====================

Condition names stay text (``NA`` is the natural condition). Every problem is an
:class:`~evalsuite.errors.InputError` naming the file, the line, the column and what was expected.
"""
from __future__ import annotations

import csv
import math
import pathlib

import numpy as np
import pandas as pd

from evalsuite.analysis.pairwise import is_mismatch
from evalsuite.analysis.ranking import PLAIN_WEIGHTS, win_counts
from evalsuite.errors import InputError

__all__ = ["read_scores", "read_human", "HUMAN_MEASURES"]

HUMAN_MEASURES = {"ratings": ("median", "mean"), "likert_means": ("mean",), "elo": ("elo", "win_rate"),
                  "pairwise": ("win_rate",)}
SCORES_EXPECTED = ("expected the summary.csv of `evalsuite score` (condition, metric, value, ...), "
                   "a condition,metric,value CSV or a condition,value CSV")
HUMAN_EXPECTED = ("expected ratings.csv, likert_means.csv, elo.csv or pairwise.csv of `evalsuite analyze`, "
                  "or a condition,value CSV")


def _read_csv(path, expected: str) -> pd.DataFrame:
    """All cells as stripped text plus ``line`` (the 1-based file line of each record)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError(f"file not found ({expected})", path=path)
    records, lines = [], []
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh, strict=True)
            header = [c.strip() for c in next(reader, [])]
            if not any(header):
                raise InputError(f"empty file: {expected}", path=path, line=1)
            for row in reader:
                if not row or (len(row) == 1 and not row[0].strip()):
                    continue
                if len(row) != len(header):
                    raise InputError(f"row has {len(row)} fields but the header has {len(header)}; "
                                     "expected one value per column", path=path, line=reader.line_num)
                records.append([c.strip() for c in row])
                lines.append(reader.line_num)
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text ({exc.reason} at byte {exc.start}); {expected}", path=path) from None
    except csv.Error as exc:
        raise InputError(f"not a well-formed CSV ({exc}); {expected}", path=path) from None
    dupes = sorted({c for c in header if header.count(c) > 1})
    if dupes:
        raise InputError(f"duplicate column(s) in the header: {', '.join(dupes)}", path=path, line=1)
    if not records:
        raise InputError(f"no data rows after the header; {expected}", path=path)
    df = pd.DataFrame(records, columns=header, dtype=str).drop(columns=["line"], errors="ignore")
    df["line"] = lines
    df.attrs["path"] = str(path)
    return df


def _numbers(df: pd.DataFrame, col: str, path, *, empty_ok: bool = True) -> pd.Series:
    """Column ``col`` as floats: a number, or an empty cell (no value) when ``empty_ok``."""
    out = []
    for text, line in zip(df[col], df["line"]):
        if text == "" and empty_ok:
            out.append(math.nan)
            continue
        try:
            v = float(text)
        except ValueError:
            v = math.inf
        if math.isnan(v) and empty_ok:
            out.append(math.nan)
            continue
        if not math.isfinite(v):
            raise InputError(f"{text!r} is not a number; expected a finite number"
                             + (" or an empty cell (no value)" if empty_ok else ""), path=path, line=int(line),
                             field=col)
        out.append(v)
    return pd.Series(out, index=df.index, dtype=float)


def _nonempty(df: pd.DataFrame, col: str, path) -> None:
    bad = df[df[col] == ""]
    if not bad.empty:
        raise InputError("empty value; expected a condition name", path=path, line=int(bad["line"].iloc[0]),
                         field=col)


def _unique(df: pd.DataFrame, keys: list[str], path, what: str) -> None:
    dup = df[df.duplicated(keys, keep=False)]
    if not dup.empty:
        first = dup.iloc[0]
        other = dup[(dup[keys] == first[keys]).all(axis=1)]["line"].tolist()
        name = " / ".join(str(first[k]) for k in keys)
        raise InputError(f"{what} {name!r} appears twice (lines {', '.join(map(str, other))}); expected one row each",
                         path=path, line=int(other[1]), field=keys[-1])


def _require(df: pd.DataFrame, cols, path, expected: str) -> None:
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise InputError(f"missing column(s) {', '.join(missing)}; {expected}", path=path, line=1)


def read_scores(path, metric: str | None = None) -> pd.DataFrame:
    """Metric values: long table ``condition, metric, value, better, line`` (see the module docstring)."""
    df = _read_csv(path, SCORES_EXPECTED)
    _require(df, ("condition", "value"), path, SCORES_EXPECTED)
    plain = "metric" not in df.columns
    if plain:
        df["metric"] = metric or pathlib.Path(path).stem
    elif metric:
        df = df[df["metric"] == metric]
        if df.empty:
            raise InputError(f"no rows for metric {metric!r}", path=path, field="metric")
    _nonempty(df, "condition", path)
    bad = df[df["metric"] == ""]
    if not bad.empty:
        raise InputError("empty value; expected a metric name", path=path, line=int(bad["line"].iloc[0]),
                         field="metric")
    _unique(df, ["metric", "condition"], path, "metric / condition")
    out = pd.DataFrame({"condition": df["condition"], "metric": df["metric"],
                        "value": _numbers(df, "value", path),
                        "better": df["better"] if "better" in df.columns else "", "line": df["line"]})
    out = out.reset_index(drop=True)
    out.attrs.update(path=str(path), source="scores", plain=plain)
    return out


def detect_human(columns) -> str:
    """``ratings``, ``likert_means``, ``elo``, ``pairwise``, ``plain`` or ``results`` from a header."""
    cols = set(columns)
    if "page_type" in cols or "winner" in cols:
        return "results"
    if {"condition_a", "condition_b", "n_a", "n_b", "n_tie"} <= cols:
        return "pairwise"
    if {"condition", "elo"} <= cols:
        return "elo"
    if {"condition", "median", "mean"} <= cols:
        return "ratings"
    if {"scale", "condition", "mean"} <= cols:
        return "likert_means"
    if {"condition", "value"} <= cols:
        return "plain"
    return ""


def _win_rates(df: pd.DataFrame, path, suffix: str) -> pd.DataFrame:
    """Per question and condition of ``pairwise.csv``, the win rate of elo.csv's ``win_rate``: each row's counts
    as a plain win matrix (:data:`~evalsuite.analysis.ranking.PLAIN_WEIGHTS`: a win 1, a tie half each way),
    divided by :func:`~evalsuite.analysis.ranking.win_counts`; matched-vs-mismatched rows left out. ``line``: the
    first row that names the condition."""
    counts = {c: _numbers(df, c, path, empty_ok=False) for c in ("n_a", "n_b", "n_tie")}
    _, win, tie = PLAIN_WEIGHTS
    rows = []
    kept = df[~is_mismatch(df["condition_a"], df["condition_b"], suffix)]
    for question, g in kept.groupby("question", sort=True):
        conds = sorted(set(g["condition_a"]) | set(g["condition_b"]))
        idx = {c: i for i, c in enumerate(conds)}
        a, b = g["condition_a"].map(idx).to_numpy(), g["condition_b"].map(idx).to_numpy()
        na, nb, nt = (counts[c][g.index].to_numpy() for c in ("n_a", "n_b", "n_tie"))
        W = np.zeros((len(conds), len(conds)))
        np.add.at(W, (a, b), win * na + tie * nt)
        np.add.at(W, (b, a), win * nb + tie * nt)
        wins, judged = win_counts(W)
        first = pd.concat([g[["condition_a", "line"]].set_axis(["condition", "line"], axis=1),
                           g[["condition_b", "line"]].set_axis(["condition", "line"], axis=1)])
        line = first.groupby("condition")["line"].min()
        rows += [{"question": question, "measure": "win_rate", "condition": c,
                  "value": wins[i] / judged[i] if judged[i] else math.nan, "line": int(line[c])}
                 for i, c in enumerate(conds)]
    return pd.DataFrame(rows, columns=["question", "measure", "condition", "value", "line"])


def read_human(path, measures=None, questions=None, mismatch_suffix: str = ":mismatched") -> pd.DataFrame:
    """Human measures: long table ``question, measure, condition, value, line`` (module docstring).

    ``measures``/``questions``: keep only these (an unknown name is an error listing the file's).
    """
    df = _read_csv(path, HUMAN_EXPECTED)
    source = detect_human(df.columns)
    if source == "results":
        raise InputError("this is a study's results file: run `evalsuite analyze` on it and correlate with its "
                         "ratings.csv, elo.csv or pairwise.csv (pass this file as --results for the "
                         "participant bootstrap)", path=path, line=1)
    if not source:
        raise InputError(f"unrecognised header ({', '.join(c for c in df.columns if c != 'line')}); "
                         f"{HUMAN_EXPECTED}", path=path, line=1)
    if source == "likert_means":
        df = df.rename(columns={"scale": "question"})
    if "question" not in df.columns:
        df["question"] = ""
    if source == "pairwise":
        for col in ("condition_a", "condition_b"):
            _nonempty(df, col, path)
        long = _win_rates(df, path, mismatch_suffix)
    else:
        _nonempty(df, "condition", path)
        names = HUMAN_MEASURES.get(source, (pathlib.Path(path).stem,))
        cols = HUMAN_MEASURES.get(source, ("value",))
        _unique(df, ["question", "condition"], path, "question / condition")
        long = pd.concat([pd.DataFrame({"question": df["question"], "measure": name, "condition": df["condition"],
                                        "value": _numbers(df, col, path), "line": df["line"]})
                          for name, col in zip(names, cols)], ignore_index=True)
    long = _select(long, "measure", measures, path, source)
    long = _select(long, "question", questions, path, source)
    if long.empty:
        raise InputError("no human measure per condition in this file (only matched-vs-mismatched comparisons?)",
                         path=path)
    long = long.reset_index(drop=True)
    long.attrs.update(path=str(path), source=source)
    return long


def _select(long: pd.DataFrame, col: str, wanted, path, source: str) -> pd.DataFrame:
    if not wanted:
        return long
    wanted = [w for w in wanted if w]
    have = list(dict.fromkeys(long[col]))
    if col == "measure":
        have = list(dict.fromkeys(have + list(HUMAN_MEASURES.get(source, ()))))
    unknown = [w for w in wanted if w not in have]
    if unknown:
        raise InputError(f"no {col} {', '.join(map(repr, unknown))} in this {source} file; it has: "
                         f"{', '.join(have) or '(none)'}", path=path, field=col)
    return long[long[col].isin(wanted)]
