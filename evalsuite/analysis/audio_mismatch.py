"""Audio mismatching: the GENEA Leaderboard's speech-gesture alignment, per system and as a ranking.

Each judgement compares one system's motion with its own speech (condition ``X``) to the same motion with
another segment's speech of the same speaker (``X:audio_mismatched``, as the study app exports it). Per
question and system, with ``n_matched``, ``n_mismatched`` and ``n_tie`` judgements:

- ``k, n``: the tie policy of :func:`evalsuite.analysis.pairwise.tie_adjusted` (``split`` by default, as
  GENEA: ties divided equally, an odd one to the side with fewer wins); ``pref_matched = k / n`` (``half``:
  ``(n_matched + n_tie / 2) / n``);
- ``p_value``: exact two-sided binomial test of ``k`` of ``n`` against 50 % (``scipy.stats.binomtest``),
  ``p_holm`` Holm-Bonferroni over the systems of the question, ``significant = p_holm < alpha``;
- ``ci_low, ci_high``: Clopper-Pearson ``1 - alpha`` interval of ``k / n``;
- ``rank``: 1 for the highest ``pref_matched`` of the question, equal shares share the smaller rank
  (competition ranking), no rank without judgements.

Between every two systems of a question, Barnard's exact test on their (tie-adjusted) matched / mismatched
counts with Holm (:func:`evalsuite.analysis.pairwise.mismatch_tables`) says which ranks differ.
"""
from __future__ import annotations

import pandas as pd

from evalsuite.analysis.pairwise import AUDIO_MISMATCH_SUFFIX, holm, mismatch_tables

__all__ = ["AUDIO_SUFFIX", "AUDIO_COLUMNS", "audio_mismatch_tables"]

AUDIO_SUFFIX = AUDIO_MISMATCH_SUFFIX
AUDIO_COLUMNS = ["question", "rank", "condition", "n_matched", "n_mismatched", "n_tie", "n", "pref_matched",
                 "ci_low", "ci_high", "p_value", "p_holm", "significant", "note"]


def audio_mismatch_tables(pw_table: pd.DataFrame, *, tie_policy: str = "split", alpha: float = 0.05,
                          suffix: str = AUDIO_SUFFIX) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``(per_system, between)`` from a :func:`~evalsuite.analysis.pairwise.pairwise_table` (one row per
    question and condition pair): ``per_system`` has :data:`AUDIO_COLUMNS`, ranked within each question;
    ``between`` is Barnard's test between systems (Holm). Both empty without audio-mismatch comparisons."""
    per, between = mismatch_tables(pw_table, suffix=suffix, tie_policy=tie_policy, alpha=alpha)
    if per.empty:
        return pd.DataFrame(columns=AUDIO_COLUMNS), between
    per = per.copy()
    per["n"] = per["n_matched"] + per["n_mismatched"] + per["n_tie"]
    per["p_holm"] = float("nan")
    for _, idx in per.groupby("question").groups.items():
        per.loc[idx, "p_holm"] = holm(per.loc[idx, "p_value"])
    per["significant"] = per["p_holm"] < alpha
    per["rank"] = per.groupby("question")["pref_matched"].rank(ascending=False, method="min").astype("Int64")
    per = per.sort_values(["question", "rank", "condition"], na_position="last").reset_index(drop=True)
    return per[AUDIO_COLUMNS], between
