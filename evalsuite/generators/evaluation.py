"""Learning criteria of the re-implemented generators, measured on a corpus's held-out split.

:func:`evaluate_condition` reads a generated folder (``<segment>.bvh|.npz``) beside the corpus's natural motion
and speech and returns, averaged over segments:

* ``pose_mse`` -- mean squared error of the world positions of the GENEA 2020 upper-body joints present in
  both (file units squared), natural resampled to the generated rate;
* ``energy_speed_r`` -- the best Pearson correlation of speech energy with mean wrist speed within +-0.3 s
  (:func:`evalsuite.metrics.coupling.energy_speed_correlation`);
* ``lexical_<class>`` -- lexical contrast of the synthetic speaker's keyword classes
  (:func:`evalsuite.metrics.coupling.lexical_contrasts`), and ``lexical_mean`` over the position classes
  (up, wide, self, point).
"""
from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus, Segment
from evalsuite.errors import InputError
from evalsuite.generators.joint_presets import default_joints
from evalsuite.metrics.coupling import (
    energy_speed_correlation,
    joint_speed,
    lexical_classes,
    lexical_contrasts,
    speech_energy,
    wrist_indices,
)
from evalsuite.motion import Motion
from evalsuite.motion.io import list_motion_files, load_motion, save_motion
from evalsuite.motion.ops import resample

__all__ = ["evaluate_condition", "POSITION_CLASSES", "segment_scores", "natural_through_rate",
           "conditional_mean_through_rate", "causal_mean_through_rate"]

POSITION_CLASSES = ("up", "wide", "self", "point")


def _positions(m: Motion, names: Sequence[str]) -> np.ndarray:
    return m.positions()[:, [m.joint_index(n) for n in names]]


def segment_scores(gen: Motion, seg: Segment) -> dict[str, float]:
    """The criteria for one generated motion of one corpus segment (see the module doc)."""
    nat = resample(seg.load_motion(), gen.fps)
    shared = [j for j in gen.joint_names if j in nat.joint_names]
    joints = [j for j in default_joints(shared) if j in shared]      # GENEA 2020 upper body, or GENEA 2023's, …
    if not joints:
        raise InputError(f"segment {seg.id!r}: no upper-body joint of a preset in both motions")
    n = min(gen.n_frames, nat.n_frames)
    err = _positions(gen, joints)[:n] - _positions(nat, joints)[:n]
    out = {"pose_mse": float((err ** 2).sum(axis=-1).mean())}
    pos = gen.positions()
    if seg.audio is not None:
        x, rate = seg.load_audio()
        energy = speech_energy(x.mean(axis=1), rate, gen.fps, gen.n_frames)
        speed = joint_speed(pos[:, wrist_indices(gen.joint_names)], gen.fps)
        out["energy_speed_r"] = energy_speed_correlation(energy, speed, gen.fps, 0.3)[0]
    classes = lexical_classes(seg.meta.get("keyword_classes"))
    if seg.transcript is not None and classes:
        head = None
        if gen.is_hierarchical and "Head" in gen.joint_names:
            head = gen.world_rotations()[:, gen.joint_index("Head")]
        words = [(w.text, w.start) for w in seg.transcript.words]
        for cls, value in lexical_contrasts(words, pos, gen.joint_names, gen.fps, classes,
                                            head_rotations=head).items():
            out[f"lexical_{cls}"] = value
    return out


def evaluate_condition(folder: str | pathlib.Path, corpus: Corpus, split: str = "test") -> dict[str, Any]:
    """Mean of :func:`segment_scores` over the split's segments found in ``folder`` (NaNs ignored)."""
    files = list_motion_files(folder)
    rows = []
    for seg in corpus.split(split):
        path = files.get(seg.id) or files.get(f"{seg.id}_0")
        if path is None:
            raise InputError(f"no generated file for segment {seg.id!r}", path=folder)
        rows.append(segment_scores(load_motion(path), seg))
    keys = sorted({k for r in rows for k in r})
    out: dict[str, Any] = {}
    for k in keys:
        vals = np.array([r.get(k, np.nan) for r in rows], dtype=np.float64)
        out[k] = float(np.nanmean(vals)) if np.isfinite(vals).any() else float("nan")
    classes = [out.get(f"lexical_{c}", np.nan) for c in POSITION_CLASSES]
    out["lexical_mean"] = float(np.nanmean(classes)) if np.isfinite(classes).any() else float("nan")
    out["segments"] = len(rows)
    return out


def natural_through_rate(corpus: Corpus, folder: str | pathlib.Path, fps: float, split: str = "test") -> pathlib.Path:
    """Write the split's natural motion resampled to ``fps`` and back to its own rate into ``folder`` (one BVH per
    segment): what a perfect model working at ``fps`` would output, the reference for :func:`evaluate_condition`."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for seg in corpus.split(split):
        nat = seg.load_motion()
        save_motion(resample(resample(nat, fps), nat.fps), folder / f"{seg.id}.bvh")
    return folder


def _write_means(corpus: Corpus, folder: str | pathlib.Path, k: int, fps: float | None, split: str,
                 mean_of: Callable[[Corpus, int, Segment], Motion]) -> pathlib.Path:
    """``mean_of(corpus, i, segment)`` for each segment of the split, resampled to ``fps`` and back when given,
    into ``folder`` (``<segment>.npz``): the synthetic speaker's reference motions below."""
    from evalsuite.synth.layout import read_meta

    if k < 1:
        raise InputError(f"k must be at least 1, got {k}")
    if not corpus.meta.get("model"):
        # read corpus.json once (a clear error unless it is a synthetic speaker's), not once per performance
        corpus = dataclasses.replace(corpus, meta=read_meta(corpus.root))
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for i, seg in enumerate(corpus.split(split)):
        mean = mean_of(corpus, i, seg)
        if fps is not None:
            mean = resample(resample(mean, fps), mean.fps)
        save_motion(mean, folder / f"{seg.id}.npz")
    return folder


def conditional_mean_through_rate(corpus: Corpus, folder: str | pathlib.Path, k: int = 16, fps: float | None = None,
                                  split: str = "test", first_seed: int = 1000) -> pathlib.Path:
    """Write, per segment of a synthetic-speaker corpus, the mean world positions of ``k`` performances of its
    speech (motion seeds ``first_seed`` ... ``first_seed + k - 1``) into ``folder`` (``<segment>.npz``), resampled
    to ``fps`` and back when given.

    The estimate of the conditional mean of the pose given the speech: what a deterministic model trained on the
    pose error converges to at best, so the reference for what such a model can reach on the other criteria
    (``evalsuite.synth``; ``benchmarks/bench_speaker_chance.py`` measures its pose error)."""
    from evalsuite.synth.oracle import segment_oracle

    def mean_of(corpus: Corpus, _: int, seg: Segment) -> Motion:
        performances = [segment_oracle(corpus, seg.id, seed=first_seed + i)[0] for i in range(k)]
        n = min(m.n_frames for m in performances)
        first = performances[0]
        return Motion.from_positions(np.mean([m.positions()[:n] for m in performances], axis=0),
                                     first.joint_names, first.fps, first.parents, name=seg.id)
    return _write_means(corpus, folder, k, fps, split, mean_of)


def causal_mean_through_rate(corpus: Corpus, folder: str | pathlib.Path, k: int = 64, fps: float | None = None,
                             split: str = "test", heard_after: float = 0.0, seed: int = 0) -> pathlib.Path:
    """Write, per segment of a synthetic-speaker corpus, the estimated mean motion given only the speech heard so
    far (:func:`evalsuite.synth.oracle.causal_mean_positions`: per frame, the mean of ``k`` performances in
    which the words not yet begun, ``heard_after`` s after their start, are drawn at random from the training
    transcripts; segment i's draws seeded ``seed + i``) into ``folder`` (``<segment>.npz``), resampled to ``fps``
    and back when given.

    The counterpart of :func:`conditional_mean_through_rate` for causal models (Aud2Motion's forward GRU), an
    estimate of what a deterministic model that hears the speech only up to the frame it outputs can reach; not a
    strict bound (it is told when the coming words start, and does not know the grammar, which a model can learn)."""
    from evalsuite.synth.oracle import causal_mean_positions

    return _write_means(corpus, folder, k, fps, split,
                        lambda corpus, i, seg: causal_mean_positions(corpus, seg.id, k, heard_after, seed=seed + i))


def swapped_audio(requests: Sequence[Any]) -> list[Any]:
    """The requests with each segment's audio replaced by the next segment's (a cyclic derangement; the
    duration stays the segment's, so features are cropped or padded to it): does a model use the speech?"""
    if len(requests) < 2:
        raise InputError("swapping audio needs at least two segments")
    return [dataclasses.replace(r, audio=requests[(i + 1) % len(requests)].audio) for i, r in enumerate(requests)]
