"""The GENEA Leaderboard's synthetic degradations, by name, and smoothing as a post-processing operator.

Definitions (``make_synthetic_baseline.py`` of the Leaderboard's objective-metric code, applied here to the
rotation vectors (axis-angle, radians) of every joint with three rotation channels; root position channels
are left as they are):

* ``gaussian_noise``: ``r + N(0, sigma^2)`` per value, ``sigma = 0.02`` rad;
* ``attenuated``: ``(1 - a) r + a * mean(r)`` with ``a = 0.8`` and the mean over the file's frames;
* ``fluctuation``: ``r + A sin(2 pi f t + phi)`` on every rotation value except the root joint's, with
  ``A = 0.05`` rad, ``f = 0.2`` and ``t`` in **frames** (the Leaderboard's convention, so the period is 5
  frames), ``phi`` drawn uniformly per value (seeded);
* ``fixing``: ``round(J * 18 / 55)`` joints (18 of SMPL-X's 55 in the Leaderboard), drawn seeded among the
  non-root joints, held at their frame-0 rotation;
* ``smoothed``: a filter of :mod:`evalsuite.motion.filters` (moving average, Savitzky-Golay, 1-euro), the
  post-processing studied in "Moving fast and slow".

Each applies to the source condition (``of``: natural by default, or any generator's output folder).
Positions-only motion is refused by the rotation-based ones (their definitions are on rotations). An SMPL-X
source (BEAT2 ``.npz``) is degraded exactly as ``make_synthetic_baseline.py`` does on its axis-angle ``poses``
and written as SMPL-X with its other keys (:mod:`~evalsuite.generators.conditions.smplx_ops`: there the
fluctuation has one phase per sample, and ``fixing`` draws its 18 joints among all 55, the root included).
"""
from __future__ import annotations

import abc
import dataclasses
from typing import Any, ClassVar

import numpy as np

from evalsuite.generators.conditions import smplx_ops
from evalsuite.generators.conditions.smplx_ops import fit_smplx, smplx_source
from evalsuite.generators.conditions.source import OF_OPTION, fit_to_request, source_motion, source_path
from evalsuite.generators.contract import GenerationRequest, GenerationResult, Generator, GeneratorSpec
from evalsuite.motion import Motion
from evalsuite.motion.filters import smooth
from evalsuite.motion.io import load_motion
from evalsuite.motion.joint_rotations import rotation_joints, rotation_vectors, with_rotation_vectors

__all__ = ["GaussianNoise", "Attenuated", "Fluctuation", "Fixing", "Smoothed"]

_LEADERBOARD = "GENEA Leaderboard synthetic baseline (make_synthetic_baseline.py), on joint rotation vectors"


class _Degradation(Generator):
    """Source motion -> rotation vectors -> :meth:`degrade` -> motion."""

    defaults: ClassVar[dict[str, float]] = {}

    def param(self, name: str) -> float:
        return self.float_option(name, self.defaults[name])

    @abc.abstractmethod
    def degrade(self, rv: np.ndarray, motion: Motion, rng: np.random.Generator) -> np.ndarray:
        """The degraded rotation vectors ``(T, R, 3)``."""

    @abc.abstractmethod
    def degrade_smplx(self, poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The degraded SMPL-X ``poses`` ``(T, 165)``, as make_synthetic_baseline.py (see smplx_ops)."""

    def generate(self, request: GenerationRequest) -> GenerationResult:
        path = source_path(self.option("of"), request)
        data = smplx_source(path)
        if data is not None:  # SMPL-X: the Leaderboard's formula on the whole file's axis-angle, then the length
            degraded = dataclasses.replace(data, poses=self.degrade_smplx(data.poses,
                                                                          np.random.default_rng(request.seed)))
            return GenerationResult(None, smplx=fit_smplx(degraded, request))
        motion = fit_to_request(load_motion(path), request)
        rv = rotation_vectors(motion)
        out = self.degrade(rv, motion, np.random.default_rng(request.seed))
        return GenerationResult(with_rotation_vectors(motion, out))


def _spec(name: str, summary: str, params: dict[str, str], stochastic: bool) -> GeneratorSpec:
    return GeneratorSpec(name=name, version="1", kind="condition", summary=summary, citation=_LEADERBOARD,
                         stochastic=stochastic, config={**OF_OPTION, **params})


class GaussianNoise(_Degradation):
    spec = _spec("gaussian_noise", "Gaussian noise on every joint rotation vector (sigma 0.02 rad).",
                 {"sigma": "noise standard deviation in radians (default 0.02)"}, True)
    defaults = {"sigma": 0.02}

    def degrade(self, rv: np.ndarray, motion: Motion, rng: np.random.Generator) -> np.ndarray:
        return rv + rng.normal(0.0, self.param("sigma"), size=rv.shape)

    def degrade_smplx(self, poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return smplx_ops.gaussian_noise(poses, rng, self.param("sigma"))


class Attenuated(_Degradation):
    spec = _spec("attenuated", "Rotations pulled 80 % of the way to the file's mean: (1-a) r + a mean(r).",
                 {"alpha": "weight of the mean (default 0.8)"}, False)
    defaults = {"alpha": 0.8}

    def degrade(self, rv: np.ndarray, motion: Motion, rng: np.random.Generator) -> np.ndarray:
        a = self.param("alpha")
        return (1 - a) * rv + a * rv.mean(axis=0, keepdims=True)

    def degrade_smplx(self, poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return smplx_ops.attenuated(poses, self.param("alpha"))


def _root_rows(motion: Motion) -> list[int]:
    roots = set(motion.skeleton.roots)
    return [r for r, (j, _, _) in enumerate(rotation_joints(motion)) if j in roots]


class Fluctuation(_Degradation):
    spec = _spec("fluctuation", "A sine of 0.05 rad at 0.2 cycles per frame with a random phase per value, added "
                                "to every joint rotation but the root's.",
                 {"amplitude": "radians (default 0.05)", "frequency": "cycles per frame (default 0.2)"}, True)
    defaults = {"amplitude": 0.05, "frequency": 0.2}

    def degrade(self, rv: np.ndarray, motion: Motion, rng: np.random.Generator) -> np.ndarray:
        t = np.arange(len(rv), dtype=np.float64)[:, None, None]
        phase = rng.uniform(0.0, 2 * np.pi, size=(1,) + rv.shape[1:])
        wave = self.param("amplitude") * np.sin(2 * np.pi * self.param("frequency") * t + phase)
        wave[:, _root_rows(motion)] = 0.0
        return rv + wave

    def degrade_smplx(self, poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return smplx_ops.fluctuation(poses, rng, self.param("amplitude"), self.param("frequency"))


class Fixing(_Degradation):
    spec = _spec("fixing", "round(J*18/55) random non-root joints held at their frame-0 rotation.",
                 {"fraction": "share of joints held (default 18/55)"}, True)
    defaults = {"fraction": 18 / 55}

    def degrade(self, rv: np.ndarray, motion: Motion, rng: np.random.Generator) -> np.ndarray:
        roots = set(_root_rows(motion))
        candidates = [r for r in range(rv.shape[1]) if r not in roots]
        n = min(len(candidates), int(round(rv.shape[1] * self.param("fraction"))))
        held = rng.choice(candidates, size=n, replace=False) if n else np.zeros(0, dtype=np.int64)
        out = rv.copy()
        out[:, held] = rv[:1, held]
        return out

    def degrade_smplx(self, poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        return smplx_ops.fixing(poses, rng, int(round(poses.shape[1] // 3 * self.param("fraction"))))


class Smoothed(Generator):
    spec = GeneratorSpec(
        name="smoothed", version="1", kind="condition", output="any",
        summary="The source condition smoothed by a filter of evalsuite.motion.filters (the post-processing of "
                "'Moving fast and slow'): moving_average (window), savgol (window, order) or one_euro "
                "(min_cutoff, beta).",
        config={**OF_OPTION, "method": "moving_average | savgol | one_euro (default moving_average)",
                "window": "frames (moving_average, savgol)", "order": "polynomial order (savgol)",
                "min_cutoff": "Hz (one_euro)", "beta": "speed coefficient (one_euro)"})

    def generate(self, request: GenerationRequest) -> GenerationResult:
        motion = fit_to_request(source_motion(self.option("of"), request), request)
        params: dict[str, Any] = {k: self.config[k] for k in ("window", "order", "min_cutoff", "beta")
                                  if k in self.config}
        for k in ("window", "order"):
            if k in params:
                params[k] = int(params[k])
        return GenerationResult(smooth(motion, str(self.option("method", "moving_average")), **params))
