"""Who is analysed: exclusion rules applied to a validated results table.

Rules (each can exclude a whole session; a session may collect several reasons):

- ``duplicate_participant``: the participant id has more than one session in the study.
  ``duplicates="keep-first"`` (default) keeps the earliest session (the only one taken
  while naive to the stimuli); ``"drop-all"`` excludes every session of that id.
- ``session_failed`` / ``session_incomplete``: ``session_status`` is not ``finished``
  (``keep_incomplete=True`` keeps incomplete sessions, never failed ones).
- ``attention_checks``: the session failed ``>= attention_fails`` attention checks
  (default 2, Prolific's rule and GENEA 2022; ``1`` = any failure, as the GENEA
  Leaderboard analysis does).
- ``mushra_post_screening`` (ITU-R BS.1534-3; off unless asked for, e.g. with the ``mushra-itu``
  preset): the hidden reference (``role == "reference"``) was rated below 90 on more than 15 % of
  the session's MUSHRA items (an item = one page x question holding a hidden reference). The rule
  counts items per assessor; it does not drop an assessor for a single low reference rating. It is
  a listening-test rule, where the hidden reference is the known ceiling; in gesture studies
  natural motion is not a ceiling and participants are not told it is there, so honest raters
  fail it. The summary says how many sessions it would exclude either way.
- ``implausible_playback``: at least ``implausible_playback`` pages of the session (default 1; 0 = off)
  are flagged ``playback_implausible`` by the study server (a video never fetched, or less time on the page
  than its clips last: the media were not really played, whatever the browser reported). Training and
  attention-check pages count too: the flag is about the participant, not the judgement.

Rows removed from every analysis without excluding anyone: training pages and the
attention-check trials themselves.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

EXCLUSION_COLUMNS = ["participant", "session", "reason", "detail"]


@dataclass
class ExclusionResult:
    """Outcome of :func:`apply_exclusions`.

    ``data``: rows to analyse (included sessions, no training rows, no attention checks).
    ``table``: one row per (session, reason) with a human-readable ``detail``.
    ``summary``: counts for the report (participants/sessions before and after, rows removed).
    """

    data: pd.DataFrame
    table: pd.DataFrame
    summary: dict = field(default_factory=dict)


def attention_outcomes(df: pd.DataFrame) -> pd.Series:
    """Per attention-check row: True when passed.

    ``attention_passed`` decides when filled; otherwise the answer is compared with
    ``attention_expected`` (exact string match).
    """
    checks = df[df["is_attention_check"] == 1]
    passed = checks["attention_passed"]
    by_answer = checks["answer"] == checks["attention_expected"]
    return pd.Series(np.where(passed == "", by_answer, passed == "1"), index=checks.index, dtype=bool)


def mushra_post_screening(df: pd.DataFrame, threshold: float = 90.0,
                          max_fraction: float = 0.15) -> pd.DataFrame:
    """BS.1534-3 post-screening of assessors on the hidden reference.

    For each session: ``n_items`` = MUSHRA items (page x question) with a hidden-reference
    rating, ``n_low`` = items where it was rated ``< threshold``; ``excluded`` when
    ``n_low / n_items > max_fraction`` (strictly greater, as the recommendation says
    "more than 15 %"). Training pages and attention checks are not items.
    Returns columns ``participant, session, n_items, n_low, fraction, excluded``.
    """
    ref = df[(df["page_type"] == "mushra") & (df["role"] == "reference")
             & (df["is_training"] == 0) & (df["is_attention_check"] == 0)]
    cols = ["participant", "session", "n_items", "n_low", "fraction", "excluded"]
    if ref.empty:
        return pd.DataFrame(columns=cols)
    # One judgement per item: if a page shows the reference twice, its lowest rating counts.
    per_item = ref.groupby(["participant", "session", "page", "question"], sort=False)["value"].min()
    low = (per_item < threshold).groupby(level=["participant", "session"], sort=False)
    out = pd.DataFrame({"n_items": low.size(), "n_low": low.sum().astype(int)}).reset_index()
    out["fraction"] = out["n_low"] / out["n_items"]
    out["excluded"] = out["fraction"] > max_fraction
    return out[cols]


def _session_order(df: pd.DataFrame) -> pd.DataFrame:
    first = df.groupby("session", sort=False).agg(participant=("participant", "first"),
                                                 first_line=("line", "min"))
    shown = df[df["shown_at"] != ""].groupby("session")["shown_at"].min()
    first["shown_at"] = shown.reindex(first.index).fillna("")
    # ISO 8601 UTC strings sort chronologically; sessions without timestamps fall back to
    # their position in the file.
    if (first["shown_at"] != "").all():
        first = first.sort_values(["shown_at", "first_line"])
    else:
        first = first.sort_values("first_line")
    return first.reset_index()


def apply_exclusions(df: pd.DataFrame, *, attention_fails: int = 2, keep_incomplete: bool = False,
                     duplicates: str = "keep-first", mushra_screening: bool = False,
                     reference_threshold: float = 90.0, reference_max_fraction: float = 0.15,
                     implausible_playback: int = 1) -> ExclusionResult:
    """Apply the exclusion rules (module docstring) and return the rows to analyse."""
    if attention_fails < 1:
        raise ValueError("attention_fails must be >= 1 (1 = exclude on any failed check)")
    if implausible_playback < 0:
        raise ValueError("implausible_playback must be >= 0 (0 = off)")
    if duplicates not in ("keep-first", "drop-all"):
        raise ValueError("duplicates must be 'keep-first' or 'drop-all'")
    records = []
    sessions = _session_order(df)

    # Duplicate participant ids.
    counts = sessions.groupby("participant", sort=False)["session"].transform("size")
    for _, s in sessions[counts > 1].iterrows():
        same = sessions[sessions["participant"] == s["participant"]]["session"].tolist()
        first = same[0]
        if duplicates == "drop-all":
            detail = f"participant id has {len(same)} sessions ({', '.join(same)}); all dropped"
        elif s["session"] == first:
            continue
        else:
            detail = f"participant id already counted with session {first!r}"
        records.append((s["participant"], s["session"], "duplicate_participant", detail))

    # Session status.
    status = df.groupby("session", sort=False).agg(participant=("participant", "first"),
                                                   status=("session_status", "first"),
                                                   n_status=("session_status", "nunique"))
    for sess, s in status.iterrows():
        st = s["status"]
        if s["n_status"] > 1:
            # Rows exported at different times may disagree; the worst status wins.
            vals = set(df.loc[df["session"] == sess, "session_status"])
            st = "failed" if "failed" in vals else "incomplete"
        if st == "failed":
            records.append((s["participant"], sess, "session_failed",
                            "session ended early (failed attention checks during the study)"))
        elif st == "incomplete" and not keep_incomplete:
            records.append((s["participant"], sess, "session_incomplete",
                            "session not finished"))

    # Attention checks.
    outcomes = attention_outcomes(df)
    checks = df.loc[outcomes.index, ["participant", "session"]].assign(failed=~outcomes)
    per_session = checks.groupby(["participant", "session"], sort=False)["failed"].agg(["sum", "size"])
    for (part, sess), row in per_session.iterrows():
        if row["sum"] >= attention_fails:
            records.append((part, sess, "attention_checks",
                            f"failed {int(row['sum'])} of {int(row['size'])} attention checks "
                            f"(limit: {attention_fails})"))

    # BS.1534-3 post-screening.
    screening = mushra_post_screening(df, reference_threshold, reference_max_fraction)
    if mushra_screening:
        for _, row in screening[screening["excluded"]].iterrows():
            records.append((row["participant"], row["session"], "mushra_post_screening",
                            f"hidden reference rated < {reference_threshold:g} on {row['n_low']} of "
                            f"{row['n_items']} items ({100 * row['fraction']:.0f}% > "
                            f"{100 * reference_max_fraction:g}%)"))

    # Playback the server found implausible (pages, not rows: a page has a row per question or slot).
    pb = df["playback_implausible"] if "playback_implausible" in df.columns else pd.Series("", index=df.index)
    flagged = df[pb == "1"].groupby(["participant", "session"], sort=False)["page"].nunique()
    judged = df[pb != ""].groupby("session")["page"].nunique()
    if implausible_playback:
        why = df["playback_reason"] if "playback_reason" in df.columns else pd.Series("", index=df.index)
        for (part, sess), n in flagged[flagged >= implausible_playback].items():
            said = [r for r in why[(pb == "1") & (df["session"] == sess)].astype(str).unique() if r]
            records.append((part, sess, "implausible_playback",
                            f"{n} of {judged[sess]} pages with media answered without fetching every video or "
                            f"faster than its clips last (limit: {implausible_playback})"
                            + (f", e.g. {said[0]}" if said else "")))

    table = pd.DataFrame(records, columns=EXCLUSION_COLUMNS)
    order = {s: i for i, s in enumerate(sessions["session"])}
    table = table.sort_values("session", key=lambda s: s.map(order), kind="stable").reset_index(drop=True)
    excluded = set(table["session"])
    keep_session = ~df["session"].isin(excluded)
    training = df["is_training"] == 1
    check_rows = df["is_attention_check"] == 1
    data = df[keep_session & ~training & ~check_rows].copy()
    data.attrs.update(df.attrs)
    summary = {
        "participants_total": int(df["participant"].nunique()),
        "sessions_total": int(df["session"].nunique()),
        "sessions_excluded": len(excluded),
        "sessions_included": int(df.loc[keep_session, "session"].nunique()),
        "participants_included": int(df.loc[keep_session, "participant"].nunique()),
        "training_rows_removed": int(training.sum()),
        "attention_check_rows_removed": int(check_rows.sum()),
        "rows_analysed": len(data),
        "reasons": table["reason"].value_counts().to_dict(),
        "attention_fails": attention_fails,
        "duplicates": duplicates,
        "keep_incomplete": keep_incomplete,
        "mushra_screening": mushra_screening,
        # How many sessions BS.1534-3 post-screening excludes (on) or would exclude (off).
        "mushra_screening_would_exclude": int(screening["excluded"].sum()),
        "implausible_playback": implausible_playback,
        "sessions_with_implausible_playback": int(flagged.index.get_level_values("session").nunique()),
    }
    return ExclusionResult(data=data.reset_index(drop=True), table=table, summary=summary)
