"""Pairwise preference statistics (Gesticulator, GENEA appropriateness, Leaderboard).

Conventions
-----------
- A comparison is an unordered pair of conditions within one question. Rows are
  re-oriented so that ``condition_a`` is the first of the two in ``condition order``
  (sorted names unless given), flipping ``a``/``b`` answers where needed; what was shown
  left/right is irrelevant once the export has translated it (``position_a``).
- Tie policies (``tie_policy``):

  ``exclude`` (default, the textbook sign test used by Gesticulator):
      ``k = n_a``, ``n = n_a + n_b``; preference ``k / n``.
  ``split`` (GENEA 2022): ties are divided equally between A and B as whole
      judgements; an odd tie goes to the side with fewer wins (pulls towards 50 %, the
      conservative rounding), ``n = n_a + n_b + n_tie``.
  ``half`` (GENEA Leaderboard): each tie counts half a win for each side: the preference
      is ``(n_a + n_tie / 2) / n`` exactly; the exact test and the CI need whole counts,
      so they use the conservatively rounded count of ``split``.

- Test: exact two-sided binomial test of ``k`` successes in ``n`` against 0.5
  (``scipy.stats.binomtest``); CIs: Clopper-Pearson (``proportion_confint(method="beta")``)
  and Wilson (``method="wilson"``), 95 % by default.
- Multiplicity: Holm-Bonferroni step-down (``multipletests(method="holm")`` -- set
  explicitly, statsmodels' default is Holm-Sidak) over all comparisons of the study, or
  per question (``holm_scope="question"``). Comparisons without a test are left out of
  the family and carry a ``note`` instead of a p-value.
- Effect sizes: ``pref_a - 0.5``; Cohen's ``h = 2 asin(sqrt(p)) - 2 asin(sqrt(0.5))``;
  ``mean_score`` = mean of the coded answers (A: +1, or +1 weak / +2 strong on 5-level
  questions; tie 0; B negative).
"""
from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
from scipy import stats
from statsmodels.stats.multitest import multipletests
from statsmodels.stats.proportion import proportion_confint

TIE_POLICIES = ("exclude", "split", "half")
CI_METHODS = {"clopper-pearson": "beta", "wilson": "wilson"}
PAIRWISE_COLUMNS = ["question", "condition_a", "condition_b", "n_a", "n_b", "n_tie", "pref_a",
                    "ci_low", "ci_high", "p_value", "p_holm"]


def preference_ci(k: int, n: int, alpha: float = 0.05, method: str = "clopper-pearson"):
    """Two-sided ``1 - alpha`` confidence interval of a binomial proportion ``k / n``.

    ``clopper-pearson``: exact interval from beta quantiles,
    ``[B(alpha/2; k, n-k+1), B(1-alpha/2; k+1, n-k)]`` with 0 / 1 at the ends.
    ``wilson``: score interval. Returns ``(nan, nan)`` for ``n == 0``.
    """
    if method not in CI_METHODS:
        raise ValueError(f"unknown CI method {method!r}; expected one of {', '.join(CI_METHODS)}")
    if n <= 0:
        return (math.nan, math.nan)
    lo, hi = proportion_confint(k, n, alpha=alpha, method=CI_METHODS[method])
    return (float(lo), float(hi))


def tie_adjusted(n_a: int, n_b: int, n_tie: int, policy: str = "exclude"):
    """Apply a tie policy: returns ``(k, n, pref_a)`` (module docstring).

    ``k`` and ``n`` are whole counts for the exact test; ``pref_a`` is the reported
    preference for A (``nan`` when ``n == 0``).
    """
    if policy not in TIE_POLICIES:
        raise ValueError(f"unknown tie policy {policy!r}; expected one of {', '.join(TIE_POLICIES)}")
    if policy == "exclude":
        k, n = n_a, n_a + n_b
        return k, n, (k / n if n else math.nan)
    n = n_a + n_b + n_tie
    half, odd = divmod(n_tie, 2)
    # The odd tie goes to the side with fewer wins: towards 50 %, never away from it.
    k = n_a + half + (odd if n_a < n_b else 0)
    if policy == "split":
        return k, n, (k / n if n else math.nan)
    return k, n, ((n_a + n_tie / 2) / n if n else math.nan)


def binomial_p(k: int, n: int, p: float = 0.5) -> float:
    """Exact two-sided binomial test p-value of ``k`` of ``n`` against ``p`` (nan if n == 0)."""
    if n <= 0:
        return math.nan
    return float(stats.binomtest(int(k), int(n), p, alternative="two-sided").pvalue)


def adjust_pvalues(pvalues, method: str) -> np.ndarray:
    """Multiplicity-adjusted p-values (statsmodels ``method``, named explicitly: its default is
    Holm-Sidak); NaN entries stay NaN and are not counted in the family."""
    p = np.asarray(pvalues, dtype=float)
    out = np.full(p.shape, np.nan)
    ok = np.isfinite(p)
    if ok.any():
        out[ok] = multipletests(p[ok], method=method)[1]
    return out


def holm(pvalues) -> np.ndarray:
    """Holm-Bonferroni adjusted p-values; NaN entries stay NaN and are not in the family.

    Step-down: sort the m p-values ascending, ``p_adj(i) = max_{j<=i} min(1, (m-j+1) p(j))``.
    """
    return adjust_pvalues(pvalues, "holm")


def add_holm(table: pd.DataFrame, scope: str, alpha: float) -> None:
    """Add ``p_holm`` and ``significant`` columns in place: one Holm family per study
    (``scope="study"``) or per question (``scope="question"``)."""
    if scope == "study":
        table["p_holm"] = holm(table["p_value"])
    else:
        table["p_holm"] = np.nan
        for _, idx in table.groupby("question").groups.items():
            table.loc[idx, "p_holm"] = holm(table.loc[idx, "p_value"])
    table["significant"] = table["p_holm"] < alpha


def orient(pw: pd.DataFrame, order=None) -> pd.DataFrame:
    """Re-orient pairwise rows so ``condition_a`` comes first in ``order`` (default: sorted)."""
    conds = sorted(set(pw["condition_a"]) | set(pw["condition_b"]))
    if order is not None:
        rank = {c: i for i, c in enumerate(order)}
        conds = sorted(conds, key=lambda c: (rank.get(c, len(rank)), c))
    pos = {c: i for i, c in enumerate(conds)}
    pw = pw.copy()
    flip = pw["condition_a"].map(pos) > pw["condition_b"].map(pos)
    pw.loc[flip, ["condition_a", "condition_b"]] = pw.loc[flip, ["condition_b", "condition_a"]].to_numpy()
    pw.loc[flip, "answer"] = pw.loc[flip, "answer"].map({"a": "b", "b": "a", "tie": "tie"})
    sign = pw["answer"].map({"a": 1, "b": -1, "tie": 0})
    pw["score"] = sign * np.where(pw["strength"] == "strong", 2, 1)
    return pw


def pairwise_counts(pw: pd.DataFrame, order=None) -> pd.DataFrame:
    """Counts per (question, condition_a, condition_b): n_a, n_b, n_tie, strong/weak split,
    participants, mean coded score."""
    cols = ["question", "condition_a", "condition_b", "n_a", "n_b", "n_tie", "n_a_strong",
            "n_b_strong", "n_participants", "mean_score", "levels"]
    if pw.empty:
        return pd.DataFrame(columns=cols)
    o = orient(pw, order)
    o = o.assign(is_a=o["answer"] == "a", is_b=o["answer"] == "b", is_tie=o["answer"] == "tie",
                 a_strong=(o["answer"] == "a") & (o["strength"] == "strong"),
                 b_strong=(o["answer"] == "b") & (o["strength"] == "strong"))
    g = o.groupby(["question", "condition_a", "condition_b"], sort=True)
    out = g.agg(n_a=("is_a", "sum"), n_b=("is_b", "sum"), n_tie=("is_tie", "sum"),
                n_a_strong=("a_strong", "sum"), n_b_strong=("b_strong", "sum"),
                n_participants=("participant", "nunique"), mean_score=("score", "mean")).reset_index()
    five = o.groupby("question")["strength"].apply(lambda s: (s != "").any())
    out["levels"] = out["question"].map(five).map({True: 5, False: 3})
    for c in ("n_a", "n_b", "n_tie", "n_a_strong", "n_b_strong", "n_participants"):
        out[c] = out[c].astype(int)
    return out[cols]


def _no_test_note(n_a, n_b, n_tie, policy):
    if n_a + n_b + n_tie == 0:
        return "no judgements for this comparison (after exclusions)"
    if policy == "exclude" and n_a + n_b == 0:
        return f"all {n_tie} judgements are ties: no test with ties excluded"
    return ""


def pairwise_table(pw: pd.DataFrame, *, tie_policy: str = "exclude", ci_method: str = "clopper-pearson",
                   holm_scope: str = "study", alpha: float = 0.05, comparisons=None,
                   order=None) -> pd.DataFrame:
    """The ``pairwise.csv`` table: one row per (question, condition pair).

    ``pw``: pairwise judgement rows (results layout). ``comparisons``: optional iterable of
    ``(question, cond1, cond2)`` that must appear even without data (e.g. every comparison
    of the design, so one emptied by exclusions is reported, with a ``note``).
    Columns: :data:`PAIRWISE_COLUMNS` then ``k, n, wilson_low, wilson_high, cohens_h,
    mean_score, n_a_strong, n_b_strong, n_participants, levels, significant, note``.
    """
    if holm_scope not in ("study", "question"):
        raise ValueError("holm_scope must be 'study' or 'question'")
    counts = pairwise_counts(pw, order)
    if comparisons is not None:
        extra = []
        have = set(zip(counts["question"], counts["condition_a"], counts["condition_b"]))
        for q, c1, c2 in comparisons:
            a, b = orient(pd.DataFrame({"condition_a": [c1], "condition_b": [c2], "answer": ["a"],
                                        "strength": [""]}), order)[["condition_a", "condition_b"]].iloc[0]
            if (q, a, b) not in have:
                have.add((q, a, b))
                extra.append({"question": q, "condition_a": a, "condition_b": b, "n_a": 0, "n_b": 0,
                              "n_tie": 0, "n_a_strong": 0, "n_b_strong": 0, "n_participants": 0,
                              "mean_score": math.nan, "levels": 3})
        if extra:
            counts = pd.concat([counts, pd.DataFrame(extra)], ignore_index=True)
            counts = counts.sort_values(["question", "condition_a", "condition_b"]).reset_index(drop=True)
    rows = []
    for r in counts.itertuples(index=False):
        k, n, pref = tie_adjusted(r.n_a, r.n_b, r.n_tie, tie_policy)
        lo, hi = preference_ci(k, n, alpha, ci_method) if n else (math.nan, math.nan)
        wlo, whi = preference_ci(k, n, alpha, "wilson") if n else (math.nan, math.nan)
        if tie_policy == "half" and n:
            # The reported point estimate is the exact half-tie share; keep it inside its CI.
            lo, hi = min(lo, pref), max(hi, pref)
        p = binomial_p(k, n)
        rows.append({**r._asdict(), "k": k, "n": n, "pref_a": pref, "ci_low": lo, "ci_high": hi,
                     "wilson_low": wlo, "wilson_high": whi, "p_value": p,
                     "cohens_h": (2 * math.asin(math.sqrt(pref)) - math.pi / 2) if n else math.nan,
                     "note": _no_test_note(r.n_a, r.n_b, r.n_tie, tie_policy)})
    cols = PAIRWISE_COLUMNS + ["k", "n", "wilson_low", "wilson_high", "cohens_h", "mean_score",
                               "n_a_strong", "n_b_strong", "n_participants", "levels", "significant", "note"]
    table = pd.DataFrame(rows, columns=[c for c in cols if c not in ("p_holm", "significant")])
    if table.empty:
        return pd.DataFrame(columns=cols)
    add_holm(table, holm_scope, alpha)
    return table[cols]


# --- matched vs mismatched designs -------------------------------------------------------

def mismatch_pairs(conditions, suffix: str = ":mismatched"):
    """``{base: mismatched}`` for every condition that has a ``base + suffix`` partner."""
    if not suffix:
        return {}
    conds = set(conditions)
    return {c: c + suffix for c in sorted(conds) if not c.endswith(suffix) and c + suffix in conds}


AUDIO_MISMATCH_SUFFIX = ":audio_mismatched"   # the study app's audio-mismatched clips (same motion, other speech)


def is_mismatch(a: pd.Series, b: pd.Series, suffix: str = ":mismatched") -> pd.Series:
    """True where a comparison of ``a`` with ``b`` (condition names, aligned Series) is ``X`` vs ``X + suffix``
    or ``X`` vs ``X`` + :data:`AUDIO_MISMATCH_SUFFIX`: matched vs mismatched, not a comparison between two
    systems (left out of rankings and win rates). An empty ``suffix`` leaves only the audio-mismatched ones."""
    out = (b == a + AUDIO_MISMATCH_SUFFIX) | (a == b + AUDIO_MISMATCH_SUFFIX)
    if not suffix:
        return out
    return out | (b == a + suffix) | (a == b + suffix)


BARNARD_EXACT_MAX_CELLS = 250_000
BARNARD_EXACT = "Barnard exact"
BARNARD_ASYMPTOTIC = "pooled z (asymptotic Barnard)"


def barnard_test(table) -> tuple[float, str]:
    """Two-sided Barnard test (pooled) on a 2x2 table ``[[m1, m2], [x1, x2]]``: columns are the
    two conditions, rows matched / mismatched preferences. Returns ``(p, test)``.

    Barnard's exact test (``scipy.stats.barnard_exact``, pooled) enumerates every table with the
    same column totals, ``(n1 + 1)(n2 + 1)`` of them, for each of many nuisance values: time and
    memory grow as ``n1 * n2``. Up to :data:`BARNARD_EXACT_MAX_CELLS` tables (about 500
    judgements per condition) it is used as is; above, the test is its large-sample form: the
    same pooled statistic ``z = (p1 - p2) / sqrt(p (1 - p) (1/n1 + 1/n2))`` referred to the
    standard normal (the exact p-value converges to it; at the switch they differ by well under
    1e-2 in absolute p). ``test`` names which one ran; ``p`` is ``nan`` when a column is empty.
    """
    t = np.asarray(table, dtype=np.int64)
    n1, n2 = t.sum(axis=0)
    if n1 == 0 or n2 == 0:
        return math.nan, ""
    if (n1 + 1) * (n2 + 1) <= BARNARD_EXACT_MAX_CELLS:
        return float(stats.barnard_exact(t, alternative="two-sided", pooled=True).pvalue), BARNARD_EXACT
    p1, p2 = t[0, 0] / n1, t[0, 1] / n2
    pooled = (t[0, 0] + t[0, 1]) / (n1 + n2)
    var = pooled * (1 - pooled) * (1 / n1 + 1 / n2)
    if var == 0:
        return 1.0, BARNARD_ASYMPTOTIC
    z = (p1 - p2) / math.sqrt(var)
    return float(2 * stats.norm.sf(abs(z))), BARNARD_ASYMPTOTIC


def barnard_p(table) -> float:
    """The p-value of :func:`barnard_test` (``nan`` when a column is empty)."""
    return barnard_test(table)[0]


def mismatch_tables(pw_table: pd.DataFrame, *, suffix: str = ":mismatched", tie_policy: str = "split",
                    alpha: float = 0.05):
    """Matched-vs-mismatched analysis (GENEA 2022 appropriateness).

    From a :func:`pairwise_table` whose comparisons include ``X`` vs ``X + suffix``:
    returns ``(per_condition, between)``. ``per_condition``: question, condition,
    n_matched, n_mismatched, n_tie, pref_matched (tie policy, default ``split`` as GENEA),
    Clopper-Pearson CI, uncorrected binomial p against 50 %. ``between``: Barnard's exact
    test between every two conditions of a question on their (tie-adjusted) matched /
    mismatched counts (:func:`barnard_test`: exact, or its large-sample form for large
    counts, named in ``test``), Holm-corrected over all those tests.
    """
    per, between = [], []
    if pw_table.empty:
        return pd.DataFrame(), pd.DataFrame()
    for q, sub in pw_table.groupby("question", sort=True):
        conds = set(sub["condition_a"]) | set(sub["condition_b"])
        pairs = mismatch_pairs(conds, suffix)
        adj = {}
        for base, mism in pairs.items():
            row = sub[(sub["condition_a"] == base) & (sub["condition_b"] == mism)]
            if row.empty:
                row = sub[(sub["condition_a"] == mism) & (sub["condition_b"] == base)]
                n_m, n_x = int(row["n_b"].sum()), int(row["n_a"].sum())
            else:
                n_m, n_x = int(row["n_a"].sum()), int(row["n_b"].sum())
            n_t = int(row["n_tie"].sum())
            k, n, pref = tie_adjusted(n_m, n_x, n_t, tie_policy)
            lo, hi = preference_ci(k, n, alpha) if n else (math.nan, math.nan)
            adj[base] = (k, n - k)
            per.append({"question": q, "condition": base, "n_matched": n_m, "n_mismatched": n_x,
                        "n_tie": n_t, "pref_matched": pref, "ci_low": lo, "ci_high": hi,
                        "p_value": binomial_p(k, n),
                        "note": _no_test_note(n_m, n_x, n_t, tie_policy)})
        for c1, c2 in itertools.combinations(sorted(adj), 2):
            t = [[adj[c1][0], adj[c2][0]], [adj[c1][1], adj[c2][1]]]
            p, test = barnard_test(t)
            note = "" if np.isfinite(p) else "no judgements for one of the conditions"
            if test == BARNARD_ASYMPTOTIC:
                note = (f"{sum(adj[c1])} and {sum(adj[c2])} judgements: above the exact test's limit "
                        f"({BARNARD_EXACT_MAX_CELLS:,} tables), pooled z test")
            between.append({"question": q, "condition_1": c1, "condition_2": c2,
                            "pref_1": adj[c1][0] / sum(adj[c1]) if sum(adj[c1]) else math.nan,
                            "pref_2": adj[c2][0] / sum(adj[c2]) if sum(adj[c2]) else math.nan,
                            "p_value": p, "test": test, "note": note})
    per_df = pd.DataFrame(per)
    between_df = pd.DataFrame(between)
    if not between_df.empty:
        between_df["p_holm"] = holm(between_df["p_value"])
        between_df["significant"] = between_df["p_holm"] < alpha
    return per_df, between_df
