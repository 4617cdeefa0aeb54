"""Encoders, the Bradley-Terry head and its held-out evaluation (see the package docstring)."""
from __future__ import annotations

import pathlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize
from scipy.special import expit, log_expit

from evalsuite.analysis.io import read_any
from evalsuite.analysis.pairwise import is_mismatch
from evalsuite.errors import InputError
from evalsuite.metrics.frechet import frechet_distance_samples
from evalsuite.registry import Registry

__all__ = ["ENCODERS", "Encoder", "kinematic_windows", "load_votes", "fit_head", "agreement", "evaluate"]

MOTION_SUFFIXES = (".bvh", ".npy", ".npz", ".csv")


@dataclass(frozen=True)
class Encoder:
    """``make(options)`` gives a function from a motion to its window features ``(N, D)``."""

    name: str
    summary: str
    make: Callable[[dict], Callable[[object], np.ndarray]]


def kinematic_windows(motion, seconds: float = 1.0) -> np.ndarray:
    """Window features ``(N, 3J)``: per joint, log(1e-6 + mean |v|), log(1e-6 + mean |a|), log(1e-6 + mean |j|)
    over 1-second windows with half-window stride (speed, acceleration, jerk by finite differences of the
    positions ``(T, J, 3)``, in file units per second^k)."""
    pos = np.asarray(motion.positions(), dtype=float)
    fps = float(motion.fps)
    v = np.linalg.norm(np.diff(pos, axis=0), axis=-1) * fps
    a = np.linalg.norm(np.diff(pos, 2, axis=0), axis=-1) * fps ** 2
    j = np.linalg.norm(np.diff(pos, 3, axis=0), axis=-1) * fps ** 3
    w = max(4, int(round(seconds * fps)))
    n = len(j)
    if n < w:
        raise InputError(f"motion of {len(pos)} frames is shorter than one {w}-frame window")
    starts = range(0, n - w + 1, max(1, w // 2))
    return np.array([np.log(1e-6 + np.concatenate([x[s:s + w].mean(0) for x in (v, a, j)])) for s in starts])


def _fgd_encoder(options: dict) -> Callable[[object], np.ndarray]:
    from evalsuite.learned.modelfile import load_model  # needs the learned extra (torch)

    if not options.get("fgd_model"):
        raise InputError("the fgd encoder needs the FGD model file (--fgd-model)")
    model = load_model(options["fgd_model"])
    return model.features


ENCODERS: Registry[Encoder] = Registry("critic encoder", "evalsuite.critic_encoders", base=Encoder,
                                       name_of=lambda e: e.name, field="encoder")
ENCODERS.register("kinematic", Encoder("kinematic", "log speed/acceleration/jerk per joint (numpy)",
                                       lambda options: kinematic_windows), origin="builtin")
ENCODERS.register("fgd", Encoder("fgd", "evalsuite's FGD encoder (learned extra, --fgd-model)", _fgd_encoder),
                  origin="builtin")


def load_votes(path, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    """Pairwise votes ``participant, segment, condition_a, condition_b, answer`` (a/b/tie) from an evalsuite
    results.csv or a battles CSV (training, attention checks and matched-vs-mismatched pages left out)."""
    d = read_any(pathlib.Path(path), study=study)
    d = d[(d["page_type"] == "pairwise") & (d["is_training"].astype(int) == 0)
          & (d["is_attention_check"].astype(int) == 0)]
    d = d[~is_mismatch(d["condition_a"], d["condition_b"], ":mismatched")]
    if question:
        d = d[d["question"] == question]
    elif d["question"].nunique() > 1:
        raise InputError(f"votes on several questions ({', '.join(sorted(set(d['question'])))}): pick one with "
                         "--question", path=path, field="question")
    if d.empty:
        raise InputError("no pairwise votes in the file (after leaving out training, checks and mismatch pages)",
                         path=path)
    return d[["participant", "segment", "condition_a", "condition_b", "answer"]].reset_index(drop=True)


def find_motion(root: pathlib.Path, condition: str, segment: str) -> pathlib.Path:
    """``root/<condition>/<segment>.<bvh|npy|npz|csv>``."""
    for suffix in MOTION_SUFFIXES:
        p = root / condition / f"{segment}{suffix}"
        if p.is_file():
            return p
    raise InputError(f"no motion for condition {condition!r}, segment {segment!r}: expected "
                     f"{root / condition / segment}.bvh (or .npy, .npz, .csv)", path=root)


def fit_head(diffs: np.ndarray, y: np.ndarray, l2: float = 1.0) -> np.ndarray:
    """The head ``w`` (D,) maximising sum_i log sigmoid(sign_i * w . (e_a - e_b)_i) - l2/2 |w|^2, with
    ``diffs`` (N, D) = e_a - e_b and ``y`` (N,) 1 where a won, 0 where b won (L-BFGS, scipy)."""
    sign = np.where(y > 0, 1.0, -1.0)
    X = diffs * sign[:, None]

    def loss(w):
        z = X @ w
        return -log_expit(z).sum() + 0.5 * l2 * w @ w, -(X.T @ expit(-z)) + l2 * w

    res = optimize.minimize(loss, np.zeros(X.shape[1]), jac=True, method="L-BFGS-B")
    return np.asarray(res.x)


def agreement(score_a: np.ndarray, score_b: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per vote 1.0 if the higher-scored side won, 0.0 if the lower, 0.5 for equal scores (votes (N,), ties
    already left out)."""
    return np.where(score_a == score_b, 0.5, ((score_a > score_b) == (y > 0)).astype(float))


def rater_ci(hits: np.ndarray, raters: np.ndarray, n_boot: int, seed: int, alpha: float = 0.05):
    """Mean agreement and its percentile CI from resampling the raters (``default_rng(seed)``)."""
    names, inv = np.unique(raters, return_inverse=True)
    s = np.bincount(inv, hits, len(names))
    c = np.bincount(inv, minlength=len(names)).astype(float)
    counts = np.random.default_rng(seed).multinomial(len(names), np.full(len(names), 1 / len(names)), size=n_boot)
    boot = (counts @ s) / np.maximum(counts @ c, 1)
    lo, hi = np.percentile(boot, [100 * alpha / 2, 100 * (1 - alpha / 2)])
    return float(hits.mean()), float(lo), float(hi)


def evaluate(votes: pd.DataFrame, emb: dict, windows: dict, natural: str | None, *, folds: int = 5,
             l2: float = 1.0, n_boot: int = 1000, seed: int = 0) -> pd.DataFrame:
    """Held-out agreement of the head and of the Fréchet distance to ``natural`` (lower wins) on the same test
    votes, by rater (``folds`` folds of raters) and by system (leave one system out).

    ``emb``: (condition, segment) -> embedding (D,); ``windows``: condition -> pooled window features (N, D)."""
    v = votes[votes["answer"] != "tie"].reset_index(drop=True)
    y = (v["answer"] == "a").to_numpy(float)
    ea = np.stack([emb[(a, s)] for a, s in zip(v["condition_a"], v["segment"])])
    eb = np.stack([emb[(b, s)] for b, s in zip(v["condition_b"], v["segment"])])
    mu, sd = np.concatenate([ea, eb]).mean(0), np.concatenate([ea, eb]).std(0) + 1e-9
    diffs = (ea - eb) / sd
    fd = {}
    if natural is not None:
        fd = {c: frechet_distance_samples(windows[natural], windows[c]) for c in windows}
    splits: dict[str, list[np.ndarray]] = {"rater": [], "system": []}
    raters = v["participant"].to_numpy()
    order = np.random.default_rng(seed).permutation(np.unique(raters))
    for k in range(min(folds, len(order))):
        test = np.isin(raters, order[k::folds])
        splits["rater"].append(test)
    for system in sorted(set(v["condition_a"]) | set(v["condition_b"])):
        if system == natural:
            continue
        splits["system"].append(((v["condition_a"] == system) | (v["condition_b"] == system)).to_numpy())
    rows = []
    for split, masks in splits.items():
        hits, fhits, who = [], [], []
        for test in masks:
            train = ~test   # by system: training votes do not involve the held-out system
            if test.sum() == 0 or train.sum() == 0:
                continue
            w = fit_head(diffs[train], y[train], l2)
            sa, sb = (ea[test] - mu) / sd @ w, (eb[test] - mu) / sd @ w
            hits.append(agreement(sa, sb, y[test]))
            if fd:
                fa = -np.array([fd[c] for c in v.loc[test, "condition_a"]])
                fb = -np.array([fd[c] for c in v.loc[test, "condition_b"]])
                fhits.append(agreement(fa, fb, y[test]))
            who.append(raters[test])
        if not hits:
            continue
        r = np.concatenate(who)
        for scorer, hh in (("critic", hits), ("fd_natural", fhits)):
            if not hh:
                continue
            mean, lo, hi = rater_ci(np.concatenate(hh), r, n_boot, seed)
            rows.append(dict(split=split, scorer=scorer, agreement=mean, ci_low=lo, ci_high=hi,
                             n_votes=len(r), n_raters=len(set(r)), folds=len(hits)))
    return pd.DataFrame(rows, columns=["split", "scorer", "agreement", "ci_low", "ci_high", "n_votes", "n_raters",
                                       "folds"])
