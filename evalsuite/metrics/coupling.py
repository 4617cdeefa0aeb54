"""Speech-gesture coupling: how motion follows the speech it accompanies.

* :func:`speech_energy`: RMS energy of the speech on the motion's frame grid, smoothed;
* :func:`energy_speed_correlation`: Pearson correlation of speech energy with (wrist) speed over lags;
* :func:`lexical_contrast`: change of a motion feature in a window after given words against the
  sequence's baseline; :func:`motion_feature` computes the features, :func:`lexical_classes` pairs a
  corpus's keyword classes with the feature each moves, :func:`lexical_contrasts` all classes at once;
* :func:`phase_statistics`: proportions, mean durations and the transition matrix of per-frame gesture
  phase labels.

Beat alignment is :mod:`evalsuite.metrics.beats`. Positions are ``(T, J, 3)`` world positions in file
units with +y up and +z forward (the BVH convention of GENEA and Trinity data).
"""
from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.ndimage import gaussian_filter1d

from evalsuite.errors import InputError
from evalsuite.metrics._validate import positions_array, positive

__all__ = ["speech_energy", "joint_speed", "energy_speed_correlation", "lexical_contrast", "motion_feature",
           "lexical_contrasts", "word_onsets", "phase_statistics", "PhaseStatistics", "CLASS_FEATURES",
           "lexical_classes", "LEXICAL_FEATURES", "LexicalClass", "wrist_indices", "read_phase_labels"]

WRISTS = (("RightHand", "LeftHand"), ("b_r_wrist", "b_l_wrist"), ("RightWrist", "LeftWrist"))
CHEST = ("Spine3", "b_spine3", "Spine2", "b_spine2", "Chest", "Spine1")
HEAD = ("Head", "b_head")
LEXICAL_FEATURES = ("wrist_height", "hand_distance", "hand_chest", "hand_forward", "head_yaw_speed")


def speech_energy(signal: npt.ArrayLike, sr: float, fps: float, n_frames: int | None = None,
                  smooth_s: float = 0.1) -> np.ndarray:
    """``(T,)`` RMS energy of a mono signal on the frame grid ``t = k / fps``.

    ``e[k] = sqrt(mean(x[n]^2))`` over the samples n with ``|n/sr - k/fps| < 1/(2 fps)`` (one frame centred
    on the frame time), then smoothed by a Gaussian of standard deviation ``smooth_s`` seconds (0: none).
    ``n_frames`` defaults to ``round(len(x) / sr * fps)``; frames beyond the signal are 0.
    """
    x = np.asarray(signal, dtype=np.float64)
    x = x.mean(axis=1) if x.ndim == 2 else x.ravel()
    sr, fps = positive(sr, "sample rate"), positive(fps, "fps")
    n = int(round(len(x) / sr * fps)) if n_frames is None else int(n_frames)
    centres = np.arange(n) / fps
    lo = np.clip(np.round((centres - 0.5 / fps) * sr).astype(np.int64), 0, len(x))
    hi = np.clip(np.round((centres + 0.5 / fps) * sr).astype(np.int64), 0, len(x))
    csum = np.concatenate([[0.0], np.cumsum(x * x)])
    count = np.maximum(hi - lo, 1)
    e = np.sqrt(np.maximum(csum[hi] - csum[lo], 0.0) / count)
    if smooth_s > 0:
        e = gaussian_filter1d(e, smooth_s * fps, mode="nearest")
    return np.asarray(e)


def joint_speed(positions: npt.ArrayLike, fps: float) -> np.ndarray:
    """``(T,)`` mean speed of the joints (units/s): central differences (``np.gradient``) of ``(T, J, 3)``,
    norm per joint, mean over joints."""
    x = positions_array(positions, min_frames=2)
    v = np.gradient(x, axis=0) * positive(fps, "fps")
    return np.asarray(np.linalg.norm(v, axis=2).mean(axis=1))


def _pearson(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a - a.mean(), b - b.mean()
    den = float(np.sqrt((a * a).sum() * (b * b).sum()))
    return float((a * b).sum() / den) if den > 1e-12 * max(1.0, float(len(a))) else 0.0


def energy_speed_correlation(energy: npt.ArrayLike, speed: npt.ArrayLike, fps: float,
                             max_lag_s: float = 0.3, smooth_s: float = 0.1) -> tuple[float, float, np.ndarray]:
    """Correlation of speech energy with motion speed over lags: ``(best r, its lag in s, r per lag)``.

    The speed is first smoothed like the energy (:func:`speech_energy`): a Gaussian of standard deviation
    ``smooth_s`` seconds (0: none), so that the envelope of the movement, not each syllable's flick, is
    compared with the envelope of the speech.
    ``r(l) = pearson(e[t], s[t + l])`` over the frames where both exist, for lags ``l = -L..L`` frames,
    ``L = round(max_lag_s * fps)``; a positive lag means the motion follows the speech. Both series are
    on the motion's frame grid and are truncated to the shorter one. The best lag maximises r. A constant
    series (no motion, or silence) has no correlation: r = 0 at every lag, and the best lag is NaN.
    """
    e = np.asarray(energy, dtype=np.float64).ravel()
    s = np.asarray(speed, dtype=np.float64).ravel()
    fps = positive(fps, "fps")
    n = min(len(e), len(s))
    lag_max = int(round(max(0.0, float(max_lag_s)) * fps))
    if n < 2 * lag_max + 3:
        raise InputError(f"need at least {2 * lag_max + 3} frames for lags of +-{max_lag_s:g} s, got {n}",
                         field="speed")
    e, s = e[:n], s[:n]
    if smooth_s > 0:
        s = gaussian_filter1d(s, smooth_s * fps, mode="nearest")
    lags = list(range(-lag_max, lag_max + 1))
    r = np.array([_pearson(e[max(0, -k): n - max(0, k)], s[max(0, k): n - max(0, -k)]) for k in lags])
    if not np.any(r != 0):
        return 0.0, float("nan"), r
    best = int(np.argmax(r))
    return float(r[best]), float(lags[best] / fps), r


def _find(names: Sequence[str], candidates: Sequence[str]) -> int | None:
    for c in candidates:
        if c in names:
            return list(names).index(c)
    return None


def wrist_indices(names: Sequence[str]) -> list[int]:
    """Indices of the wrist joints (RightHand/LeftHand, b_r_wrist/b_l_wrist or RightWrist/LeftWrist)."""
    for pair in WRISTS:
        idx = [list(names).index(j) for j in pair if j in names]
        if idx:
            return idx
    raise InputError(f"no wrist joints (one of {', '.join(p for pair in WRISTS for p in pair)}) in the motion",
                     field="joints")


def motion_feature(name: str, positions: npt.ArrayLike, joint_names: Sequence[str], fps: float,
                   head_rotations: npt.ArrayLike | None = None) -> np.ndarray:
    """``(T,)`` per-frame motion feature for lexical contrast (units of the positions, or deg/s):

    * ``wrist_height``: the higher wrist's height, ``max_w y_w``;
    * ``hand_distance``: distance between the two wrists;
    * ``hand_chest``: minus the distance of the nearer wrist to the chest joint (Spine3; higher = closer);
    * ``hand_forward``: the more forward wrist's z minus the chest's z;
    * ``head_yaw_speed``: ``|d yaw / dt|`` in deg/s of the head, yaw = ``atan2(R[0,2], R[2,2])`` of its world
      rotation ``head_rotations`` ``(T, 3, 3)`` (needs rotations: NaN without them).
    """
    x = positions_array(positions, min_frames=2)
    names = list(joint_names)
    if name == "head_yaw_speed":
        if head_rotations is None:
            return np.full(len(x), np.nan)
        rot = np.asarray(head_rotations, dtype=np.float64)
        yaw = np.unwrap(np.arctan2(rot[:, 0, 2], rot[:, 2, 2]))
        return np.asarray(np.abs(np.gradient(np.degrees(yaw))) * positive(fps, "fps"))
    w = wrist_indices(names)
    if name == "wrist_height":
        return np.asarray(x[:, w, 1].max(axis=1))
    if name == "hand_distance":
        if len(w) < 2:
            raise InputError("hand_distance needs both wrists", field="joints")
        return np.asarray(np.linalg.norm(x[:, w[0]] - x[:, w[1]], axis=1))
    chest = _find(names, CHEST)
    if chest is None:
        raise InputError(f"{name} needs a chest joint (one of {', '.join(CHEST)})", field="joints")
    if name == "hand_chest":
        return np.asarray(-np.linalg.norm(x[:, w] - x[:, [chest]], axis=2).min(axis=1))
    if name == "hand_forward":
        return np.asarray((x[:, w, 2] - x[:, [chest], 2]).max(axis=1))
    raise InputError(f"unknown motion feature {name!r}; expected one of {', '.join(LEXICAL_FEATURES)}",
                     field="feature")


def lexical_contrast(feature: npt.ArrayLike, fps: float, onsets: npt.ArrayLike,
                     window: tuple[float, float] = (0.2, 1.2)) -> float:
    """Mean of a motion feature in the windows after word onsets minus its mean over the whole sequence.

    ``C = mean_{t in W} f(t) - mean_t f(t)``, ``W`` = the frames with ``o + w0 <= t/fps < o + w1`` for some
    onset o (each frame once). NaN when no onset window lies inside the sequence or f is NaN.
    """
    f = np.asarray(feature, dtype=np.float64).ravel()
    fps = positive(fps, "fps")
    t = np.arange(len(f)) / fps
    sel = np.zeros(len(f), dtype=bool)
    for o in np.asarray(onsets, dtype=np.float64).ravel():
        sel |= (t >= o + window[0]) & (t < o + window[1])
    if not sel.any() or not np.isfinite(f).all():
        return float("nan")
    return float(f[sel].mean() - f.mean())


@dataclass(frozen=True)
class LexicalClass:
    """A word class for lexical contrast: its words (lower case) and the motion feature it moves."""

    words: tuple[str, ...]
    feature: str


# The motion feature each keyword class's semantic gesture moves (the synthetic speaker's classes,
# evalsuite.synth.model). The words of each class are the corpus's own (corpus.json's ``keyword_classes``, kept by
# the reader in each segment's ``meta``): :func:`lexical_classes` pairs the two.
CLASS_FEATURES: dict[str, str] = {
    "up": "wrist_height",
    "wide": "hand_distance",
    "self": "hand_chest",
    "point": "hand_forward",
    "negation": "head_yaw_speed",
}


def lexical_classes(keyword_classes: Mapping[str, Sequence[str]] | None) -> dict[str, LexicalClass]:
    """``{class: LexicalClass(words, feature)}`` for a corpus's ``keyword_classes`` (class -> words, as
    corpus.json stores them) whose class has a feature in :data:`CLASS_FEATURES`; ``{}`` for a corpus without
    keyword classes (lexical contrast is then not measured)."""
    if not keyword_classes:
        return {}
    return {c: LexicalClass(tuple(str(w).lower() for w in words), CLASS_FEATURES[c])
            for c, words in keyword_classes.items() if c in CLASS_FEATURES}


def word_onsets(words: Sequence[tuple[str, float]], vocabulary: Sequence[str]) -> np.ndarray:
    """Onset times of the ``(text, start)`` words whose lower-cased text is in ``vocabulary``."""
    vocab = {v.lower() for v in vocabulary}
    return np.array([s for w, s in words if w.lower().strip(".,;:!?\"'") in vocab], dtype=np.float64)


def lexical_contrasts(words: Sequence[tuple[str, float]], positions: npt.ArrayLike, joint_names: Sequence[str],
                      fps: float, classes: Mapping[str, LexicalClass],
                      window: tuple[float, float] = (0.2, 1.2),
                      head_rotations: npt.ArrayLike | None = None) -> dict[str, float]:
    """:func:`lexical_contrast` of each class's feature after its words (``(text, start)`` pairs); NaN for a
    class with no word in the sequence."""
    out: dict[str, float] = {}
    cache: dict[str, np.ndarray] = {}
    for cls, spec in classes.items():
        onsets = word_onsets(words, spec.words)
        if onsets.size == 0:
            out[cls] = float("nan")
            continue
        if spec.feature not in cache:
            cache[spec.feature] = motion_feature(spec.feature, positions, joint_names, fps, head_rotations)
        out[cls] = lexical_contrast(cache[spec.feature], fps, onsets, window)
    return out


@dataclass(frozen=True)
class PhaseStatistics:
    """``names``: the phases; ``proportion[p]``: fraction of frames; ``mean_duration[p]``: mean length (s) of
    a run of p; ``transitions[i, j]``: fraction of runs of ``names[i]`` followed by a run of ``names[j]``."""

    names: tuple[str, ...]
    proportion: dict[str, float]
    mean_duration: dict[str, float]
    transitions: np.ndarray


def phase_statistics(phases: Sequence[str], fps: float, names: Sequence[str] | None = None) -> PhaseStatistics:
    """Phase-structure statistics of per-frame labels: proportions ``n_p / T``, mean run durations
    ``(frames in runs of p) / (runs of p) / fps`` and the row-normalised matrix of run-to-run transitions
    (rows without runs are 0)."""
    labels = [str(p) for p in phases]
    fps = positive(fps, "fps")
    order = tuple(names) if names is not None else tuple(sorted(set(labels)))
    index = {p: i for i, p in enumerate(order)}
    unknown = sorted(set(labels) - set(index))
    if unknown:
        raise InputError(f"phase labels {', '.join(unknown)} are not among {', '.join(order)}", field="phase")
    runs: list[tuple[str, int]] = []
    for p in labels:
        if runs and runs[-1][0] == p:
            runs[-1] = (p, runs[-1][1] + 1)
        else:
            runs.append((p, 1))
    k = len(order)
    counts = np.zeros((k, k))
    for (a, _), (b, _) in zip(runs[:-1], runs[1:]):
        counts[index[a], index[b]] += 1
    rows = counts.sum(axis=1, keepdims=True)
    trans = np.divide(counts, rows, out=np.zeros_like(counts), where=rows > 0)
    n = max(len(labels), 1)
    prop = {p: labels.count(p) / n for p in order}
    dur = {}
    for p in order:
        lengths = [m for q, m in runs if q == p]
        dur[p] = float(np.mean(lengths)) / fps if lengths else float("nan")
    return PhaseStatistics(order, prop, dur, trans)


def read_phase_labels(path: str | os.PathLike[str]) -> list[str]:
    """The ``phase`` column of a per-frame label CSV (``frame,phase,kind,keyword``, one row per frame)."""
    import csv

    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        if reader.fieldnames is None or "phase" not in reader.fieldnames:
            raise InputError("expected a header with a 'phase' column", path=path, line=1)
        return [row["phase"] for row in reader]
