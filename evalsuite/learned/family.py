"""FGD as a metric family of ``evalsuite score`` (``--fgd MODEL``), built on :mod:`evalsuite.learned.fgd`.

Per sequence (in the workers) the motion is cut into the model's windows and encoded; per condition the
Gaussians of the natural and the condition's features give FGD, with the bootstrap over sequences of
:func:`~evalsuite.learned.fgd.bootstrap_fd_samples` (interval centred on the estimate, bias beside it; too
small samples reported), and optionally the raw-space distance. Every condition also gets a row ``fgd_n``
(the condition's windows; ``n_windows_reference`` beside it); with ``n``, ``fgd[n=N]`` (FGD on N windows
per side, :func:`~evalsuite.learned.sample_size.fgd_at_n`); with ``infinity``, ``fgd_inf``
(:func:`~evalsuite.learned.sample_size.fgd_infinity`, and the data of its figure). This
module sits above :mod:`evalsuite.metrics` (it imports it, never the reverse); the ``score`` command adds
the family for a run when a model is given.
"""
from __future__ import annotations

import math
import pathlib
import warnings

import numpy as np

from evalsuite.errors import InputError
from evalsuite.learned.fgd import FEATURE_UNIT, RAW_UNIT, RawReference, bootstrap_fd_samples
from evalsuite.learned.modelfile import AnyFeatureModel, load_model
from evalsuite.learned.representation import needs_resampling
from evalsuite.learned.sample_size import fgd_at_n, fgd_infinity
from evalsuite.metrics.families import MetricFamily, MetricInfo, ReduceContext, SequenceContext
from evalsuite.metrics.families.base import bootstrap_bias, centred_ci
from evalsuite.metrics.frechet import FrechetWarning, frechet_distance, gaussian_stats, sample_size_warnings

__all__ = ["FGDFamily"]

_MODELS: dict[tuple[str, float], AnyFeatureModel] = {}   # per process: a worker loads each model once


def _model(path: str) -> AnyFeatureModel:
    key = (path, pathlib.Path(path).stat().st_mtime)
    if key not in _MODELS:
        _MODELS[key] = load_model(path)
    return _MODELS[key]


class FGDFamily(MetricFamily):
    """FGD (and, with ``raw=True``, the raw-space distance) against the natural motion, for one model."""

    name = "fgd"

    def __init__(self, model_path: str | pathlib.Path, raw: bool = False, n: int | None = None,
                 infinity: bool = False, draws: int = 200):
        self.model_path = str(model_path)
        self.raw, self.n, self.infinity, self.draws = raw, n, infinity, draws
        if n is not None and n < 2:
            raise InputError(f"--fgd-n needs at least 2 windows, got {n}", field="fgd-n")
        load_model(self.model_path)  # fail early, in the parent, on a missing or corrupt model
        self.metrics = (MetricInfo("fgd", FEATURE_UNIT, "lower", description="Fréchet gesture distance"),) + (
            (MetricInfo("fgd_raw", RAW_UNIT, "lower", description="Fréchet distance of raw windows"),)
            if raw else ()) + (
            (MetricInfo("fgd_inf", FEATURE_UNIT, "lower", description="FGD extrapolated to infinitely many windows"),)
            if infinity else ())

    def measure(self, ctx: SequenceContext) -> None:
        model = _model(self.model_path)
        if needs_resampling(ctx.motion.fps, model.fps):   # never silently: into the run's provenance
            ctx.record.setdefault("resampled", []).append(
                {"from_fps": float(ctx.motion.fps), "to_fps": float(model.fps), "why": "FGD model"})
        try:
            windows = model.windows(ctx.motion)
        except InputError as exc:
            ctx.record["fgd_error"] = exc.reason
            return
        ctx.record["fgd_features"] = model.encode(windows)
        if self.raw:
            ctx.record["fgd_raw_windows"] = model.normalize(windows).reshape(len(windows), -1)

    def bootstrap_work(self, setup) -> int:
        return 1

    def reduce(self, ctx: ReduceContext) -> None:
        if ctx.cond == ctx.reference:
            return
        sides = []
        for label, recs in (("reference", ctx.ref), (ctx.cond, ctx.recs)):
            bad = [f"{label}/{s}: {r['fgd_error']}" for s, r in sorted(recs.items()) if "fgd_error" in r]
            if bad:
                raise InputError("FGD: " + "; ".join(bad[:3]), field="fgd")
            sides.append([recs[s] for s in sorted(recs)])
        ref_feats = [r["fgd_features"] for r in sides[0]]
        cond_feats = [r["fgd_features"] for r in sides[1]]
        n_ref, n_cond = sum(len(f) for f in ref_feats), sum(len(f) for f in cond_feats)
        for label, n in (("the reference", n_ref), (ctx.cond, n_cond)):
            if n < 2:
                raise InputError(f"FGD: {label} gives {n} window(s); need at least 2 for a covariance", field="fgd")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FrechetWarning)
            value = frechet_distance(*gaussian_stats(np.concatenate(ref_feats)),
                                     *gaussian_stats(np.concatenate(cond_feats)))
        ctx.issues.extend(f"{ctx.cond}: fgd: {w}" for w in sample_size_warnings(
            (n_ref, n_cond), ref_feats[0].shape[1], (len(ref_feats), len(cond_feats)), "windows"))
        samples = bootstrap_fd_samples(ref_feats, cond_feats, n_bootstrap=ctx.n_bootstrap, seed=ctx.seed)
        ctx.advance(ctx.n_bootstrap)
        ci = centred_ci(value, samples) if samples.size else (math.nan, math.nan)
        model = _model(self.model_path)
        extra = {"model_hash": model.content_hash, "window": int(model.window),
                 "n_windows_reference": int(n_ref), "n_windows_condition": int(n_cond)}
        if samples.size:
            extra["bootstrap_bias"] = bootstrap_bias(value, samples)
        ctx.add("fgd", value, ci=ci, n=len(cond_feats))
        ctx.summary[-1].update(extra)
        ctx.add("fgd_n", n_cond, n=len(cond_feats), unit="windows", better="")
        ctx.summary[-1].update(extra)
        self._sample_size_rows(ctx, np.concatenate(ref_feats), np.concatenate(cond_feats), extra)
        if self.raw:
            raw = RawReference(np.concatenate([r["fgd_raw_windows"] for r in sides[0]]))
            ctx.add("fgd_raw", raw.distance(np.concatenate([r["fgd_raw_windows"] for r in sides[1]]))["value"],
                    ci=(math.nan, math.nan), n=len(cond_feats))
            ctx.summary[-1].update(extra)

    def _sample_size_rows(self, ctx: ReduceContext, ref: np.ndarray, cond: np.ndarray, extra: dict) -> None:
        """``fgd[n=N]`` and ``fgd_inf`` (see the module docstring); too few windows is an issue, not an error."""
        if self.n is not None:
            r = fgd_at_n(ref, cond, self.n, draws=self.draws, seed=ctx.seed)
            ctx.add(f"fgd[n={self.n}]", r["value"], std=r["std"], ci=(r["ci_low"], r["ci_high"]), n=self.n)
            ctx.summary[-1].update(extra, fgd_draws=self.draws)
            if r["with_replacement"]:
                ctx.issues.append(f"{ctx.cond}: fgd[n={self.n}]: a side has fewer than {self.n} windows "
                                  f"(reference {len(ref)}, condition {len(cond)}): drawn with replacement, biased up")
        if self.infinity:
            try:
                fit = fgd_infinity(ref, cond, seed=ctx.seed)
            except InputError as exc:
                ctx.issues.append(f"{ctx.cond}: fgd_inf: {exc.reason}")
                return
            ctx.add("fgd_inf", fit["value"], ci=(fit["ci_low"], fit["ci_high"]), n=int(fit["ns"][-1]))
            ctx.summary[-1].update(extra, fgd_inf_slope=fit["slope"])
            ctx.figure_data.setdefault("fgd_inf", {})[ctx.cond] = {
                k: fit[k] for k in ("value", "slope", "ns", "fgd_n", "draws")}
