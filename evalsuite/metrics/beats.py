"""Beat alignment between speech audio and motion, in both directions, with sigma in seconds.

* **Audio onsets** (:func:`audio_onsets`): spectral flux. The signal (mono, any rate) is cut
  into Hann windows of ``frame_s`` (default 46 ms) every ``hop_s`` (default 10 ms); the onset
  strength is the half-wave rectified increase of log-compressed magnitude, summed over
  frequency, ``f[n] = Σ_k max(0, log(1 + γ|X_n,k|) - log(1 + γ|X_{n-1},k|))``, normalised to a
  maximum of 1. Onsets are its peaks (``scipy.signal.find_peaks``) at least ``min_interval_s``
  apart and above ``mean + delta`` of a local window of ``threshold_window_s``. Time of frame n
  is its window centre. (Librosa's default onset detector is a spectral-flux method too, on a
  mel spectrogram; the references use it at 16 or 22.05 kHz.)
* **Motion beats** (:func:`motion_beats`): local minima of the mean speed of the chosen joints
  (default: the wrists), i.e. moments where the hands stop or turn, at least ``min_interval_s``
  apart with prominence ``prominence`` x the median speed. The speed between frames t and t+1
  is placed at ``(t + 0.5) / fps`` seconds.
* **Score** (:func:`beat_alignment_score`): for each beat of the source stream, ``exp(-d²/2σ²)``
  with d the distance (s) to the nearest beat of the target stream, averaged over source
  beats. ``a2m`` = audio onsets -> motion beats (BEAT/EMAGE "BC"), ``m2a`` = motion beats ->
  audio onsets (AIST++ direction). 1 when every source beat has a coincident target beat;
  0 if the target stream has no beats; NaN if the source has none.

σ is in seconds (default 0.1 s), so the score does not change with the frame rate (the
AIST++/Bailando σ of 3 frames does).
"""
from __future__ import annotations

import os

import numpy as np
import numpy.typing as npt
from scipy.ndimage import uniform_filter1d
from scipy.signal import find_peaks, stft

from evalsuite.metrics._validate import positions_array, positive

__all__ = ["read_wav", "onset_strength", "audio_onsets", "motion_beats", "beat_alignment_score",
           "beat_alignment"]


def read_wav(path: str | os.PathLike[str]) -> tuple[np.ndarray, int]:
    """Mono float signal in [-1, 1) and its sample rate (:func:`evalsuite.audio.read_wav`, channels averaged)."""
    from evalsuite.audio import read_wav as read
    from evalsuite.audio import to_mono

    samples, rate = read(path)
    return to_mono(samples), rate


def onset_strength(signal: npt.ArrayLike, sr: float, frame_s: float = 0.046, hop_s: float = 0.01,
                   compression: float = 100.0) -> tuple[np.ndarray, np.ndarray]:
    """Spectral-flux onset strength ``(N,)`` and the times (s) of its frames."""
    x = np.asarray(signal, dtype=np.float64).ravel()
    sr = positive(sr, "sample rate")
    nper = max(16, int(round(frame_s * sr)))
    hop = max(1, int(round(hop_s * sr)))
    if x.size < nper:
        x = np.pad(x, (0, nper - x.size))
    _, times, spec = stft(x, fs=sr, window="hann", nperseg=nper, noverlap=nper - hop, boundary="zeros",
                          padded=True)
    mag = np.log1p(compression * np.abs(spec))
    flux = np.maximum(np.diff(mag, axis=1, prepend=mag[:, :1]), 0.0).sum(axis=0)
    peak = flux.max()
    return (flux / peak if peak > 0 else flux), times


def audio_onsets(signal: npt.ArrayLike, sr: float, *, frame_s: float = 0.046, hop_s: float = 0.01,
                 min_interval_s: float = 0.1, delta: float = 0.07, threshold_window_s: float = 0.5) -> np.ndarray:
    """Onset times (s) by spectral-flux peak picking (see the module docstring)."""
    env, times = onset_strength(signal, sr, frame_s, hop_s)
    if env.max() <= 0:
        return np.zeros(0)
    hop = times[1] - times[0] if len(times) > 1 else hop_s
    window = max(1, int(round(threshold_window_s / hop)))
    threshold = uniform_filter1d(env, size=window, mode="nearest") + delta
    peaks, _ = find_peaks(env, height=threshold, distance=max(1, int(round(min_interval_s / hop))))
    return np.asarray(times[peaks])


def motion_beats(positions: npt.ArrayLike, fps: float, *, min_interval_s: float = 0.2, prominence: float = 0.1,
                 smooth_s: float = 0.0) -> np.ndarray:
    """Motion beat times (s): local minima of the mean joint speed ``(T, J, 3)`` -> ``(K,)``.

    ``prominence`` is relative to the median speed (minima shallower than that are noise);
    ``smooth_s`` > 0 applies a moving average of that length to the speed first.
    """
    x = positions_array(positions, min_frames=3)
    fps = positive(fps, "fps")
    d = np.diff(x, axis=0)
    speed = np.sqrt(np.einsum("tjk,tjk->tj", d, d)).mean(axis=1) * fps
    if smooth_s > 0:
        speed = uniform_filter1d(speed, size=max(1, int(round(smooth_s * fps))), mode="nearest")
    scale = float(np.median(speed))
    if not scale > 0:
        scale = float(speed.max())
    if not scale > 0:
        return np.zeros(0)  # no motion, no beats
    minima, _ = find_peaks(-speed, distance=max(1, int(round(min_interval_s * fps))),
                           prominence=prominence * scale)
    return np.asarray((minima + 0.5) / fps)


def beat_alignment_score(source_beats: npt.ArrayLike, target_beats: npt.ArrayLike, sigma: float = 0.1) -> float:
    """Mean over source beats of ``exp(-d²/(2σ²))``, d = distance (s) to the nearest target beat."""
    sigma = positive(sigma, "sigma")
    src = np.sort(np.asarray(source_beats, dtype=np.float64).ravel())
    tgt = np.sort(np.asarray(target_beats, dtype=np.float64).ravel())
    if src.size == 0:
        return float("nan")
    if tgt.size == 0:
        return 0.0
    pos = np.clip(np.searchsorted(tgt, src), 1, max(tgt.size - 1, 1))
    left = tgt[np.maximum(pos - 1, 0)]
    right = tgt[np.minimum(pos, tgt.size - 1)]
    d = np.minimum(np.abs(src - left), np.abs(src - right))
    return float(np.mean(np.exp(-(d ** 2) / (2 * sigma ** 2))))


def beat_alignment(audio_beats: npt.ArrayLike, motion_beat_times: npt.ArrayLike, sigma: float = 0.1) -> dict[str, float]:
    """Both directions: ``{"a2m": audio onsets -> motion beats, "m2a": motion beats -> audio onsets}``."""
    return {"a2m": beat_alignment_score(audio_beats, motion_beat_times, sigma),
            "m2a": beat_alignment_score(motion_beat_times, audio_beats, sigma)}
