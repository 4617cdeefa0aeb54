"""Gesture-phase labels for training the phase classifier of ``ferstl-mogan``: read from a corpus's per-frame
label files, or estimated from the motion by a heuristic labeller when a corpus has none.

Ferstl et al. (MIG 2019) trained their phase classifier on 3.8 h of hand annotation that is not public. A
corpus made by the synthetic speaker has per-frame labels (``rest, preparation, stroke, hold, retraction``);
for other corpora :func:`heuristic_phases` labels the wrists' motion:

1. wrist positions (hip-centred) are smoothed (Gaussian, 0.05 s); ``v(t)`` is the larger wrist speed, ``d(t)``
   the larger distance of a wrist from its rest position (the median position over the frames where that wrist
   is lowest: its lowest 20 % by height);
2. a frame *moves* when ``v > speed_fraction * P95(v)`` (default 0.35), and is *away* when
   ``d > distance_fraction * P95(d)`` (default 0.2);
3. still frames are ``rest`` (not away) or ``hold`` (away);
4. each run of moving frames is named by where it starts and ends: rest -> away is a preparation followed by a
   stroke (split at the run's deepest speed dip when the dip is below 60 % of the run's peak, else at 40 % of
   the run), away -> rest a ``retraction``, away -> away a ``stroke`` (split into preparation and stroke at a dip
   as above), rest -> rest a preparation and a retraction (halves).

:data:`PHASE5` are the five labels; :func:`to_classes` maps them onto the paper's four classes for adversarial
training (preparation, stroke, hold, other = rest and retraction).
"""
from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from scipy.ndimage import gaussian_filter1d

__all__ = ["PHASE5", "CLASSES4", "heuristic_phases", "to_classes", "labels_at_fps", "corpus_phases"]

PHASE5 = ("rest", "preparation", "stroke", "hold", "retraction")
CLASSES4 = ("preparation", "stroke", "hold", "other")
_TO4 = {"preparation": 0, "stroke": 1, "hold": 2, "rest": 3, "retraction": 3}


def to_classes(labels: Sequence[str]) -> np.ndarray:
    """Five-phase labels -> indices of :data:`CLASSES4` (rest and retraction are 'other'; unknown too)."""
    return np.array([_TO4.get(str(p), 3) for p in labels], dtype=np.int64)


def labels_at_fps(labels: Sequence[str], source_fps: float, fps: float, n_frames: int) -> list[str]:
    """Per-frame labels at ``source_fps`` -> ``n_frames`` labels at ``fps`` (nearest frame in time)."""
    if not len(labels):
        return ["rest"] * n_frames
    idx = np.clip(np.round(np.arange(n_frames) / fps * source_fps).astype(np.int64), 0, len(labels) - 1)
    return [labels[i] for i in idx]


def corpus_phases(path: str | os.PathLike[str], source_fps: float, fps: float, n_frames: int) -> list[str]:
    """A synthetic-speaker label file (``frame,phase,kind,keyword``) at ``fps``."""
    from evalsuite.metrics.coupling import read_phase_labels

    return labels_at_fps(read_phase_labels(path), source_fps, fps, n_frames)


def _split(speed: np.ndarray, first: str, second: str, default: float = 0.4) -> list[str]:
    n = len(speed)
    if n < 3:
        return [second] * n
    inner = speed[1:-1]
    k = int(np.argmin(inner)) + 1
    cut = k if inner.min() < 0.6 * speed.max() else max(1, int(round(default * n)))
    return [first] * cut + [second] * (n - cut)


def heuristic_phases(wrists: np.ndarray, fps: float, *, speed_fraction: float = 0.35,
                     distance_fraction: float = 0.2, smooth_s: float = 0.05) -> list[str]:
    """Five-phase labels of one sequence from its wrist positions ``(T, W, 3)`` (hip-centred, y up); see the
    module docstring for the rules."""
    p = np.asarray(wrists, dtype=np.float64)
    if p.ndim != 3 or p.shape[-1] != 3:
        raise ValueError(f"wrist positions must have shape (T, W, 3), got {p.shape}")
    n = len(p)
    if n < 3:
        return ["rest"] * n
    p = gaussian_filter1d(p, max(smooth_s * fps, 1e-3), axis=0, mode="nearest")
    speed = np.linalg.norm(np.diff(p, axis=0, prepend=p[:1]), axis=-1).max(axis=1) * fps
    rest = []
    for w in range(p.shape[1]):
        low = p[:, w, 1] <= np.percentile(p[:, w, 1], 20)
        rest.append(np.median(p[low, w], axis=0))
    dist = np.linalg.norm(p - np.stack(rest)[None], axis=-1).max(axis=1)
    moving = speed > speed_fraction * max(np.percentile(speed, 95), 1e-9)
    away = dist > distance_fraction * max(np.percentile(dist, 95), 1e-9)
    out = ["hold" if a else "rest" for a in away]
    t = 0
    while t < n:
        if not moving[t]:
            t += 1
            continue
        e = t
        while e < n and moving[e]:
            e += 1
        start_away = bool(away[t - 1]) if t > 0 else bool(away[t])
        end_away = bool(away[e]) if e < n else bool(away[e - 1])
        run = speed[t:e]
        if not start_away and end_away:
            labels = _split(run, "preparation", "stroke")
        elif start_away and not end_away:
            labels = ["retraction"] * (e - t)
        elif start_away and end_away:
            labels = _split(run, "preparation", "stroke", default=0.0)
        else:
            labels = _split(run, "preparation", "retraction", default=0.5)
        out[t:e] = labels
        t = e
    return out
