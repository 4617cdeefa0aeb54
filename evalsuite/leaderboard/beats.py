"""The GENEA Leaderboard's beat alignment (``bc_a2m``, ``bc_m2a``), as ``emage_evaltools`` BC computes it.

Per sequence of T frames at 30 fps (positions (T, 55, 3) in metres, the Leaderboard's zeroing) and its 16 kHz
speech, the first and last 2 s are cut from both:

* **audio beats**: ``librosa.onset.onset_detect(y, sr=16000, hop_length=512, units="time")`` on the samples
  ``y[2*16000 : int((T - 60) / 30 * 16000)]`` (times from the cut's start);
* **motion beats** per joint j: the speed ``v[t, j] = |x'[t, j]|`` by central differences (forward/backward at
  the ends, dt = 1/30), divided by the joint's mean speed ``m[j]`` (``mean_vel_smplxflame_30.npy``), and the
  local minima of ``v[60 : T-60, j]`` (``scipy.signal.argrelextrema(np.less, order=7)``, frame indices i from
  the cut's start) kept where the speed exceeds 0.10 — tested, as the script does, at the *absolute* frame i,
  that is 60 frames (2 s) before the minimum at frame 60 + i (:func:`motion_beats` ``published_threshold_frame``);
* the Gaussian hit rate ``H(a, b) = mean_{y in b} exp(-min_{x in a} (x - y)^2 / (2 sigma^2))``, sigma = 0.3 s:
  ``a2m = H(motion beats, audio beats)`` (each onset to its nearest motion beat), ``m2a = H(audio, motion)``;
  per sequence the sum over the 13 upper-body joints (0 for a joint without beats) divided by 13;
* over sequences, the mean weighted by ``T - 120``.

Speech without onsets crashes the script (a division by zero); here it is an InputError naming the file.
"""
from __future__ import annotations

import os
from collections.abc import Iterable, Sequence

import numpy as np
from scipy.signal import argrelextrema

from evalsuite.errors import InputError

__all__ = ["UPPER_BODY", "SIGMA", "ORDER", "THRESHOLD", "AUDIO_SR", "HOP_LENGTH", "CUT_FRAMES", "FPS",
           "joint_speed", "motion_beats", "load_wave", "audio_onsets", "hit_rate", "beat_alignment",
           "sequence_bc", "sequence_onsets", "mean_velocity", "read_mean_velocity"]

UPPER_BODY = (3, 6, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21)  # spine1..3, neck, collars, head, arms, wrists
SIGMA = 0.3        # seconds
ORDER = 7          # frames either side of a minimum
THRESHOLD = 0.10   # normalised speed a beat must exceed
AUDIO_SR = 16000
HOP_LENGTH = 512
FPS = 30
CUT_FRAMES = 60    # 2 s at 30 fps, cut at both ends


def joint_speed(positions: np.ndarray, fps: float = FPS) -> np.ndarray:
    """Speed (T, J) of positions (T, J, 3) or (T, 3J): central differences ``(x[t+1] - x[t-1]) / (2 dt)`` inside,
    ``(x[1] - x[0]) / dt`` and ``(x[T-1] - x[T-2]) / dt`` at the ends, then the Euclidean norm per joint."""
    x = np.asarray(positions, dtype=np.float64)
    x = x.reshape(len(x), -1, 3)
    if len(x) < 2:
        raise InputError(f"beat alignment needs at least 2 frames, got {len(x)}")
    dt = 1.0 / fps
    vel = np.concatenate([(x[1:2] - x[:1]) / dt, (x[2:] - x[:-2]) / (2 * dt), (x[-1:] - x[-2:-1]) / dt])
    return np.linalg.norm(vel, axis=2)


def motion_beats(positions: np.ndarray, mean_vel: np.ndarray, t_start: int, t_end: int, fps: float = FPS,
                 threshold: float = THRESHOLD, order: int = ORDER, published_threshold_frame: bool = True
                 ) -> list[np.ndarray]:
    """Beat frames per joint (a list of J int arrays, indices from ``t_start``): local minima of the normalised
    speed ``v[t_start:t_end, j]`` whose speed exceeds ``threshold``.

    ``published_threshold_frame=True`` (the Leaderboard): the speed is tested at the absolute frame equal to the
    minimum's index in the cut window, i.e. ``t_start`` frames before the minimum; False tests the minimum itself.
    """
    speed = joint_speed(positions, fps)
    mean_vel = np.asarray(mean_vel)
    if mean_vel.shape not in ((), (speed.shape[1],)):
        raise InputError(f"mean velocity has shape {mean_vel.shape}; expected ({speed.shape[1]},), one per joint")
    speed = speed / mean_vel
    shift = 0 if published_threshold_frame else t_start
    out = []
    for j in range(speed.shape[1]):
        above = speed[:, j] > threshold
        minima = argrelextrema(speed[t_start:t_end, j], np.less, order=order)[0]
        keep = [i for i in minima if 0 <= i + shift < len(above) and above[i + shift]]
        out.append(np.asarray(keep, dtype=np.int64))
    return out


def load_wave(path: str | os.PathLike[str], sr: int = AUDIO_SR) -> np.ndarray:
    """Mono float32 samples at ``sr`` read with ``librosa.load`` (as the script reads the speech)."""
    librosa = _librosa()
    if not os.path.isfile(path):
        raise InputError("no such speech file (expected BEAT2's wave16k/<video_id>.wav)", path=path)
    try:
        y, _ = librosa.load(os.fspath(path), sr=sr)
    except Exception as exc:  # soundfile/audioread raise many types for a bad file
        raise InputError(f"cannot be read as audio ({type(exc).__name__}: {exc})", path=path) from None
    return np.asarray(y)


def audio_onsets(y: np.ndarray, t_start: int | None = None, t_end: int | None = None, sr: int = AUDIO_SR,
                 hop_length: int = HOP_LENGTH) -> np.ndarray:
    """Onset times (s) of ``y[t_start:t_end]`` (float32) from ``librosa.onset.onset_detect(units="time")`` with
    the script's parameters, measured from ``t_start``."""
    librosa = _librosa()
    cut = np.asarray(y)[t_start:t_end] if t_start is not None else np.asarray(y)
    return np.asarray(librosa.onset.onset_detect(y=cut.astype(np.float32), sr=sr, hop_length=hop_length,
                                                 units="time"), dtype=np.float64)


def hit_rate(a: Iterable[float], b: Iterable[float], sigma: float = SIGMA) -> float:
    """``H(a, b) = mean_{y in b} exp(-min_{x in a} |x - y|^2 / (2 sigma^2))`` (times in seconds)."""
    a_arr = np.asarray(list(a), dtype=np.float64)
    b_arr = np.asarray(list(b), dtype=np.float64)
    if not len(b_arr) or not len(a_arr):
        raise InputError("beat alignment of an empty beat list")
    d = np.abs(b_arr[:, None] - a_arr[None, :]).min(axis=1)
    return float(np.exp(-(d ** 2) / (2 * sigma ** 2)).mean())


def beat_alignment(onsets: np.ndarray, beats: Sequence[np.ndarray], joints: Sequence[int] = UPPER_BODY,
                   fps: float = FPS, sigma: float = SIGMA) -> tuple[float, float]:
    """``(a2m, m2a)`` of one sequence: ``sum_{j in joints} H_j / len(joints)`` with ``H_j`` = :func:`hit_rate`
    (motion beats of joint j as times ``frame / fps`` vs the onsets), 0 for a joint without beats."""
    onsets = np.asarray(onsets, dtype=np.float64)
    if not len(onsets):
        raise InputError("no onsets in the speech (silence or too short); beat alignment needs audio beats")
    a2m = m2a = 0.0
    for j in joints:
        if len(beats[j]):
            times = np.asarray(beats[j], dtype=np.float64) / fps
            a2m += hit_rate(times, onsets, sigma)
            m2a += hit_rate(onsets, times, sigma)
    return a2m / len(joints), m2a / len(joints)


def sequence_bc(positions: np.ndarray, wave: np.ndarray, mean_vel: np.ndarray, *, fps: float = FPS,
                sr: int = AUDIO_SR, cut: int = CUT_FRAMES, sigma: float = SIGMA,
                published_threshold_frame: bool = True, source: str | None = None,
                onsets: np.ndarray | None = None) -> tuple[float, float, int]:
    """``(a2m, m2a, weight)`` of one sequence of T frames (positions (T, 55, 3), 16 kHz speech ``wave``): the
    first and last ``cut`` frames (2 s) left out of both streams, weight ``T - 2 cut``. ``onsets``: those of
    :func:`sequence_onsets` for this T, when already known."""
    t = len(positions)
    if onsets is None:
        onsets = sequence_onsets(wave, t, fps=fps, sr=sr, cut=cut, source=source)
    if not len(onsets):
        raise InputError("no onsets in the speech between the cut first and last 2 s; beat alignment needs audio "
                         "beats (the organisers' script divides by zero here)", path=source)
    beats = motion_beats(positions, mean_vel, cut, t - cut, fps, published_threshold_frame=published_threshold_frame)
    a2m, m2a = beat_alignment(onsets, beats, fps=fps, sigma=sigma)
    return a2m, m2a, t - 2 * cut


def sequence_onsets(wave: np.ndarray, n_frames: int, *, fps: float = FPS, sr: int = AUDIO_SR, cut: int = CUT_FRAMES,
                    source: str | None = None) -> np.ndarray:
    """Onset times (s) of the speech of a sequence of ``n_frames`` between the cut first and last ``cut`` frames:
    samples ``int(cut / fps * sr)`` to ``int((n_frames - cut) / fps * sr)``."""
    if n_frames <= 2 * cut:
        raise InputError(f"beat alignment needs more than {2 * cut} frames ({2 * cut / fps:g} s are cut), got "
                         f"{n_frames}", path=source)
    return audio_onsets(wave, int(cut / fps * sr), int((n_frames - cut) / fps * sr), sr=sr)


def mean_velocity(positions: Iterable[np.ndarray], fps: float = FPS) -> np.ndarray:
    """Per-joint mean speed (J,) over every frame of every sequence (:func:`joint_speed`), as EMAGE's
    ``mean_vel_smplxflame_30.npy`` was made: full SMPL-X positions (orientation and translation applied) of the
    recordings of the ``smplxflame_30`` folder, all frames pooled."""
    total, count = None, 0
    for p in positions:
        s = joint_speed(p, fps)
        total = s.sum(axis=0) if total is None else total + s.sum(axis=0)
        count += len(s)
    if total is None or not count:
        raise InputError("mean velocity of no sequences")
    return np.asarray(total / count)


def read_mean_velocity(path: str | os.PathLike[str], n_joints: int = 55) -> np.ndarray:
    """A per-joint mean velocity ``.npy`` (``mean_vel_smplxflame_30.npy``: (55,) float), checked."""
    try:
        arr = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        raise InputError("no such mean velocity file (mean_vel_smplxflame_30.npy, or evalsuite's "
                         "mean_velocity of a training split)", path=path, field="bc-mean-vel") from None
    except (ValueError, OSError) as exc:
        raise InputError(f"not a .npy array ({exc})", path=path, field="bc-mean-vel") from None
    arr = np.asarray(arr, dtype=np.float64).reshape(-1)
    if arr.shape != (n_joints,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InputError(f"expected {n_joints} positive finite speeds (one per SMPL-X joint), found shape "
                         f"{arr.shape}", path=path, field="bc-mean-vel")
    return arr


def _librosa():
    try:
        import librosa
    except ImportError:
        raise InputError("beat alignment (bc_a2m, bc_m2a) uses librosa's onset detection as the Leaderboard does: "
                         "pip install 'evalsuite[leaderboard]'", field="audio") from None
    return librosa

