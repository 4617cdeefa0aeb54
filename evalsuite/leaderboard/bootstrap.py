"""Confidence intervals for the Leaderboard preset: the organisers' bootstrap and evalsuite's.

* :func:`leaderboard_bootstrap`, as ``evaluation_bootstrap`` of the script (FGD, FD_g and FD_k only): the
  pooled rows of each side (latents; frames; frame differences) are resampled with replacement, each side on
  its own, B times (the script: 1000), and the distance recomputed; reported are the mean and the 2.5 and 97.5
  percentiles (each distance with the trace term from the symmetric form, equal to the script's ``sqrtm`` up
  to rounding and much faster). Its data are assembled as that function does: for FD_g/FD_k the ground truth is cut to each
  sample's length t and repeated once per sample used (unlike the point value, which pools the ground truth
  once at full length); FGD's sides are those of the point value.
* :func:`recording_bootstrap`, evalsuite's: recordings (the sampling unit) are resampled with replacement and
  every metric is recomputed from its per-recording parts; reported are the 2.5 and 97.5 percentiles and the
  standard deviation.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from evalsuite.leaderboard import metrics as lm
from evalsuite.metrics.frechet import trace_sqrt_product

__all__ = ["Pieces", "pooled_gaussian", "recording_bootstrap", "leaderboard_bootstrap"]

_Stats = tuple[int, np.ndarray, np.ndarray]   # (n, mean (D,), centred sum of squares (D, D))


def _stats(x: np.ndarray) -> _Stats:
    x = np.asarray(x, dtype=np.float64).reshape(len(x), -1)
    mu = x.mean(axis=0)
    c = x - mu
    return len(x), mu, c.T @ c


def _merge(parts: list[_Stats]) -> _Stats:
    """Pooled statistics (Chan et al.): ``M2 = sum_i M2_i + n_i (mu_i - mu)(mu_i - mu)^T``."""
    n = sum(p[0] for p in parts)
    mu = np.sum([p[0] * p[1] for p in parts], axis=0) / n
    m2 = np.sum([p[2] + p[0] * np.outer(p[1] - mu, p[1] - mu) for p in parts], axis=0)
    return n, mu, m2


@dataclass
class Pieces:
    """One recording's parts of every metric (what :func:`recording_bootstrap` recombines)."""

    video_id: str
    fd: dict[str, tuple[list[_Stats], list[_Stats]]] = field(default_factory=dict)
    var_k: list[float] = field(default_factory=list)
    sample_div: float | None = None
    div: tuple[float, int] = (0.0, 0)
    srgr: tuple[float, int] = (0.0, 0)
    bc: tuple[float, float, int] = (0.0, 0.0, 0)

    def add_fd(self, metric: str, a: np.ndarray | None, b: np.ndarray | None) -> None:
        """Add rows to side a (ground truth) and/or side b (predictions) of a Fréchet distance."""
        sides = self.fd.setdefault(metric, ([], []))
        for side, x in zip(sides, (a, b)):
            if x is not None and len(x):
                side.append(_stats(x))


def pooled_gaussian(pieces: list[Pieces], metric: str, side: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean (D,) and unbiased covariance (D, D) of every row of ``side`` (0: ground truth, 1: predictions) of a
    Fréchet distance over ``pieces``: :func:`evalsuite.leaderboard.metrics.gaussian` of the pooled rows, from the
    recordings' statistics (equal up to rounding; the rows need not be held)."""
    n, mu, m2 = _merge([s for p in pieces for s in p.fd[metric][side]])
    return mu, np.atleast_2d(m2 / (n - 1))


def _fd(pieces: list[Pieces], metric: str) -> float:
    a = _merge([s for p in pieces for s in p.fd[metric][0]])
    b = _merge([s for p in pieces for s in p.fd[metric][1]])
    return _fd_fast(a[1], a[2] / (a[0] - 1), b[1], b[2] / (b[0] - 1), lm.FD_EPS if metric == "fgd" else 0.0)


def _fd_fast(mu1: np.ndarray, s1: np.ndarray, mu2: np.ndarray, s2: np.ndarray, eps: float) -> float:
    """The script's Fréchet distance with ``tr sqrtm((S1 + eps I)(S2 + eps I))`` from the symmetric form
    (:func:`evalsuite.metrics.frechet.trace_sqrt_product`: equal up to rounding, a fraction of ``sqrtm``'s cost)."""
    diff = mu1 - mu2
    off = np.eye(len(s1)) * eps
    return float(diff @ diff + np.trace(s1) + np.trace(s2) - 2.0 * trace_sqrt_product(s1 + off, s2 + off))


def _value(pieces: list[Pieces], metric: str) -> float:
    if metric in ("fid_g", "fid_k", "fgd"):
        return _fd(pieces, metric)
    if metric == "var_k":
        return float(np.mean([v for p in pieces for v in p.var_k]))
    if metric == "sample_div":
        return float(np.mean([p.sample_div for p in pieces if p.sample_div is not None]))
    if metric in ("div", "srgr"):
        parts = [getattr(p, metric) for p in pieces]
        return sum(s for s, _ in parts) / sum(n for _, n in parts)
    k = 0 if metric == "bc_a2m" else 1
    return sum(p.bc[k] for p in pieces) / sum(p.bc[2] for p in pieces)


def recording_bootstrap(pieces: list[Pieces], metrics: dict[str, float] | list[str], n_boot: int, seed: int = 0
                        ) -> dict[str, tuple[float, float, float]]:
    """``metric -> (2.5th percentile, 97.5th percentile, std)`` over ``n_boot`` resamples of the recordings."""
    rng = np.random.default_rng(seed)
    draws: dict[str, list[float]] = {m: [] for m in metrics}
    for _ in range(n_boot):
        idx = rng.integers(0, len(pieces), len(pieces))
        chosen = [pieces[i] for i in idx]
        for m in draws:
            try:
                draws[m].append(_value(chosen, m))
            except (ValueError, ZeroDivisionError, np.linalg.LinAlgError):
                draws[m].append(np.nan)
    return {m: (float(np.nanpercentile(v, 2.5)), float(np.nanpercentile(v, 97.5)), float(np.nanstd(v, ddof=1)))
            for m, v in draws.items() if np.isfinite(v).any()}


def leaderboard_bootstrap(frames: dict[str, list[np.ndarray]], n_boot: int, seed: int = 0
                          ) -> dict[str, tuple[float, float, float]]:
    """``metric -> (mean, 2.5th percentile, 97.5th percentile)`` of the organisers' bootstrap for ``fgd`` (keys
    ``fgd_a``, ``fgd_b`` of ``frames``: the latents of each side), ``fid_g`` (``fd_g_gt``, ``fd_g_pred``) and
    ``fid_k`` (``fd_k_gt``, ``fd_k_pred``)."""
    rng = np.random.RandomState(seed)
    out: dict[str, tuple[float, float, float]] = {}
    for metric, a_key, b_key in (("fgd", "fgd_a", "fgd_b"), ("fid_g", "fd_g_gt", "fd_g_pred"),
                                 ("fid_k", "fd_k_gt", "fd_k_pred")):
        if not frames.get(a_key) or not frames.get(b_key):
            continue
        a, b = np.concatenate(frames[a_key]), np.concatenate(frames[b_key])
        vals = []
        for _ in range(n_boot):
            ia = rng.randint(len(a), size=len(a))
            ib = rng.randint(len(b), size=len(b))
            vals.append(_fd_fast(*lm.gaussian(a[ia]), *lm.gaussian(b[ib]), lm.FD_EPS if metric == "fgd" else 0.0))
        arr = np.asarray(vals)
        out[metric] = (float(arr.mean()), float(np.percentile(arr, 2.5)), float(np.percentile(arr, 97.5)))
    return out
