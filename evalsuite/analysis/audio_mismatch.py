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
  (competition ranking), no rank without judgements;
- ``leaderboard_win_rate``: the GENEA Leaderboard analysis's ``win_rate_split_ties``, in which a strong
  preference counts twice and a tie half: ``(w_m + 2 s_m + t / 2) / (w_m + w_x + 2 s_m + 2 s_x + t)`` with
  ``w``/``s`` the weak/strong preferences for the matched (``m``) and mismatched (``x``) video and ``t``
  ties (3-level answers are weak; then it equals the ``half`` share).

Between every two systems of a question, Barnard's exact test on their (tie-adjusted) matched / mismatched
counts with Holm (:func:`evalsuite.analysis.pairwise.mismatch_tables`) says which ranks differ.
"""
from __future__ import annotations

import pandas as pd

from evalsuite.analysis.pairwise import AUDIO_MISMATCH_SUFFIX, holm, mismatch_tables

__all__ = ["AUDIO_SUFFIX", "AUDIO_COLUMNS", "audio_mismatch_tables"]

AUDIO_SUFFIX = AUDIO_MISMATCH_SUFFIX
AUDIO_COLUMNS = ["question", "rank", "condition", "n_matched", "n_mismatched", "n_tie", "n", "pref_matched",
                 "ci_low", "ci_high", "p_value", "p_holm", "significant", "leaderboard_win_rate", "note"]


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
    per["leaderboard_win_rate"] = [_leaderboard_win_rate(pw_table, q, c, suffix)
                                   for q, c in zip(per["question"], per["condition"])]
    per = per.sort_values(["question", "rank", "condition"], na_position="last").reset_index(drop=True)
    return per[AUDIO_COLUMNS], between


def _leaderboard_win_rate(pw_table: pd.DataFrame, question: str, condition: str, suffix: str) -> float:
    """``win_rate_split_ties`` of the matched video (module docstring) from the comparison's counts."""
    rows = pw_table[pw_table["question"] == question]
    row = rows[(rows["condition_a"] == condition) & (rows["condition_b"] == condition + suffix)]
    cols = ("n_a", "n_b", "n_a_strong", "n_b_strong")
    if row.empty:     # oriented the other way round
        row = rows[(rows["condition_b"] == condition) & (rows["condition_a"] == condition + suffix)]
        cols = ("n_b", "n_a", "n_b_strong", "n_a_strong")
    m, x, s_m, s_x = (int(row[c].sum()) for c in cols)
    t = int(row["n_tie"].sum())
    wins, appearances = (m - s_m) + 2 * s_m + t / 2, (m - s_m) + (x - s_x) + 2 * (s_m + s_x) + t
    return wins / appearances if appearances else float("nan")
