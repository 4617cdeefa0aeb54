"""The GENEA Leaderboard's objective metrics on arrays, computed as the organisers' script computes them.

Facts from ``GENEALeaderboard/objective_metric`` (``exp_eval_metrics.py``, ``emage_evaltools/metric_modified.py``);
docs/leaderboard.md lists every quirk reproduced here. Shapes: a *pose sequence* is ``(T, 165)`` axis-angle
(55 SMPL-X joints x 3, radians, global orientation, jaw and eyes included, NaN already read as 0); a *position
sequence* is ``(T, 55, 3)`` or ``(T, 165)`` joint positions in metres (the Leaderboard's zeroing, see
:func:`evalsuite.motion.smplx_body.smplx_positions` ``mode="leaderboard"``).

Beat alignment (``bc_a2m``, ``bc_m2a``) is in :mod:`evalsuite.leaderboard.beats`.
"""
from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import linalg

from evalsuite.errors import InputError

__all__ = ["FD_EPS", "SRGR_THRESHOLD", "SRGR_SCALE", "SEM_FPS", "gaussian", "frechet_published", "frechet_fgd", "frechet_fgd_stats",
           "fid_g", "fid_k", "var_k", "sample_div", "l1_div_terms", "div", "read_sem", "semantic_weights",
           "srgr_rate", "srgr"]

FD_EPS = 1e-6          # the eps of both Fréchet distances of the script
SRGR_THRESHOLD = 0.1   # metres: a joint "succeeds" closer than this to the ground truth
SRGR_SCALE = 0.1672    # the fixed divisor of SRGR ("range [0, 1] when all succeed"; it is not a bound)
SEM_FPS = 30           # frames per second the sem times are converted with


def gaussian(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean (D,) and unbiased covariance (D, D) (``np.cov(rowvar=False)``, N-1) of samples ``x`` (N, D)."""
    x = np.asarray(x, dtype=np.float64)
    return x.mean(axis=0), np.atleast_2d(np.cov(x, rowvar=False))


def frechet_published(mu1: np.ndarray, sigma1: np.ndarray, mu2: np.ndarray, sigma2: np.ndarray,
                      eps: float = FD_EPS) -> float:
    """Fréchet distance as ``calculate_frechet_distance`` of the script (FD_g and FD_k):

        FD = |mu1 - mu2|^2 + tr S1 + tr S2 - 2 tr sqrtm(S1 S2)

    ``sqrtm`` of the (non-symmetric) product; when it is not finite it is retried on ``(S1 + eps I)(S2 + eps I)``;
    a complex result whose diagonal has an imaginary part above 1e-3 is an error, otherwise its real part is used.
    No clipping at 0 (evalsuite's own :func:`evalsuite.metrics.frechet.frechet_distance` clips and uses the
    symmetric form).
    """
    mu1, mu2 = np.atleast_1d(mu1), np.atleast_1d(mu2)
    sigma1, sigma2 = np.atleast_2d(sigma1), np.atleast_2d(sigma2)
    if mu1.shape != mu2.shape or sigma1.shape != sigma2.shape:
        raise InputError(f"Fréchet distance of different dimensions: {mu1.shape} vs {mu2.shape}")
    diff = mu1 - mu2
    covmean = linalg.sqrtm(sigma1 @ sigma2)
    if not np.isfinite(covmean).all():
        offset = np.eye(sigma1.shape[0]) * eps
        covmean = linalg.sqrtm((sigma1 + offset) @ (sigma2 + offset))
    if np.iscomplexobj(covmean):
        if not np.allclose(np.diagonal(covmean).imag, 0, atol=1e-3):
            raise InputError(f"Fréchet distance: sqrtm has an imaginary component {np.max(np.abs(covmean.imag)):.3g} "
                             "(the organisers' script stops here too)")
        covmean = covmean.real
    return float(diff @ diff + np.trace(sigma1) + np.trace(sigma2) - 2.0 * np.trace(covmean))


def frechet_fgd(a: np.ndarray, b: np.ndarray, eps: float = FD_EPS) -> float:
    """Fréchet distance as ``FGD.frechet_distance`` (the latents of FGD): samples ``a`` (N, D), ``b`` (M, D),

        FD = |mu_a - mu_b|^2 + tr S_a + tr S_b - 2 Re tr sqrtm((S_a + eps I)(S_b + eps I))

    (eps always added inside the square root only; no retry, no imaginary-part check)."""
    return frechet_fgd_stats(*gaussian(a), *gaussian(b), eps=eps)


def frechet_fgd_stats(mu1: np.ndarray, s1: np.ndarray, mu2: np.ndarray, s2: np.ndarray, eps: float = FD_EPS) -> float:
    """:func:`frechet_fgd` from the means and covariances of the two sides."""
    diff = mu1 - mu2
    offset = np.eye(s1.shape[0]) * eps
    covmean = linalg.sqrtm((s1 + offset) @ (s2 + offset))
    if np.iscomplexobj(covmean):
        covmean = covmean.real
    return float(diff @ diff + np.trace(s1) + np.trace(s2) - 2.0 * np.trace(covmean))


def _stack(seqs: Sequence[np.ndarray], what: str) -> np.ndarray:
    if not seqs:
        raise InputError(f"{what}: no sequences")
    return np.concatenate([np.asarray(s, dtype=np.float64).reshape(len(s), -1) for s in seqs], axis=0)


def fid_g(gt: Sequence[np.ndarray], pred: Sequence[np.ndarray]) -> float:
    """FD_g: :func:`frechet_published` between Gaussians of every ground-truth frame and every predicted frame.

    ``gt``: one (T_i, 165) per recording; ``pred``: one (T'_j, 165) per sample used (all samples of every
    recording with ``--sampling all``). Frames are pooled at each sequence's own full length: the script pairs
    ground truth and predictions by list position and does not cut them to a common length.
    """
    g, p = _stack(gt, "fid_g ground truth"), _stack(pred, "fid_g predictions")
    return frechet_published(*gaussian(g), *gaussian(p))


def fid_k(gt: Sequence[np.ndarray], pred: Sequence[np.ndarray]) -> float:
    """FD_k: as :func:`fid_g` on frame differences ``x[t+1] - x[t]`` (T-1, 165) of each sequence (no fps scaling)."""
    g = _stack([np.diff(np.asarray(s, dtype=np.float64), axis=0) for s in gt], "fid_k ground truth")
    p = _stack([np.diff(np.asarray(s, dtype=np.float64), axis=0) for s in pred], "fid_k predictions")
    return frechet_published(*gaussian(g), *gaussian(p))


def var_k(pred: Sequence[np.ndarray]) -> float:
    """Div_k: ``mean_j mean_d var_t x_j[t, d]`` over the samples used ``pred`` (each (T_j, 165)); the variance over
    time per dimension has ddof 0 (``np.var``)."""
    if not pred:
        raise InputError("var_k: no sequences")
    return float(np.concatenate([np.var(np.asarray(p, dtype=np.float64).reshape(len(p), -1), axis=0)
                                 for p in pred]).mean())


def sample_div(groups: Mapping[str, Sequence[np.ndarray]]) -> float:
    """Div_sample: per recording r with samples ``x_1 .. x_S`` (S >= 2), each cut to the shortest length T_r,

        div_r = mean_{t, d} var_s x_s[t, d]      (variance across samples, ddof 0, of the flattened (S, T_r*165))

    and the mean of div_r over recordings. Raises InputError naming a recording with fewer than 2 samples (the
    script prints "Aborting" and leaves the metric out)."""
    if not groups:
        raise InputError("sample_div: no recordings with samples named <video_id>_<k>")
    values = []
    for video_id, samples in groups.items():
        if len(samples) < 2:
            raise InputError(f"sample_div needs at least 2 samples per recording; {video_id} has {len(samples)} "
                             "(name them <video_id>_<k>.npz)")
        n = min(len(s) for s in samples)
        flat = np.stack([np.asarray(s, dtype=np.float64)[:n].reshape(-1) for s in samples])
        values.append(float(np.var(flat, axis=0).mean()))
    return float(np.mean(values))


def l1_div_terms(positions: np.ndarray) -> tuple[float, int]:
    """``(sum_{t,d} |x[t, d] - mean_t x[:, d]|, T)`` of one position sequence (T, 165)."""
    x = np.asarray(positions, dtype=np.float64)
    x = x.reshape(len(x), -1)
    return float(np.abs(x - x.mean(axis=0)).sum()), len(x)


def div(positions: Sequence[np.ndarray]) -> float:
    """L1div (Div_pose): ``sum_i sum_{t,d} |x_i[t, d] - mean_t x_i[:, d]| / sum_i T_i`` over the predicted position
    sequences used (each (T_i, 55, 3), cut to the ground truth's length)."""
    terms = [l1_div_terms(p) for p in positions]
    total = sum(n for _, n in terms)
    return sum(s for s, _ in terms) / total if total else 0.0


def read_sem(path: str | os.PathLike[str]) -> list[tuple[float, float, float]]:
    """``(start, end, weight)`` per line of a BEAT2 ``sem/<video_id>.txt``: tab-separated
    ``label, start, end, duration, weight[, comment]`` (seconds), read as the script reads it (pandas, no header)."""
    import pandas as pd

    try:
        table = pd.read_csv(path, sep="\t", header=None, names=["label", "start", "end", "duration", "weight",
                                                                 "comment"])
    except FileNotFoundError:
        raise InputError("no such semantic annotation file (expected BEAT2's sem/<video_id>.txt)", path=path) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError(f"not a BEAT2 semantic file ({exc}); expected tab-separated label, start, end, duration, "
                         "weight", path=path) from None
    rows = []
    for i, (s, e, w) in enumerate(zip(table["start"], table["end"], table["weight"]), start=1):
        try:
            s, e, w = float(s), float(e), float(w)
        except (TypeError, ValueError):
            raise InputError(f"expected numbers for start, end and weight (columns 2, 3, 5), found {s!r}, {e!r}, "
                             f"{w!r}", path=path, line=i) from None
        if not all(math.isfinite(v) for v in (s, e, w)):
            raise InputError("missing start, end or weight (columns 2, 3, 5 of a tab-separated line)", path=path,
                             line=i)
        rows.append((s, e, w))
    return rows


def semantic_weights(rows: Sequence[tuple[float, float, float]], n_frames: int, fps: float = SEM_FPS) -> np.ndarray:
    """Per-frame weights (n_frames,) float32 as the script builds them: for each ``(start, end, w)`` with end > start,
    frames ``floor(start*fps) .. ceil(end*fps) - 1`` take ``max(current, w)``; frames outside every interval are 0."""
    out = np.zeros(n_frames, dtype=np.float32)
    for s, e, w in rows:
        if e <= s:
            continue
        a, b = int(np.floor(s * fps)), int(np.ceil(e * fps))
        out[a:b] = np.maximum(out[a:b], w)
    return out


def srgr_rate(pred: np.ndarray, gt: np.ndarray, weights: np.ndarray, threshold: float = SRGR_THRESHOLD,
              scale: float = SRGR_SCALE) -> float:
    """SRGR of one sequence: ``sum_{t,j} [|p[t,j] - g[t,j]|_2 < threshold] * w[t] / scale  /  (T * J)`` for positions
    (T, J, 3) (or (T, 3J)) and frame weights (T,). With the fixed scale 0.1672 it exceeds 1 when the weights of
    the frames average more than 0.1672."""
    p = np.asarray(pred, dtype=np.float64)
    g = np.asarray(gt, dtype=np.float64)
    p, g = p.reshape(len(p), -1, 3), g.reshape(len(g), -1, 3)
    if p.shape != g.shape or len(weights) != len(p):
        raise InputError(f"srgr: shapes {p.shape}, {g.shape} and {len(weights)} weights do not match")
    hit = (np.linalg.norm(p - g, axis=2) < threshold).astype(np.float64)
    # the script multiplies each frame's hits by its float32 weight times (1 / scale), in float64 (NumPy 1.x)
    w = np.asarray(weights, dtype=np.float32).astype(np.float64) * (1.0 / scale)
    return float((hit * w[:, None]).sum() / hit.size)


def srgr(sequences: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> float:
    """SRGR over sequences ``(pred, gt, weights)``: ``sum_i rate_i T_i / sum_i T_i`` (:func:`srgr_rate`)."""
    total = sum(len(w) for _, _, w in sequences)
    if not total:
        raise InputError("srgr: no frames")
    return sum(srgr_rate(p, g, w) * len(w) for p, g, w in sequences) / total
