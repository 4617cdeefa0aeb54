"""GENEA 2022/2023 released ratings as results.csv rows (formats: ``docs/human-data.md``).

``genea-ratings``: one 0-100 rating per row (rater, system, segment, rating; optional question and page) ->
``mushra`` rows, the question from a ``question`` column, else ``question=``, else ``human-likeness``. The
systems rated together on one screen share a page: the ``page`` column, else the rater and segment.

``genea-pairwise``: one 5-option preference per row (rater, segment, the two systems and the preference for
the first, -2..2 or the option's words, ``Left is clearly better`` ... ``Right is clearly better``) ->
``pairwise`` rows: ``a`` when the first is preferred, ``b`` the second, ``tie`` at 0; ``strong`` at |2|,
``weak`` at |1|. A ``mismatched`` column (``a``/``b``/empty) marks the side shown with another segment's
speech (GENEA 2023's appropriateness test): that side's condition gets evalsuite's ``:mismatched`` suffix.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from evalsuite.analysis.importers import Importer
from evalsuite.analysis.importers.common import fail, read_aliased, rows

RATER = ("participant", "rater", "rater_id", "user", "user_id", "userid", "prolific_id", "subject")
SEGMENT = ("segment", "segment_id", "clip", "clip_name", "item", "input_code", "stimulus")
QUESTION = ("question", "measure", "dimension")
OPTIONS = {"left is clearly better": 2, "left is slightly better": 1, "they are equal": 0,
           "right is slightly better": -1, "right is clearly better": -2}


def read_ratings(path, *, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    what = "a ratings CSV: rater, system, segment, rating"
    df = read_aliased(path, {"participant": RATER, "condition": ("condition", "system", "system_id", "model"),
                             "segment": SEGMENT,
                             "rating": ("rating", "score", "value", "answer", "human_likeness", "humanlikeness",
                                        "appropriateness"),
                             "question": QUESTION, "page": ("page", "page_id", "screen", "trial")},
                      ("participant", "condition", "segment", "rating"), what)
    value = pd.to_numeric(df["rating"], errors="coerce")
    bad = ~((value >= 0) & (value <= 100))
    if bad.any():
        row = df[bad].iloc[0]
        fail(f"invalid rating {row['rating']!r}; expected a number in 0..100", path, int(row["line"]), "rating")
    q = df["question"].replace("", question or "human-likeness") if "question" in df.columns else (
        question or "human-likeness")
    page = df["page"] if "page" in df.columns else df["participant"] + "/" + df["segment"]
    return rows(len(df), study or path.stem, participant=df["participant"].to_numpy(), page=page.to_numpy(),
                page_type="mushra",
                question=q.to_numpy() if isinstance(q, pd.Series) else q, segment=df["segment"].to_numpy(),
                condition=df["condition"].to_numpy(), answer=df["rating"].to_numpy())


def _preference(df: pd.DataFrame, path) -> np.ndarray:
    text = df["preference"].str.lower().str.replace("_", " ")
    words = text.map(OPTIONS)
    num = pd.to_numeric(df["preference"], errors="coerce")
    pref = words.where(words.notna(), num)
    bad = ~pref.isin([-2, -1, 0, 1, 2])
    if bad.any():
        row = df[bad].iloc[0]
        fail(f"invalid preference {row['preference']!r}; expected -2..2 (for the first system) or one of "
             f"{', '.join(repr(o) for o in OPTIONS)}", path, int(row["line"]), "preference")
    return pref.to_numpy(dtype=float)


def read_pairwise(path, *, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    what = "a pairwise CSV: rater, segment, system_a, system_b, preference"
    df = read_aliased(path, {"participant": RATER, "segment": SEGMENT,
                             "condition_a": ("condition_a", "system_a", "system_1", "system_left", "left", "model_a"),
                             "condition_b": ("condition_b", "system_b", "system_2", "system_right", "right", "model_b"),
                             "preference": ("preference", "rating", "score", "answer", "choice"),
                             "question": QUESTION, "mismatched": ("mismatched", "mismatched_side")},
                      ("participant", "segment", "condition_a", "condition_b", "preference"), what)
    pref = _preference(df, path)
    a, b = df["condition_a"].copy(), df["condition_b"].copy()
    if "mismatched" in df.columns:
        side = df["mismatched"].str.lower()
        bad = ~side.isin(["a", "b", ""])
        if bad.any():
            row = df[bad].iloc[0]
            fail(f"invalid side {row['mismatched']!r}; expected a, b or empty", path, int(row["line"]), "mismatched")
        a = a.where(side != "a", a + ":mismatched")
        b = b.where(side != "b", b + ":mismatched")
    same = a == b
    if same.any():
        row = df[same].iloc[0]
        fail(f"both systems are {a[same].iloc[0]!r}; a pairwise row compares two different stimuli (mark the "
             "mismatched one with a 'mismatched' column)", path, int(row["line"]), "condition_b")
    answer = np.where(pref > 0, "a", np.where(pref < 0, "b", "tie"))
    strength = np.where(np.abs(pref) == 2, "strong", np.where(np.abs(pref) == 1, "weak", ""))
    q = (df["question"].replace("", question or "preference").to_numpy() if "question" in df.columns
         else (question or "preference"))
    return rows(len(df), study or path.stem, participant=df["participant"].to_numpy(),
                page=(df["participant"] + "/" + df["segment"] + "/" + df.index.astype(str)).to_numpy(),
                page_type="pairwise", question=q, segment=df["segment"].to_numpy(), condition_a=a.to_numpy(),
                condition_b=b.to_numpy(), answer=answer, strength=strength)


RATINGS = Importer("genea-ratings", "GENEA 2022/2023 0-100 ratings per rater, system and segment", read_ratings)
PAIRWISE = Importer("genea-pairwise", "GENEA 2023 5-option pairwise preferences (-2..2)", read_pairwise)
