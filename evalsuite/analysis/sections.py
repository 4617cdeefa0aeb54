"""What the report says before the numbers: the settings that apply, and notes collapsed.

- :func:`settings_rows`: only the settings that change a number in *this* study's outputs
  (a MUSHRA-only study shows no pairwise tie policy and no bootstrap).
- :func:`collapse_notes`: the tables' per-row notes, with repeated notes (same text apart from
  the numbers in it) merged into one line with a count, e.g. 56 Wilcoxon comparisons that
  dropped zero differences become one line; every single note stays in its table's ``note``
  column.
- :func:`display_order`: HTML column order with the decisive columns (``better``,
  ``significant``, ``p_holm`` ...) right after the identifiers, so they are on screen at
  1300 px; the CSV files keep their documented order.
"""
from __future__ import annotations

import re
from collections import defaultdict

import pandas as pd

from evalsuite.analysis.exclusions import mushra_post_screening
from evalsuite.analysis.report import elo_method

IDENTIFIERS = ("question", "scale", "test", "condition", "condition_a", "condition_b", "condition_1",
               "condition_2", "role")
DECISIVE = ("better", "significant", "p_holm", "p_bonferroni", "elo", "pref_a", "pref_matched", "median",
            "ci_low", "ci_high", "median_diff", "pref_1", "pref_2", "mean", "p_value")
_NUM = re.compile(r"\d+(?:,\d{3})*(?:\.\d+)?")
SHOW_SUBJECTS = 3


def display_order(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with identifiers first, then the decisive columns, then the rest (note last)."""
    ids = [c for c in df.columns if c in IDENTIFIERS]
    dec = [c for c in DECISIVE if c in df.columns and c not in ids]
    rest = [c for c in df.columns if c not in ids and c not in dec and c != "note"]
    return df[ids + dec + rest + (["note"] if "note" in df.columns else [])]


def collapse_notes(items: list[tuple[str, str, str, str]]) -> list[str]:
    """``items`` = (what, subject, note, table). Notes of one ``what`` whose text differs only in
    its numbers become one line: the text with the varying numbers as ``N`` and their range, the
    count, and the first few subjects."""
    groups: dict[tuple, list] = defaultdict(list)
    for what, subject, note, table in items:
        groups[(what, _NUM.sub("#", note), table)].append((subject, note))
    out = []
    for (what, skeleton, table), members in groups.items():
        if len(members) == 1:
            subject, note = members[0]
            out.append(f"{what} {subject}: {note}" if subject else f"{what}: {note}")
            continue
        tokens = [_NUM.findall(note) for _, note in members]
        numbers = [[float(x.replace(",", "")) for x in toks] for toks in tokens]
        parts = skeleton.split("#")
        text, ranges = parts[0], list[str]()
        for k, piece in enumerate(parts[1:]):
            vals = [nums[k] for nums in numbers]
            if min(vals) == max(vals):
                text += tokens[0][k]
            else:
                text += "N" if not ranges else f"N{len(ranges) + 1}"
                ranges.append(f"{'N' if not ranges else f'N{len(ranges) + 1}'} = {_num(min(vals))} to "
                              f"{_num(max(vals))}")
            text += piece
        subjects = [s for s, _ in members if s]
        eg = ", ".join(subjects[:SHOW_SUBJECTS]) + (", ..." if len(subjects) > SHOW_SUBJECTS else "")
        where = f"; each in the note column of {table}.csv" if table else ""
        rng = f" ({'; '.join(ranges)})" if ranges else ""
        out.append(f"{what}, {len(members)} times: {text}{rng} -- e.g. {eg}{where}")
    return out


def _num(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else f"{v:g}"


def settings_rows(opt, raw: pd.DataFrame, tables: dict, path_label: str) -> pd.DataFrame:
    """The report's Settings table: only the settings that apply to this study's analyses."""
    rows = [("input", path_label), ("study", raw.attrs.get("study"))]
    if opt.preset:
        rows.append(("preset", opt.preset))
    results = raw.attrs.get("format") == "results"
    has = {k: k in tables for k in ("pairwise", "mismatch", "mismatch_barnard", "elo", "ratings",
                                      "likert_means")}
    if has["pairwise"]:
        rows.append(("tie policy (pairwise)", opt.tie_policy))
        rows.append(("preference CI", f"{opt.ci_method}, {100 * (1 - opt.alpha):g}%"))
    if has["mismatch"]:
        rows.append(("tie policy (matched/mismatched)", opt.mismatch_tie_policy))
    if has["pairwise"] or has["ratings"] or has["mismatch_barnard"]:
        rows.append(("multiple comparisons", f"Holm-Bonferroni per {opt.holm_scope}, alpha = {opt.alpha:g}"))
    if has["likert_means"]:
        rows.append(("Likert post-hoc", f"Bonferroni, alpha = {opt.alpha:g}"))
    if has["ratings"]:
        rows.append(("Wilcoxon zero differences", opt.zero_method))
    if has["elo"]:
        rows.append(("Elo fit", f"{elo_method(opt.elo_prior)} (--elo-prior {opt.elo_prior:g})"))
        boot = "none" if opt.n_boot == 0 else (f"{opt.n_boot} participant resamples, seed {opt.seed}"
                                               + (", drawn as the GENEA Leaderboard draws them"
                                                  if opt.bootstrap_sampler == "leaderboard" else ""))
        rows.append(("bootstrap (Elo CIs)", boot))
    if results:
        if (raw["is_attention_check"] == 1).any():
            rows.append(("attention checks", "exclude on any failure" if opt.attention_fails == 1
                         else f"exclude at >= {opt.attention_fails} failures"))
        if (raw["page_type"] == "mushra").any() and (raw["role"] == "reference").any():
            n = int(mushra_post_screening(raw)["excluded"].sum())
            rows.append(("BS.1534-3 post-screening (preset mushra-itu)",
                         f"on: excludes {n} session(s)" if opt.mushra_screening else f"off (would exclude {n} session(s))"))
        if "playback_implausible" in raw.columns:
            flagged = raw.loc[raw["playback_implausible"].astype(str) == "1", "session"].nunique()
            rows.append(("implausible playback", (f"exclude at >= {opt.implausible_playback} flagged pages"
                                                  if opt.implausible_playback else "off")
                         + f" ({flagged} sessions flagged)"))
        if raw.groupby("participant")["session"].nunique().gt(1).any():
            rows.append(("duplicate participants", opt.duplicates))
        if (raw["session_status"] == "incomplete").any():
            rows.append(("incomplete sessions", "kept" if opt.keep_incomplete else "excluded"))
    return pd.DataFrame(rows, columns=["setting", "value"])
