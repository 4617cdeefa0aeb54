"""Benchmark: votes to ranking accuracy, adaptive pair selection against the balanced design.

A simulation with a known truth: ``--systems`` systems (default 8) with fixed Bradley-Terry strengths
(natural log, :data:`TRUTH_8` or evenly spaced for another count), one simulated judgement per vote,
``P(i preferred to j) = sigma(t_i - t_j)``, no ties.

- *balanced*: the pairs of every round are all ``C (C - 1) / 2`` pairs in a random order (what the
  balanced plans of a pairwise block show over the study);
- *adaptive*: before each vote the strengths are refitted to every vote so far and the next pair is
  :func:`study_app.adaptive.choose_pair` (most informative, uniform exploration at ``--exploration``),
  exactly what the study server does at each page view.

Both are scored with the same estimate (:func:`study_app.adaptive.fit`) at each checkpoint, as Kendall's
tau between the estimated and the true strengths (``scipy.stats.kendalltau``; 1 = the true order). Each
repetition uses the same seed for both designs; the table gives the mean tau over repetitions and its
standard error, and the last lines the votes each design needed until its mean tau first reached
``--target`` (and their ratio, adaptive / balanced).

Run: python benchmarks/bench_adaptive_pairs.py [--reps 20] [--votes 1400] [--exploration 0.2]
"""
from __future__ import annotations

import argparse
import itertools
import os
import random
import time

import numpy as np
from scipy.stats import kendalltau
from tqdm import tqdm

from study_app.adaptive import choose_pair, fit

# Strengths of 8 systems: a spread like a leaderboard's, with some close neighbours (natural log).
TRUTH_8 = (1.2, 0.95, 0.75, 0.55, 0.3, 0.1, -0.35, -0.9)


def truth_for(n: int) -> np.ndarray:
    return np.array(TRUTH_8) if n == 8 else np.linspace(1.0, -1.0, n)


def simulate(design: str, truth: np.ndarray, checkpoints: list[int], exploration: float, seed: int) -> list[float]:
    """Kendall tau to the truth after each checkpoint's number of votes, for one repetition."""
    names = [f"S{k}" for k in range(len(truth))]
    strength = dict(zip(names, truth))
    pairs = [list(p) for p in itertools.combinations(names, 2)]
    rng = random.Random(seed)
    votes: list[tuple[str, str, float]] = []
    queue: list[list[str]] = []
    out = []
    for n in range(1, checkpoints[-1] + 1):
        if design == "balanced":
            if not queue:
                queue = rng.sample(pairs, len(pairs))
            x, y = queue.pop()
        else:
            k, _how = choose_pair(fit(names, votes), pairs, exploration, rng)
            x, y = pairs[k]
        p = 1 / (1 + np.exp(-(strength[x] - strength[y])))
        votes.append((x, y, float(rng.random() < p)))
        if n in checkpoints:
            tau = kendalltau(fit(names, votes).theta, truth).statistic
            out.append(float(tau))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--systems", type=int, default=8, help="Number of systems (8: the fixed TRUTH_8 strengths).")
    ap.add_argument("--reps", type=int, default=20, help="Repetitions (seeds 0..reps-1), the same for both designs.")
    ap.add_argument("--votes", type=int, default=1400, help="Votes per repetition (the last checkpoint).")
    ap.add_argument("--exploration", type=float, default=0.2, help="Uniform exploration rate of the adaptive design.")
    ap.add_argument("--target", type=float, default=0.9, help="Mean Kendall tau whose votes the last lines compare.")
    args = ap.parse_args()
    truth = truth_for(args.systems)
    checkpoints = sorted({v for v in (25, 50, 100, 150, 200, 300, 400, 600, 800, 1000, 1200, 1400, 2000, 3000)
                          if v <= args.votes} | {args.votes})
    print(f"{args.systems} systems, strengths {', '.join(f'{t:g}' for t in truth)}; {args.reps} repetitions; "
          f"exploration {args.exploration:g}; load {os.getloadavg()[0]:.2f}")
    taus = {}
    for design in ("balanced", "adaptive"):
        t0 = time.perf_counter()
        taus[design] = np.array([simulate(design, truth, checkpoints, args.exploration, seed)
                                 for seed in tqdm(range(args.reps), desc=design, leave=False)])
        print(f"{design}: {time.perf_counter() - t0:.1f} s")
    print(f"{'votes':>6}  {'balanced tau':>14}  {'adaptive tau':>14}")
    for k, v in enumerate(checkpoints):
        row = [f"{taus[d][:, k].mean():.3f} ± {taus[d][:, k].std(ddof=1) / np.sqrt(args.reps):.3f}"
               if args.reps > 1 else f"{taus[d][0, k]:.3f}" for d in ("balanced", "adaptive")]
        print(f"{v:>6}  {row[0]:>14}  {row[1]:>14}")
    need = {}
    for d in ("balanced", "adaptive"):
        reached = [v for k, v in enumerate(checkpoints) if taus[d][:, k].mean() >= args.target]
        need[d] = reached[0] if reached else None
        print(f"votes to mean tau >= {args.target:g}, {d}: {need[d] if need[d] else f'> {checkpoints[-1]}'}")
    if need["balanced"] and need["adaptive"]:
        print(f"ratio adaptive / balanced: {need['adaptive'] / need['balanced']:.2f}")


if __name__ == "__main__":
    main()
