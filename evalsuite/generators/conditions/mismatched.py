"""``mismatched``: a condition's motion on other speech (the GENEA 2022/23 and Leaderboard design).

Segments are sorted by duration and the source motion is shifted cyclically by ``s`` places in that order
(``s`` in 1..n-1, so no segment keeps its own motion: a derangement). Like the GENEA Leaderboard's
``make_synthetic_baseline.py`` (``human_mismatch``), ``s`` is drawn (seeded) among the shifts where every
pair's durations differ by at most ``tolerance`` (default 20 %); when no shift qualifies, the shift with the
least total duration difference is used. The borrowed motion is cropped to the segment's length; a shorter
one is extended by playing it backwards and forwards (no jump), which is noted in the provenance. With SMPL-X
sources the segment gets the donor's ``poses`` and ``trans`` and keeps its own other keys (``betas``,
``expressions``, ...), as ``human_mismatch`` does, written as SMPL-X.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from evalsuite.generators.conditions.smplx_ops import fit_smplx, smplx_source, take_frames, with_motion
from evalsuite.generators.conditions.source import OF_OPTION, source_path
from evalsuite.generators.contract import (
    GenerationRequest,
    GenerationResult,
    Generator,
    GeneratorError,
    GeneratorSpec,
)
from evalsuite.motion import Motion
from evalsuite.motion.io import load_motion
from evalsuite.motion.ops import resample
from evalsuite.motion.smplx import SmplxData

__all__ = ["Mismatched", "choose_shift", "ping_pong_indices"]


def choose_shift(durations: Sequence[float], rng: np.random.Generator, tolerance: float = 0.2) -> int:
    """A cyclic shift ``s`` (1..n-1) of the duration-sorted order: random among those with every pair within
    ``tolerance`` (relative), else the one with the least total absolute difference."""
    d = np.asarray(durations, dtype=np.float64)
    n = len(d)
    ok, cost = [], []
    for s in range(1, n):
        other = np.roll(d, -s)
        rel = np.abs(other - d) / np.maximum(np.maximum(other, d), 1e-9)
        if np.all(rel <= tolerance):
            ok.append(s)
        cost.append(float(np.abs(other - d).sum()))
    if ok:
        return int(rng.choice(ok))
    return int(np.argmin(cost)) + 1


def ping_pong_indices(n_source: int, n: int) -> np.ndarray:
    """Frame indices ``0, 1, …, m-1, m-2, …, 0, 1, …`` of length ``n`` (``m = n_source``)."""
    if n_source <= 1:
        return np.zeros(n, dtype=np.int64)
    period = 2 * (n_source - 1)
    k = np.arange(n) % period
    return np.where(k < n_source, k, period - k).astype(np.int64)


class Mismatched(Generator):
    spec = GeneratorSpec(
        name="mismatched", version="1", kind="condition", stochastic=True, output="any",
        summary="Each segment gets another segment's motion from the source condition (a seeded derangement "
                "among shifts of the duration-sorted segments whose durations differ by at most 20 %, as the "
                "GENEA Leaderboard's human_mismatch), cropped to length.",
        config={**OF_OPTION, "tolerance": "largest relative duration difference of a pair (default 0.2)"})
    batch_only = True

    def generate(self, request: GenerationRequest) -> GenerationResult:
        raise GeneratorError("mismatched needs every segment of the split together (the runner calls "
                             "generate_batch)")

    def generate_batch(self, requests: Sequence[GenerationRequest]) -> list[GenerationResult]:
        if len(requests) < 2:
            raise GeneratorError("mismatched needs at least two segments")
        order = sorted(range(len(requests)), key=lambda i: (requests[i].duration, requests[i].segment_id))
        rng = np.random.default_rng(requests[0].seed)  # the run's seed for this sample, derived per first segment
        shift = choose_shift([requests[i].duration for i in order], rng, self.float_option("tolerance", 0.2))
        out: list[GenerationResult | None] = [None] * len(requests)
        for pos, i in enumerate(order):
            donor = order[(pos + shift) % len(order)]
            req = requests[i]
            donor_path = source_path(self.option("of"), requests[donor])
            donor_data = smplx_source(donor_path)
            if donor_data is not None:  # SMPL-X: the donor's poses and trans, the segment's other keys
                out[i] = GenerationResult(None, {"motion_from": requests[donor].segment_id,
                                                 "extended_by_ping_pong": bool(donor_data.n_frames < req.n_frames)},
                                          smplx=self._smplx(req, donor_data))
                continue
            src: Motion = resample(load_motion(donor_path), req.fps)
            idx = ping_pong_indices(src.n_frames, req.n_frames)
            m = src.with_values(src.values[idx]) if src.is_hierarchical else src.with_positions(src.positions()[idx])
            out[i] = GenerationResult(m, {"motion_from": requests[donor].segment_id,
                                          "extended_by_ping_pong": bool(src.n_frames < req.n_frames)})
        return [r for r in out if r is not None]

    def _smplx(self, req: GenerationRequest, donor: SmplxData) -> SmplxData:
        try:
            own = smplx_source(source_path(self.option("of"), req)) or donor
        except GeneratorError:  # no motion of its own: the donor's other keys too
            own = donor
        base = fit_smplx(own, req)
        fit_smplx(donor, req)  # the same frame rate
        return with_motion(base, take_frames(donor, ping_pong_indices(donor.n_frames, req.n_frames)))
