"""Latent-space metrics of Gesture2Vec (Yazdian et al. 2022): NSD and codebook diversity.

NSD (neighbour sample distance), for a sequence's latent windows ``z_0 .. z_{N-1}``
(consecutive overlapping windows at the model's stride)::

    n_k(i) = ( ||z_{i-k} - z_i|| + ||z_{i+k} - z_i|| ) / 2,     i in [K, N - K), K = max(ks)
    NSD_k  = mean_i n_k(i) / mean_{a<b} ||z_a - z_b||

averaged over the windows of all sequences of a condition (neighbours never cross a sequence
boundary); the denominator is the mean pairwise Euclidean distance over all of the
condition's windows (exact up to ``max_pair_windows`` windows, beyond that over a seeded
random subset of that many). Lower = neighbouring windows closer than typical pairs
(smoother, more consistent motion). The reference (``scripts/Clustering.py``) uses the same
index range ``[2, N-2)`` for k = 1 and 2.

Codebook: k-means (``scipy.cluster.vq.kmeans2``, k-means++ init, seeded) on the natural
reference's latents; each condition's windows are assigned to their nearest code and

    Hellinger(p_ref, p_cond) = sqrt(1 - sum_i sqrt(p_i q_i))        in [0, 1]
    perplexity(p)            = exp(-sum_i p_i log(p_i + 1e-10))      in [1, n_codes]

(the reference's formulas; perplexity = the effective number of codes used).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.cluster.vq import kmeans2, vq
from scipy.spatial.distance import cdist

from evalsuite.errors import InputError


def mean_pairwise_distance(z: np.ndarray, *, max_windows: int = 4000, seed: int = 0, block: int = 1024) -> float:
    """Mean Euclidean distance over all unordered pairs of rows (seeded subset above ``max_windows``)."""
    z = np.asarray(z, dtype=np.float64)
    if len(z) < 2:
        raise InputError("need at least 2 windows for a mean pairwise distance")
    if len(z) > max_windows:
        z = z[np.sort(np.random.default_rng(seed).choice(len(z), max_windows, replace=False))]
    total = 0.0
    for s in range(0, len(z), block):
        total += float(cdist(z[s:s + block], z).sum())  # every pair twice, diagonal zero
    n = len(z)
    return total / (n * (n - 1))


def neighbour_distances(z: np.ndarray, k: int, margin: int) -> np.ndarray:
    """``n_k(i)`` for ``i in [margin, N - margin)`` of one sequence's latents ``(N, d)``."""
    n = len(z)
    if n - 2 * margin <= 0:
        return np.zeros(0)
    i = np.arange(margin, n - margin)
    return 0.5 * (np.linalg.norm(z[i - k] - z[i], axis=1) + np.linalg.norm(z[i + k] - z[i], axis=1))


def nsd(sequences: list[np.ndarray], ks=(1, 2), *, max_pair_windows: int = 4000, seed: int = 0) -> dict:
    """NSD for each offset ``k`` over per-sequence latent arrays; see the module docstring.

    Returns ``{"nsd_k1": ..., "nsd_k1_raw": ..., "nsd_k1_std": ..., ..., "mean_pairwise_distance": ...,
    "n_windows": ..., "n_neighbourhoods": ...}`` (``_raw``: unnormalised mean, ``_std``: std of
    the normalised values).
    """
    seqs = [np.asarray(s, dtype=np.float64) for s in sequences if len(s)]
    if not seqs:
        raise InputError("no latent windows for NSD")
    margin = max(ks)
    denom = mean_pairwise_distance(np.concatenate(seqs), max_windows=max_pair_windows, seed=seed)
    out = {"mean_pairwise_distance": denom, "n_windows": int(sum(len(s) for s in seqs))}
    for k in ks:
        d = np.concatenate([neighbour_distances(s, k, margin) for s in seqs])
        if len(d) == 0:
            raise InputError(f"NSD needs sequences of at least {2 * margin + 1} windows; none is that long")
        out[f"nsd_k{k}_raw"] = float(d.mean())
        out[f"nsd_k{k}"] = float(d.mean() / denom) if denom > 0 else math.nan
        out[f"nsd_k{k}_std"] = float((d / denom).std()) if denom > 0 else math.nan
        out["n_neighbourhoods"] = int(len(d))
    return out


def fit_codebook(latents: np.ndarray, n_codes: int = 64, *, seed: int = 0, iterations: int = 50) -> np.ndarray:
    """Code vectors ``(n_codes, d)`` from seeded k-means (k-means++ init) on natural latents."""
    z = np.asarray(latents, dtype=np.float64)
    if n_codes < 2:
        raise InputError(f"n_codes must be at least 2, got {n_codes}")
    if len(z) < n_codes:
        raise InputError(f"{len(z)} reference windows cannot fit {n_codes} codes; use fewer codes")
    centroids, _ = kmeans2(z, n_codes, iter=iterations, minit="++", rng=np.random.default_rng(seed))
    return centroids


def code_histogram(latents: np.ndarray, codebook: np.ndarray) -> np.ndarray:
    """Counts of windows per nearest code ``(n_codes,)``."""
    codes, _ = vq(np.asarray(latents, dtype=np.float64), codebook)
    return np.bincount(codes, minlength=len(codebook)).astype(np.float64)


def hellinger(h1: np.ndarray, h2: np.ndarray) -> float:
    """Hellinger distance between two histograms (normalised to probabilities first)."""
    p = np.asarray(h1, dtype=np.float64)
    q = np.asarray(h2, dtype=np.float64)
    if p.shape != q.shape or p.sum() <= 0 or q.sum() <= 0:
        raise InputError("histograms must have the same shape and positive totals")
    p, q = p / p.sum(), q / q.sum()
    return float(math.sqrt(max(0.0, 1.0 - float(np.sqrt(p * q).sum()))))


def perplexity(h: np.ndarray) -> float:
    """``exp(-sum p log(p + 1e-10))`` of a histogram (the reference's formula)."""
    p = np.asarray(h, dtype=np.float64)
    p = p / p.sum()
    return float(np.exp(-(p * np.log(p + 1e-10)).sum()))


def score_latent(model, reference: dict, conditions: dict, *, n_codes: int = 64, ks=(1, 2), seed: int = 0,
                 reference_name: str = "reference", stride: int | None = None) -> list[dict]:
    """NSD and codebook rows for the reference and every condition.

    Rows: ``condition, metric (nsd_k1, nsd_k2, codebook_hellinger, codebook_perplexity), value,
    unit, model_hash, window, n_windows, resampled`` (files of that set resampled to the
    model's frame rate, as in :func:`~evalsuite.learned.fgd.score_fgd`). NSD is NaN for a set none of whose sequences has
    ``2 max(ks) + 1`` windows.
    """
    from evalsuite.learned.fgd import WindowSet
    from evalsuite.learned.modelfile import FeatureModel, load_model

    model = model if isinstance(model, FeatureModel) else load_model(model)
    ref = WindowSet(model, reference, raw=False, label="reference", stride=stride)
    ref_all = ref.all_features
    n_codes = min(n_codes, len(ref_all))
    codebook = fit_codebook(ref_all, n_codes, seed=seed)
    ref_hist = code_histogram(ref_all, codebook)
    rows = []

    from evalsuite.learned.fgd import resampled_text

    def add(condition, metric, value, unit, n, ws):
        rows.append({"condition": condition, "metric": metric, "value": float(value), "unit": unit,
                     "model_hash": model.content_hash, "window": model.window, "n_windows": int(n),
                     "resampled": resampled_text(ws.resampled)})

    sets = [(reference_name, ref)] + [(name, WindowSet(model, conditions[name], raw=False, label=str(name),
                                                       stride=stride)) for name in conditions]
    for name, ws in sets:
        try:
            res = nsd(ws.features, ks, seed=seed)
        except InputError:  # no sequence long enough for the neighbourhoods: NSD undefined, not fatal
            res = {f"nsd_k{k}": math.nan for k in ks}
        for k in ks:
            add(name, f"nsd_k{k}", res[f"nsd_k{k}"], "ratio", ws.n_windows, ws)
        hist = ref_hist if ws is ref else code_histogram(ws.all_features, codebook)
        add(name, "codebook_hellinger", hellinger(ref_hist, hist), "", ws.n_windows, ws)
        add(name, "codebook_perplexity", perplexity(hist), f"codes (of {n_codes})", ws.n_windows, ws)
    return rows
