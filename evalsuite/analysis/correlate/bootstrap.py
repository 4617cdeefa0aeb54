"""Bootstrap CIs of ``evalsuite correlate``: resampling the conditions, and the participants.

:func:`condition_bootstrap` draws the ``(metric, human)`` pairs of the conditions with replacement.

:class:`ParticipantResampler` is for ``--results``: judgements of one participant are not independent, so the
uncertainty of a human measure comes from the participants. Each resample draws the participants with
replacement (seeded, ``numpy.random.default_rng(seed).multinomial``, as the Elo bootstrap of ``evalsuite
analyze``) and recomputes the measure as ``evalsuite analyze`` computes it on the whole sample, from the same
per-participant quantities of the analysis modules:

- ``median``, ``mean`` (``ratings.csv``, :func:`~evalsuite.analysis.ratings.rating_summary`): of the resampled
  participants' MUSHRA ratings;
- ``mean`` (``likert_means.csv``): of the participant-level scale scores of
  :func:`~evalsuite.analysis.likert.participant_scores`;
- ``win_rate``: (wins + ties / 2) / judgements from the plain win matrices of
  :func:`~evalsuite.analysis.ranking.win_matrices` (:func:`~evalsuite.analysis.ranking.win_counts`),
  matched-vs-mismatched comparisons left out (:func:`~evalsuite.analysis.pairwise.is_mismatch`);
- ``elo``: the Bradley-Terry fit of :func:`~evalsuite.analysis.ranking.bradley_terry` (same prior).

:meth:`ParticipantResampler.point` recomputes the measure on the full sample, so the command can check
that the results file and the human table belong together.
"""
from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd

from evalsuite.analysis.correlate.statistics import percentile, replicates
from evalsuite.analysis.exclusions import apply_exclusions
from evalsuite.analysis.io import read_any
from evalsuite.analysis.likert import participant_scores, statement_matrix
from evalsuite.analysis.pairwise import is_mismatch
from evalsuite.analysis.ranking import PLAIN_WEIGHTS, bradley_terry, to_elo, win_counts, win_matrices

__all__ = ["condition_bootstrap", "two_level_bootstrap", "ParticipantResampler"]
_CHUNK = 250


def condition_bootstrap(x, y, n_boot: int, seed: int, alpha: float = 0.05):
    """Percentile CIs of rho and tau-b from ``n_boot`` resamples of the conditions (pairs ``(x_i, y_i)``
    drawn with replacement, ``numpy.random.default_rng(seed)``). Returns
    ``(rho_lo, rho_hi, tau_lo, tau_hi, n_undefined)``."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    idx = np.random.default_rng(seed).integers(0, x.size, size=(n_boot, x.size))
    rho, tau = replicates(x[idx], y[idx])
    return (*percentile(rho, alpha), *percentile(tau, alpha), int((~np.isfinite(rho)).sum()))


def two_level_bootstrap(x, H, seed: int, alpha: float = 0.05):
    """Percentile CIs of rho and tau-b resampling the conditions and the participants together.

    ``x``: (n,) metric values of the conditions; ``H``: (R, n) the human measure of the same conditions on R
    participant resamples (:meth:`ParticipantResampler.replicates`). Replicate r draws n conditions with
    replacement (``idx_r``, ``numpy.random.default_rng([seed, 2])``, independent of the participant draw) and
    correlates ``x[idx_r]`` with ``H[r, idx_r]``: a new set of systems rated by a new set of raters, so the
    interval holds both sources of uncertainty. Returns ``(rho_lo, rho_hi, tau_lo, tau_hi, n_undefined)``."""
    x, H = np.asarray(x, dtype=float), np.asarray(H, dtype=float)
    R, n = H.shape
    idx = np.random.default_rng([seed, 2]).integers(0, n, size=(R, n))
    rho, tau = replicates(x[idx], np.take_along_axis(H, idx, axis=1))
    return (*percentile(rho, alpha), *percentile(tau, alpha), int((~np.isfinite(rho)).sum()))


class ParticipantResampler:
    """Human measures on participant resamples of a study's judgements (after exclusions)."""

    def __init__(self, data: pd.DataFrame, mismatch_suffix: str = ":mismatched", prior: float = 0.1):
        keep = pd.Series(True, index=data.index)
        for col in ("is_training", "is_attention_check"):
            if col in data.columns:
                keep &= data[col].astype(str).isin(["0", "", "False"])
        self.data = data[keep]
        self.suffix = mismatch_suffix
        self.prior = prior
        self._cache: dict = {}

    @classmethod
    def from_results(cls, path, *, study=None, attention_fails: int = 2, keep_incomplete: bool = False,
                     duplicates: str = "keep-first", mushra_screening: bool = False, implausible_playback: int = 1,
                     mismatch_suffix: str = ":mismatched", elo_prior: float = 0.1) -> ParticipantResampler:
        """Read ``path`` (results.csv or battles CSV) and apply ``evalsuite analyze``'s exclusions (its options,
        same defaults); ``elo_prior``: analyze's ``--elo-prior``."""
        raw = read_any(pathlib.Path(path), study=study)
        excl = apply_exclusions(raw, attention_fails=attention_fails, keep_incomplete=keep_incomplete,
                                duplicates=duplicates, mushra_screening=mushra_screening,
                                implausible_playback=implausible_playback)
        return cls(excl.data, mismatch_suffix, elo_prior)

    # --- per measure: (participants, f(counts (R, P)) -> (R, C)) -----------------------------------

    def _subset(self, source: str, question: str) -> pd.DataFrame:
        d = self.data
        if source == "ratings":
            return d[(d["page_type"] == "mushra") & (d["question"] == question)]
        if source == "likert_means":
            return d[(d["page_type"] == "likert") & (d["scale"] == question)]
        if source in ("elo", "pairwise"):
            pw = d[(d["page_type"] == "pairwise") & (d["question"] == question)]
            return pw[~is_mismatch(pw["condition_a"], pw["condition_b"], self.suffix)]
        return d.iloc[0:0]

    def _measure(self, source: str, question: str, measure: str, conditions):
        """``(n_participants, fn)`` with ``fn(counts) -> (R, len(conditions))``; None if not computable."""
        sub = self._subset(source, question)
        if sub.empty:
            return None
        conditions = list(conditions)
        if source in ("elo", "pairwise"):
            every = sorted(set(sub["condition_a"]) | set(sub["condition_b"]))
        else:
            every = sorted(set(sub["condition"]))
        if not set(conditions) <= set(every):
            return None
        parts = sorted(sub["participant"].unique())
        pidx = {p: i for i, p in enumerate(parts)}
        cidx = {c: i for i, c in enumerate(every)}
        cols = [cidx[c] for c in conditions]
        P, C = len(parts), len(every)
        if source == "ratings" and measure == "median":
            vals = [[np.empty(0)] * P for _ in conditions]
            for (p, c), g in sub.groupby(["participant", "condition"]):
                if c in conditions:
                    vals[conditions.index(c)][pidx[p]] = g["value"].to_numpy(float)

            def median(counts):
                out = np.empty((counts.shape[0], len(conditions)))
                for r, k in enumerate(counts):
                    idx = np.repeat(np.arange(P), k.astype(int))
                    for j, per in enumerate(vals):
                        v = np.concatenate([per[i] for i in idx])
                        out[r, j] = np.median(v) if v.size else np.nan
                return out
            return P, median
        if source in ("ratings", "likert_means") and measure == "mean":
            if source == "ratings":
                S = np.zeros((P, C))
                N = np.zeros((P, C))
                np.add.at(S, (sub["participant"].map(pidx), sub["condition"].map(cidx)), sub["value"].to_numpy(float))
                np.add.at(N, (sub["participant"].map(pidx), sub["condition"].map(cidx)), 1.0)
            else:
                scores = participant_scores(statement_matrix(sub))
                S = np.zeros((P, C))
                N = np.zeros((P, C))
                S[scores["participant"].map(pidx), scores["condition"].map(cidx)] = scores["score"].to_numpy(float)
                N[scores["participant"].map(pidx), scores["condition"].map(cidx)] = 1.0
            return P, lambda counts: _ratio(counts @ S[:, cols], counts @ N[:, cols])
        if measure == "win_rate":
            wins, judged = win_counts(win_matrices(sub, every, PLAIN_WEIGHTS)[1])   # (P, C) each
            return P, lambda counts: _ratio(counts @ wins[:, cols], counts @ judged[:, cols])
        if source == "elo" and measure == "elo":
            _, Wp = win_matrices(sub, every)
            flat = Wp.reshape(P, -1)
            W = Wp.sum(axis=0)

            def elo(counts):
                out = []
                for s in range(0, counts.shape[0], _CHUNK):
                    Wb = (counts[s:s + _CHUNK] @ flat).reshape(-1, C, C)
                    out.append(to_elo(bradley_terry(np.concatenate([W[None], Wb]), self.prior)[1:]))
                return np.concatenate(out)[:, cols]
            return P, elo
        return None

    def point(self, source: str, question: str, measure: str, conditions):
        """The measure on the full sample (every participant once), or None when not computable."""
        m = self._measure(source, question, measure, conditions)
        if m is None:
            return None
        P, fn = m
        return fn(np.ones((1, P)))[0]

    def replicates(self, source: str, question: str, measure: str, conditions, n_boot: int, seed: int):
        """``(n_boot, len(conditions))`` measures on participant resamples, or None when not computable
        (cached: every metric is correlated with the same resamples)."""
        key = (source, question, measure, tuple(conditions), n_boot, seed)
        if key not in self._cache:
            m = self._measure(source, question, measure, conditions)
            if m is None:
                self._cache[key] = None
            else:
                P, fn = m
                counts = np.random.default_rng(seed).multinomial(P, np.full(P, 1 / P), size=n_boot).astype(float)
                self._cache[key] = fn(counts)
        return self._cache[key]


def _ratio(num, den):
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1), np.nan)

