"""Global rankings from pairwise judgements: Bradley-Terry strengths on the Elo scale.

Model: ``P(i beats j) = p_i / (p_i + p_j)``, shown as ``Elo_i = 400 log10(p_i) + 1000`` with
the mean Elo fixed at 1000 (an Elo difference of 200 = preferred 76 % of the time, ties
ignored), not the order-dependent online Elo update. The GENEA Leaderboard fits the same
model by unpenalised weighted logistic regression (``400 * coef + 1000``; its fit starts at
zero and keeps the coefficients' mean at 0, i.e. the same anchor).

- Weights (Leaderboard): a strong win counts 4, a weak win 2, a plain win of a 3-level
  question 2, and a tie 1 for each side (a tie = half a win each way).
- ``prior`` (``--elo-prior``, default 0.1): virtual ties of that total weight (half to each
  side) between every pair of conditions compared in the data. It is a penalty, so the
  estimate is a *penalised* (maximum a posteriori) fit, not the plain MLE: it keeps the
  estimate finite when a condition never wins (e.g. in a bootstrap resample) and moves
  estimates by a few Elo points on real data. ``prior = 0`` is the plain maximum-likelihood
  estimate, i.e. the Leaderboard's estimate; it exists only when every set of conditions
  both beat and lost to (or tied with) the rest (the win graph is strongly connected),
  otherwise the table says so.
- Fit: Newton's method on the (penalised) log-likelihood in natural-log strengths, all
  bootstrap resamples at once, with step halving; it stops when the largest gradient entry
  is below ``1e-10`` times the total weight (quadratic convergence: the estimate is exact
  to far below 1e-6 Elo).
- CIs: percentile bootstrap over *participants* (judgements of one rater are not
  independent): resample participants with replacement ``n_boot`` times, refit, take the
  ``alpha/2`` and ``1 - alpha/2`` percentiles (linear interpolation) and the median.
  ``sampler="multinomial"`` (default) draws the counts with ``numpy.random.default_rng(seed)``;
  ``sampler="leaderboard"`` draws participant indices exactly as the Leaderboard's analysis
  does (``np.random.seed(seed)`` then ``np.random.choice(users, len(users))`` per round over
  the sorted participant ids), so the same seed gives the same resamples. With ``prior = 0``
  a resample without a finite MLE is fitted with a prior of ``1e-6`` (the direction the
  unpenalised fit runs away to) and counted in the note.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from tqdm import tqdm

from evalsuite.analysis.pairwise import orient

SAMPLERS = ("multinomial", "leaderboard")
RUNAWAY_PRIOR = 1e-6
# (strong win, any other win, tie to each side): the Leaderboard's weights of the fit, and plain counts with a
# tie half a win each way (the ``win_rate`` of elo.csv).
LEADERBOARD_WEIGHTS = (4.0, 2.0, 1.0)
PLAIN_WEIGHTS = (1.0, 1.0, 0.5)


def win_matrices(pw: pd.DataFrame, conditions, weights: tuple[float, float, float] = LEADERBOARD_WEIGHTS):
    """Per-participant weighted win matrices: returns ``(participants, W)`` with
    ``W[p, i, j]`` = weight of condition ``i`` beating ``j`` in participant ``p``'s judgements
    (``weights``: a strong win, any other win, a tie to each side; participants sorted)."""
    idx = {c: i for i, c in enumerate(conditions)}
    parts = sorted(pw["participant"].unique())
    pidx = {p: i for i, p in enumerate(parts)}
    o = orient(pw)
    a = o["condition_a"].map(idx).to_numpy()
    b = o["condition_b"].map(idx).to_numpy()
    p = o["participant"].map(pidx).to_numpy()
    strong, plain, tie = weights
    win = np.where(o["strength"] == "strong", strong, plain)
    ans = o["answer"].to_numpy()
    C = len(conditions)
    W = np.zeros((len(parts), C, C))
    # Vectorised scatter-add: winner row, loser column; ties add the tie weight both ways.
    np.add.at(W, (p, a, b), np.where(ans == "a", win, np.where(ans == "tie", tie, 0.0)))
    np.add.at(W, (p, b, a), np.where(ans == "b", win, np.where(ans == "tie", tie, 0.0)))
    return parts, W


def win_counts(W) -> tuple[np.ndarray, np.ndarray]:
    """``(wins, judgements)`` of each condition from win matrices ``W`` of shape ``(..., C, C)`` made with
    :data:`PLAIN_WEIGHTS`: ``wins_i = sum_j W_ij`` (a tie half a win) and ``judgements_i = sum_j (W_ij + W_ji)``
    (each judgement adds 1 to ``W_ij + W_ji``), both of shape ``(..., C)``. The win rate is their ratio."""
    W = np.asarray(W, dtype=float)
    return W.sum(axis=-1), (W + np.swapaxes(W, -1, -2)).sum(axis=-1)


def to_elo(log10_strength):
    """Elo scale of :func:`bradley_terry`'s log10 strengths: ``400 log10(p_i) + 1000`` (mean 1000)."""
    return 400 * log10_strength + 1000


def mle_exists(W) -> np.ndarray:
    """For a ``(C, C)`` or ``(R, C, C)`` win matrix: True where the plain MLE is finite, i.e. the
    directed graph ``i -> j`` for ``W[i, j] > 0`` is strongly connected (Zermelo; Hunter 2004)."""
    W = np.asarray(W, dtype=float)
    single = W.ndim == 2
    A = (W if not single else W[None]) > 0
    C = A.shape[-1]
    reach = A | np.eye(C, dtype=bool)[None]
    for _ in range(max(1, math.ceil(math.log2(max(C, 2))))):
        reach = (reach.astype(np.float32) @ reach.astype(np.float32)) > 0
    ok = reach.all(axis=(1, 2))
    return ok[0] if single else ok


def _newton(W: np.ndarray, tol: float, max_iter: int) -> np.ndarray:
    """Maximise ``sum_ij W_ij log sigma(t_i - t_j)`` for a batch ``(R, C, C)``; mean t = 0."""
    R, C, _ = W.shape
    N = W + np.swapaxes(W, 1, 2)
    wins = W.sum(axis=2)
    scale = np.maximum(W.sum(axis=(1, 2)), 1e-300)
    t = np.zeros((R, C))
    J = np.full((C, C), 1.0 / C)

    def loglik(th, w):
        d = th[:, :, None] - th[:, None, :]
        return -(w * np.logaddexp(0.0, -d)).sum(axis=(1, 2))

    ll = loglik(t, W)
    active = np.ones(R, dtype=bool)
    for _ in range(max_iter):
        d = t[:, :, None] - t[:, None, :]
        s = 0.5 * (1.0 + np.tanh(0.5 * d))           # sigma(t_i - t_j), overflow-free
        g = wins - (N * s).sum(axis=2)
        done = np.abs(g).max(axis=1) <= tol * scale
        active &= ~done
        if not active.any():
            break
        w = N * s * (1.0 - s)
        H = -w                                       # negative Hessian (Laplacian), plus J for the
        idx = np.arange(C)                           # mean-zero direction the likelihood leaves free
        H[:, idx, idx] = w.sum(axis=2)
        step = np.linalg.solve(H[active] + J[None], g[active][..., None])[..., 0]
        cur = t[active]
        lam = np.ones(len(cur))
        base = ll[active]
        sub = W[active]
        new = cur + step
        new_ll = loglik(new, sub)
        for _h in range(40):   # step halving: never accept a lower likelihood
            worse = new_ll < base - 1e-12 * np.abs(base)
            if not worse.any():
                break
            lam = np.where(worse, lam / 2, lam)
            new = cur + lam[:, None] * step
            new_ll = loglik(new, sub)
        new -= new.mean(axis=1, keepdims=True)
        t[active] = new
        ll[active] = new_ll
    return t


def bradley_terry(W, prior: float = 0.1, tol: float = 1e-10, max_iter: int = 200):
    """Bradley-Terry strengths for one ``(C, C)`` or a batch ``(R, C, C)`` of weighted win
    matrices. Returns log10 strengths with mean 0 (same leading shape as ``W[..., 0]``).

    ``prior`` adds virtual ties of that weight (half to each side) between every pair with
    ``N_ij > 0`` in the first matrix of the batch (a penalised fit; ``0`` = plain MLE).
    With ``prior = 0`` a matrix without a finite MLE (:func:`mle_exists`) gives NaN.
    """
    if prior < 0 or not math.isfinite(prior):
        raise ValueError(f"prior must be a finite number >= 0, got {prior!r}")
    W = np.asarray(W, dtype=float)
    single = W.ndim == 2
    if single:
        W = W[None]
    pairs = (W + np.swapaxes(W, 1, 2)).sum(axis=0) > 0
    np.fill_diagonal(pairs, False)
    Wp = W + pairs[None] * (prior / 2)
    ok = mle_exists(Wp)
    t = np.full(W.shape[:2], np.nan)
    if ok.any():
        t[ok] = _newton(Wp[ok], tol, max_iter)
    logp = t / math.log(10)
    return logp[0] if single else logp


def elo_table(pw: pd.DataFrame, *, n_boot: int = 1000, seed: int = 42, prior: float = 0.1,
              alpha: float = 0.05, sampler: str = "multinomial", progress: bool = False) -> pd.DataFrame:
    """Elo (Bradley-Terry) per question and condition with participant-bootstrap CIs.

    Columns: question, condition, elo, ci_low, ci_high, boot_median, n_judgements, win_rate
    (ties half, unweighted), n_participants, note.
    """
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler must be one of {', '.join(SAMPLERS)}")
    cols = ["question", "condition", "elo", "ci_low", "ci_high", "boot_median", "n_judgements", "win_rate",
            "n_participants", "note"]
    rows = []
    for q, g in pw.groupby("question", sort=True):
        conds = sorted(set(g["condition_a"]) | set(g["condition_b"]))
        parts, Wp = win_matrices(g, conds)
        W = Wp.sum(axis=0)
        wins, n_judge = win_counts(win_matrices(g, conds, PLAIN_WEIGHTS)[1].sum(axis=0))
        nan = np.full(len(conds), math.nan)
        elo, lo, hi, med = nan, nan, nan, nan
        notes = []
        if len(conds) < 2 or not mle_exists(W + W.T):
            notes.append("comparison graph not connected: no common Elo scale")
        elif prior == 0 and not mle_exists(W):
            notes.append("no finite maximum-likelihood estimate (a set of conditions never lost to, or "
                         "never beat, the rest): use --elo-prior > 0")
        else:
            elo = to_elo(bradley_terry(W, prior))
            if n_boot > 0 and len(parts) >= 2:
                boot, runaway = _bootstrap(W, Wp, n_boot, seed, prior, sampler, q, progress)
                lo, hi = np.percentile(boot, [100 * alpha / 2, 100 * (1 - alpha / 2)], axis=0)
                med = np.percentile(boot, 50, axis=0)
                if runaway:
                    notes.append(f"{runaway} of {n_boot} bootstrap resamples have no finite MLE; fitted with "
                                 f"a prior of {RUNAWAY_PRIOR:g}")
            elif len(parts) < 2:
                notes.append("a single participant: no bootstrap CI")
        for i, c in enumerate(conds):
            rows.append({"question": q, "condition": c, "elo": float(elo[i]), "ci_low": float(lo[i]),
                         "ci_high": float(hi[i]), "boot_median": float(med[i]), "n_judgements": int(n_judge[i]),
                         "win_rate": float(wins[i] / n_judge[i]) if n_judge[i] else math.nan,
                         "n_participants": len(parts), "note": "; ".join(notes)})
    out = pd.DataFrame(rows, columns=cols)
    return out.sort_values(["question", "elo"], ascending=[True, False], na_position="last",
                           kind="stable").reset_index(drop=True)


def _bootstrap(W, Wp, n_boot, seed, prior, sampler, q, progress):
    """Elo of ``n_boot`` participant resamples (``(n_boot, C)``) and the count of resamples
    without a finite MLE (``prior == 0`` only)."""
    n_parts, C = Wp.shape[0], Wp.shape[1]
    flat = Wp.reshape(n_parts, -1)
    pairs = (W + W.T) > 0
    np.fill_diagonal(pairs, False)
    if sampler == "multinomial":
        rng = np.random.default_rng(seed)
        draw = lambda r: rng.multinomial(n_parts, np.full(n_parts, 1 / n_parts), size=r)  # noqa: E731
    else:
        legacy = np.random.RandomState(seed)
        draw = lambda r: np.stack([np.bincount(legacy.randint(0, n_parts, size=n_parts),  # noqa: E731
                                               minlength=n_parts) for _ in range(r)])
    out, runaway, chunk = [], 0, 500
    for start in tqdm(range(0, n_boot, chunk), desc=f"bootstrap {q}", disable=not progress, unit="chunk"):
        r = min(chunk, n_boot - start)
        Wb = (draw(r) @ flat).reshape(r, C, C) + pairs[None] * (prior / 2)
        ok = mle_exists(Wb)
        t = np.empty((r, C))
        if ok.any():
            t[ok] = _newton(Wb[ok], 1e-10, 200)
        if not ok.all():
            runaway += int((~ok).sum())
            t[~ok] = _newton(Wb[~ok] + pairs[None] * (RUNAWAY_PRIOR / 2), 1e-10, 200)
        out.append(400 * t / math.log(10) + 1000)
    return np.concatenate(out), runaway
