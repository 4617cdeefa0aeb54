"""Fréchet Gesture Distance (FGD) in the encoder's feature space and in raw window space.

    FGD = FD( N(mu_ref, S_ref), N(mu_cond, S_cond) )
        = ||mu_ref - mu_cond||^2 + tr S_ref + tr S_cond - 2 tr (S_ref^1/2 S_cond S_ref^1/2)^1/2

* ``fgd``: the Gaussians are fitted to the 32-d encoder features of every window of the
  natural (reference) and of the generated (condition) sequences (Yoon et al. 2020; GENEA
  2020/2022/2023), computed with :func:`evalsuite.metrics.frechet.frechet_distance`
  (symmetric eigen form, no ``sqrtm``; clipped at 0). Unit: squared feature units.
* ``fgd_raw``: the same on the flattened z-normalised windows (``window x D`` dims; "FGD on
  raw data space", after Ahuja et al. 2020, GENEA 2020/2022). Unit: squared z-scores. With no
  more windows than dims the covariances are singular, as in the references; the trace term
  is computed exactly from the data matrices (see :func:`raw_frechet_distance`), so it costs
  one eigen-decomposition of size ``min(N_ref, N_cond, window*D)`` per condition.

Windows: every complete window (or the GENEA rule, stored in the model) at the model's fps,
joints and stride; sequences are resampled (interpolation, never silently: each output row's
``resampled`` field names the files and rates) and joints selected by name to match the model;
a sequence that cannot match (missing joints, shorter than one window) is an InputError.

Bootstrap CI (``fgd`` only): ``n_bootstrap`` resamples with replacement of whole sequences
(default; windows of one sequence are correlated) or of windows, drawn independently for
the reference and the condition; the percentile interval at ``ci_level`` moved so that the
resamples' median sits on the estimate (:func:`evalsuite.metrics.families.base.centred_ci`: it
contains the estimate; resamples with duplicate sequences have a smaller effective sample and so
a larger small-sample bias), with Efron's bootstrap bias (mean of the resamples minus the
estimate) in ``bootstrap_bias``. With fewer than 2 sequences on a side, windows are resampled
instead. Seeded: same inputs + seed = same CI.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import torch
from tqdm.auto import tqdm

from evalsuite.errors import InputError
from evalsuite.learned.modelfile import AnyFeatureModel, FeatureModel, load_model, torch_threads
from evalsuite.learned.representation import resampled_files
from evalsuite.metrics.families.base import bootstrap_bias, centred_ci
from evalsuite.metrics.frechet import FrechetWarning, frechet_distance, gaussian_stats

FEATURE_UNIT = "feature^2"
RAW_UNIT = "z^2"
ROW_KEYS = ("condition", "metric", "value", "unit", "ci_low", "ci_high", "model_hash", "window",
            "n_windows_reference", "n_windows_condition", "resampled", "bootstrap_bias")


class WindowSet:
    """Windows of a set of sequences: per-sequence features and (optionally) raw normalised windows."""

    def __init__(self, model: AnyFeatureModel, motions: dict, *, raw: bool, label: str, stride: int | None = None):
        if not motions:
            raise InputError(f"{label}: no sequences")
        self.names = sorted(motions)
        # provenance: which sequences the model resamples to its frame rate (interpolation)
        self.resampled = resampled_files({n: motions[n] for n in self.names}, model.fps, label)
        self.features: list[np.ndarray] = []
        raws = []
        for name in self.names:
            try:
                win = model.windows(motions[name], stride)
            except InputError as exc:
                raise InputError(f"{label}/{name}: {exc}") from None
            self.features.append(model.encode(win))
            if raw:
                raws.append(model.normalize(win).reshape(len(win), -1))
        self.raw = np.concatenate(raws) if raw else None

    @property
    def all_features(self) -> np.ndarray:
        return np.concatenate(self.features)

    @property
    def n_windows(self) -> int:
        return int(sum(len(f) for f in self.features))


def _unit_moments(groups: list[np.ndarray], shift: np.ndarray):
    """Counts, sums and outer-product sums per resampling unit (after subtracting ``shift``)."""
    counts = np.array([len(g) for g in groups], dtype=np.float64)
    centred = [g - shift for g in groups]
    sums = np.stack([c.sum(axis=0) for c in centred])
    outer = np.stack([(c.T @ c).ravel() for c in centred])
    return counts, sums, outer


def _resampled_gaussians(moments, weights: np.ndarray, shift: np.ndarray):
    counts, sums, outer = moments
    d = sums.shape[1]
    n = weights @ counts
    mu = (weights @ sums) / n[:, None]
    second = (weights @ outer).reshape(len(weights), d, d)
    cov = (second - n[:, None, None] * mu[:, :, None] * mu[:, None, :]) / (n - 1)[:, None, None]
    return mu + shift, cov


def _units(groups: list[np.ndarray], unit: str) -> list[np.ndarray]:
    if unit == "window" or len(groups) < 2:
        return [row[None] for g in groups for row in g]
    return [g for g in groups if len(g)]


def bootstrap_fd_samples(reference: list[np.ndarray], condition: list[np.ndarray], *, n_bootstrap: int = 1000,
                         unit: str = "sequence", seed: int = 0) -> np.ndarray:
    """The Fréchet distance of ``n_bootstrap`` resamples ``(B,)`` of two grouped sample sets.

    ``reference``/``condition`` are lists of per-sequence arrays ``(n_i, D)``; ``unit``
    ``"sequence"`` resamples whole arrays, ``"window"`` single rows (see module docstring).
    """
    if unit not in ("sequence", "window"):
        raise InputError(f"bootstrap unit must be 'sequence' or 'window', got {unit!r}")
    if n_bootstrap < 1:
        return np.zeros(0)
    rng = np.random.default_rng(seed)
    shift = np.concatenate(reference).mean(axis=0)
    sides = []
    for groups in (reference, condition):
        units = _units(groups, unit)
        u = len(units)
        weights = rng.multinomial(u, np.full(u, 1.0 / u), size=n_bootstrap).astype(np.float64)
        sides.append(_resampled_gaussians(_unit_moments(units, shift), weights, shift))
    (mu_r, cov_r), (mu_c, cov_c) = sides
    return batched_frechet_distance(mu_r, cov_r, mu_c, cov_c)


def bootstrap_fd(reference: list[np.ndarray], condition: list[np.ndarray], *, n_bootstrap: int = 1000,
                 unit: str = "sequence", seed: int = 0, ci_level: float = 0.95) -> tuple[float, float]:
    """Bootstrap interval of the Fréchet distance between two grouped sample sets: the percentile interval
    of :func:`bootstrap_fd_samples` moved to have its median on the estimate (``centred_ci``)."""
    samples = bootstrap_fd_samples(reference, condition, n_bootstrap=n_bootstrap, unit=unit, seed=seed)
    if not samples.size:
        return math.nan, math.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FrechetWarning)
        value = frechet_distance(*gaussian_stats(np.concatenate(reference)), *gaussian_stats(np.concatenate(condition)))
    return centred_ci(value, samples, level=ci_level)


def batched_frechet_distance(mu1, sigma1, mu2, sigma2) -> np.ndarray:
    """:func:`evalsuite.metrics.frechet.frechet_distance` for stacks ``(B, d)``, ``(B, d, d)``.

    The same symmetric eigen form (PSD square root of ``sigma1``, eigenvalues of
    ``sigma1^1/2 sigma2 sigma1^1/2``, negatives clipped, result clipped at 0) for the
    bootstrap's resamples, as batched float64 LAPACK calls through torch on one thread
    (small eigenproblems gain nothing from threads; on a busy machine threads cost 10x).
    """
    with torch_threads(1):
        s1 = torch.from_numpy(np.ascontiguousarray(sigma1, dtype=np.float64))
        s2 = torch.from_numpy(np.ascontiguousarray(sigma2, dtype=np.float64))
        w, v = torch.linalg.eigh((s1 + s1.transpose(-1, -2)) / 2)
        root = (v * w.clamp(min=0.0).sqrt().unsqueeze(-2)) @ v.transpose(-1, -2)
        inner = root @ s2 @ root
        eig = torch.linalg.eigvalsh((inner + inner.transpose(-1, -2)) / 2)
        tr_covmean = eig.clamp(min=0.0).sqrt().sum(dim=-1).numpy()
    diff = np.asarray(mu1, dtype=np.float64) - np.asarray(mu2, dtype=np.float64)
    raw = ((diff * diff).sum(axis=-1) + np.trace(sigma1, axis1=-2, axis2=-1)
           + np.trace(sigma2, axis1=-2, axis2=-1) - 2.0 * tr_covmean)
    return np.maximum(raw, 0.0)


class RawReference:
    """The reference side of the raw-space distance, reused for every condition.

    With ``A = (X - mean) / sqrt(N - 1)`` (so ``S = A^T A``), the eigenvalues of
    ``S_r^1/2 S_c S_r^1/2`` are the squared singular values of ``A_c F`` for any ``F`` with
    ``F F^T = S_r`` up to an orthogonal factor: ``F = A_r^T`` when ``N_r <= D`` (so
    ``A_c F = A_c A_r^T``, an ``N_c x N_r`` matrix), else ``F = V diag(sqrt(lambda))`` from the
    ``D x D`` eigendecomposition of ``S_r``. The trace term is then the sum of those singular
    values (the nuclear norm) — exact, without a ``D x D`` square root when ``D`` is large.
    """

    def __init__(self, x: np.ndarray):
        x = np.asarray(x, dtype=np.float64)
        if len(x) < 2:
            raise InputError("need at least 2 reference windows")
        self.mean = x.mean(axis=0)
        a = (x - self.mean) / math.sqrt(len(x) - 1)
        self.trace = float(np.einsum("ij,ij->", a, a))
        if a.shape[0] <= a.shape[1]:
            self.factor = a.T
        else:
            lam, v = np.linalg.eigh(a.T @ a)
            self.factor = v * np.sqrt(np.clip(lam, 0.0, None))

    def distance(self, y: np.ndarray) -> dict:
        y = np.asarray(y, dtype=np.float64)
        if y.ndim != 2 or y.shape[1] != self.mean.shape[0] or len(y) < 2:
            raise InputError(f"condition windows must have shape (N >= 2, {self.mean.shape[0]}), got {y.shape}")
        mu = y.mean(axis=0)
        a = (y - mu) / math.sqrt(len(y) - 1)
        c = a @ self.factor
        gram = c.T @ c if c.shape[1] <= c.shape[0] else c @ c.T
        eig = np.linalg.eigvalsh((gram + gram.T) / 2) if gram.size else np.zeros(0)
        tr_covmean = float(np.sqrt(np.clip(eig, 0.0, None)).sum())
        diff = self.mean - mu
        mean_term = float(diff @ diff)
        trace_term = self.trace + float(np.einsum("ij,ij->", a, a)) - 2.0 * tr_covmean
        raw = mean_term + trace_term
        return {"mean_term": mean_term, "trace_term": trace_term, "raw": raw, "value": max(raw, 0.0)}


def raw_frechet_distance(x: np.ndarray, y: np.ndarray) -> float:
    """Exact Fréchet distance between Gaussians fitted to ``x (N, D)`` and ``y (M, D)``, for large D.

    Same value as :func:`evalsuite.metrics.frechet.frechet_distance_samples` (up to round-off),
    computed from the data matrices so that ``D`` may exceed the number of samples.
    """
    return RawReference(x).distance(y)["value"]


def resampled_text(records: list[dict]) -> str:
    """``file (from -> to fps); ...`` for an output's provenance ("" when nothing was resampled)."""
    return "; ".join(f"{r['file']} ({r['from_fps']:g} -> {r['to_fps']:g} fps)" for r in records)


def _row(condition, metric, value, unit, ci, model, window, n_ref, n_cond, resampled="", bias=math.nan) -> dict:
    return {"condition": condition, "metric": metric, "value": float(value), "unit": unit,
            "ci_low": ci[0], "ci_high": ci[1], "model_hash": model.content_hash, "window": int(window),
            "n_windows_reference": int(n_ref), "n_windows_condition": int(n_cond), "resampled": resampled,
            "bootstrap_bias": float(bias)}


def score_fgd(model_path, reference: dict, conditions: dict, *, raw: bool = True, n_bootstrap: int = 1000,
              bootstrap_unit: str = "sequence", ci_level: float = 0.95, seed: int = 0,
              progress: bool = False) -> list[dict]:
    """FGD (and raw-space FGD) of every condition against natural reference motion.

    Args:
        model_path: a model file (or a loaded :class:`FeatureModel`).
        reference: ``{sequence name: Motion}`` of natural motion.
        conditions: ``{condition: {sequence name: Motion}}`` of generated motion.
        raw: also compute ``fgd_raw`` (point estimate only; CI fields are NaN).
        n_bootstrap, bootstrap_unit, ci_level, seed: the CI of ``fgd`` (0 resamples: NaN CI).

    Returns:
        rows (dicts) with keys ``condition, metric ("fgd" | "fgd_raw"), value, unit, ci_low,
        ci_high, model_hash, window, n_windows_reference, n_windows_condition, resampled,
        bootstrap_bias`` (``resampled``: the reference and condition files resampled by
        interpolation to the model's frame rate, ``file (from -> to fps); ...``, empty when none
        was; ``bootstrap_bias``: mean of the resampled FGDs minus the FGD, NaN without bootstrap).
    """
    model = model_path if isinstance(model_path, FeatureModel) else load_model(model_path)
    ref = WindowSet(model, reference, raw=raw, label="reference")
    ref_feat = ref.all_features
    if len(ref_feat) < 2:
        raise InputError(f"the reference gives {len(ref_feat)} window(s); need at least 2 for a covariance")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FrechetWarning)
        ref_stats = gaussian_stats(ref_feat)
    raw_ref = RawReference(ref.raw) if raw and ref.raw is not None else None
    rows = []
    for name in tqdm(list(conditions), desc="FGD", unit="condition", disable=not progress, leave=False):
        cond = WindowSet(model, conditions[name], raw=raw, label=str(name))
        feats = cond.all_features
        if len(feats) < 2:
            raise InputError(f"{name}: {len(feats)} window(s); need at least 2 for a covariance")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FrechetWarning)
            value = frechet_distance(*ref_stats, *gaussian_stats(feats))
        samples = bootstrap_fd_samples(ref.features, cond.features, n_bootstrap=n_bootstrap, unit=bootstrap_unit,
                                       seed=seed)
        ci = centred_ci(value, samples, level=ci_level) if samples.size else (math.nan, math.nan)
        bias = bootstrap_bias(value, samples) if samples.size else math.nan
        resampled = resampled_text(ref.resampled + cond.resampled)
        rows.append(_row(name, "fgd", value, FEATURE_UNIT, ci, model, model.window, ref.n_windows, cond.n_windows,
                         resampled, bias))
        if raw_ref is not None and cond.raw is not None:
            rows.append(_row(name, "fgd_raw", raw_ref.distance(cond.raw)["value"], RAW_UNIT, (math.nan, math.nan),
                             model, model.window, ref.n_windows, cond.n_windows, resampled))
    return rows
