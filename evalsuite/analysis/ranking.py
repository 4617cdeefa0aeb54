"""Global rankings from pairwise judgements: Bradley-Terry strengths on the Elo scale.

Model: ``P(i beats j) = p_i / (p_i + p_j)``. The GENEA Leaderboard's "Elo" is exactly this
Bradley-Terry maximum-likelihood fit expressed as ``Elo_i = 400 log10(p_i) + 1000``
(an Elo difference of 200 = preferred 76 % of the time, ties ignored), not the
order-dependent online Elo update.

- Weights (Leaderboard): a strong win counts 4, a weak win 2, a plain win of a 3-level
  question 2, and a tie 1 for each side (a tie = half a win each way).
- Fit: Hunter's (2004) MM algorithm ``p_i <- W_i / sum_j N_ij / (p_i + p_j)`` with ``W_i``
  the weighted wins of ``i`` and ``N_ij = W_ij + W_ji``, normalised to geometric mean 1
  (mean Elo 1000). It converges to the same maximum as the Leaderboard's unpenalised
  logistic regression. A small ``prior`` (virtual ties of weight 0.1 between every pair
  compared in the data) keeps the estimate finite when a condition never wins, e.g. in
  a bootstrap resample; it moves estimates by far less than their CI on real data.
- CIs: percentile bootstrap over *participants* (judgements of one rater are not
  independent): resample participants with replacement ``n_boot`` times (seeded), refit,
  take the 2.5 / 97.5 percentiles.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from tqdm import tqdm

from evalsuite.analysis.pairwise import orient


def win_matrices(pw: pd.DataFrame, conditions):
    """Per-participant weighted win matrices: returns ``(participants, W)`` with
    ``W[p, i, j]`` = weight of condition ``i`` beating ``j`` in participant ``p``'s judgements."""
    idx = {c: i for i, c in enumerate(conditions)}
    parts = sorted(pw["participant"].unique())
    pidx = {p: i for i, p in enumerate(parts)}
    o = orient(pw)
    a = o["condition_a"].map(idx).to_numpy()
    b = o["condition_b"].map(idx).to_numpy()
    p = o["participant"].map(pidx).to_numpy()
    win = np.where(o["strength"] == "strong", 4.0, 2.0)
    ans = o["answer"].to_numpy()
    C = len(conditions)
    W = np.zeros((len(parts), C, C))
    # Vectorised scatter-add: winner row, loser column; ties add 1 both ways.
    np.add.at(W, (p, a, b), np.where(ans == "a", win, np.where(ans == "tie", 1.0, 0.0)))
    np.add.at(W, (p, b, a), np.where(ans == "b", win, np.where(ans == "tie", 1.0, 0.0)))
    return parts, W


def bradley_terry(W, prior: float = 0.1, tol: float = 1e-10, max_iter: int = 100_000):
    """Bradley-Terry strengths by MM for one ``(C, C)`` or a batch ``(R, C, C)`` of weighted
    win matrices. Returns log10 strengths with mean 0 (same leading shape as ``W[..., 0]``).

    ``prior`` adds virtual ties of that weight (half to each side) between every pair with
    ``N_ij > 0`` in the first matrix of the batch.
    """
    W = np.asarray(W, dtype=float)
    single = W.ndim == 2
    if single:
        W = W[None]
    pairs = (W + np.swapaxes(W, 1, 2)).sum(axis=0) > 0
    np.fill_diagonal(pairs, False)
    W = W + pairs[None] * (prior / 2)
    N = W + np.swapaxes(W, 1, 2)
    wins = W.sum(axis=2)
    R, C, _ = W.shape
    p = np.ones((R, C))
    for _ in range(max_iter):
        denom = (N / (p[:, :, None] + p[:, None, :])).sum(axis=2)
        new = np.where(denom > 0, wins / np.where(denom > 0, denom, 1), p)
        new = np.maximum(new, 1e-300)
        new /= np.exp(np.log(new).mean(axis=1, keepdims=True))
        done = np.max(np.abs(np.log(new) - np.log(p))) < tol
        p = new
        if done:
            break
    logp = np.log10(p)
    logp -= logp.mean(axis=1, keepdims=True)
    return logp[0] if single else logp


def connected(W) -> bool:
    """True when the comparison graph (pairs with any judgement) is connected."""
    adj = (W + W.T) > 0
    C = adj.shape[0]
    seen, stack = {0}, [0]
    while stack:
        i = stack.pop()
        for j in np.flatnonzero(adj[i]):
            if j not in seen:
                seen.add(int(j))
                stack.append(int(j))
    return len(seen) == C


def elo_table(pw: pd.DataFrame, *, n_boot: int = 1000, seed: int = 42, prior: float = 0.1,
              alpha: float = 0.05, progress: bool = False) -> pd.DataFrame:
    """Elo (Bradley-Terry) per question and condition with participant-bootstrap CIs.

    Columns: question, condition, elo, ci_low, ci_high, n_judgements, win_rate (ties
    half, unweighted), n_participants, note.
    """
    cols = ["question", "condition", "elo", "ci_low", "ci_high", "n_judgements", "win_rate",
            "n_participants", "note"]
    rows = []
    for q, g in pw.groupby("question", sort=True):
        conds = sorted(set(g["condition_a"]) | set(g["condition_b"]))
        parts, Wp = win_matrices(g, conds)
        W = Wp.sum(axis=0)
        n_judge = np.array([((g["condition_a"] == c) | (g["condition_b"] == c)).sum() for c in conds])
        o = orient(g)
        wins = np.array([((o["condition_a"] == c) & (o["answer"] == "a")).sum()
                         + ((o["condition_b"] == c) & (o["answer"] == "b")).sum()
                         + 0.5 * (((o["condition_a"] == c) | (o["condition_b"] == c)) & (o["answer"] == "tie")).sum()
                         for c in conds])
        if len(conds) < 2 or not connected(W):
            for i, c in enumerate(conds):
                rows.append({"question": q, "condition": c, "elo": math.nan, "ci_low": math.nan,
                             "ci_high": math.nan, "n_judgements": int(n_judge[i]),
                             "win_rate": wins[i] / n_judge[i] if n_judge[i] else math.nan,
                             "n_participants": len(parts),
                             "note": "comparison graph not connected: no common Elo scale"})
            continue
        elo = 400 * bradley_terry(W, prior) + 1000
        lo = hi = np.full(len(conds), math.nan)
        note = ""
        if n_boot > 0 and len(parts) >= 2:
            rng = np.random.default_rng(seed)
            draws = []
            flat = Wp.reshape(len(parts), -1)
            chunk = 250
            for start in tqdm(range(0, n_boot, chunk), desc=f"bootstrap {q}", disable=not progress,
                              unit="chunk"):
                r = min(chunk, n_boot - start)
                counts = rng.multinomial(len(parts), np.full(len(parts), 1 / len(parts)), size=r)
                Wb = (counts @ flat).reshape(r, len(conds), len(conds))
                draws.append(400 * bradley_terry(np.concatenate([W[None], Wb]), prior)[1:] + 1000)
            boot = np.concatenate(draws)
            lo, hi = np.percentile(boot, [100 * alpha / 2, 100 * (1 - alpha / 2)], axis=0)
        elif len(parts) < 2:
            note = "a single participant: no bootstrap CI"
        for i, c in enumerate(conds):
            rows.append({"question": q, "condition": c, "elo": float(elo[i]), "ci_low": float(lo[i]),
                         "ci_high": float(hi[i]), "n_judgements": int(n_judge[i]),
                         "win_rate": float(wins[i] / n_judge[i]) if n_judge[i] else math.nan,
                         "n_participants": len(parts), "note": note})
    out = pd.DataFrame(rows, columns=cols)
    return out.sort_values(["question", "elo"], ascending=[True, False], na_position="last",
                           kind="stable").reset_index(drop=True)
