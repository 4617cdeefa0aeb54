"""Pitch and energy tracks at 100 fps, frame ``t`` centred on ``t / 100`` s (audio mixed to mono in floating
point, samples in [-1, 1)).

``pitch`` -- the permissive default tracker, numpy only, after YIN (de Cheveigné & Kawahara 2002): for each
frame, the difference function ``d(tau) = sum_j (x_j - x_{j+tau})^2`` over an integration window of
``2 / fmin`` seconds, its cumulative-mean normalisation ``d'(tau) = d(tau) tau / sum_{k<=tau} d(k)``, the
first ``tau`` in ``[rate / fmax, rate / fmin]`` where ``d'`` drops below ``threshold`` (0.15), moved on to
the bottom of that dip and refined by parabolic interpolation; F0 = ``rate / tau`` in Hz. A frame is
unvoiced (F0 = 0) when no dip goes below the threshold or its RMS is below ``silence_db`` (-60 dBFS).
Defaults fmin 60 Hz, fmax 500 Hz (adult speech). The threshold 0.3 is permissive (YIN's paper uses 0.1): on the
Aud2Repr2Pose demo recording it marks 55 % of frames voiced where Praat marks 67 %, 0.3 % voiced where Praat
says unvoiced, and F0 within 0.33 % of Praat's in the median of frames both call voiced (1.5 % differ by more
than 5 %). Not Praat: voicing decisions and octave choices can differ; use ``pitch_praat`` for Praat's.

``energy`` -- RMS of a rectangular window of 0.04 s centred on the frame, in dB re full scale:
``10 log10(max(mean(x^2), 1e-10))`` (a full-scale sine: -3.01 dB; silence: -100 dB).

``pitch_praat`` -- Praat's ``To Pitch`` (autocorrelation, default settings: floor 75 Hz, ceiling 600 Hz, time
step 0.75 / floor) through praat-parselmouth (the optional ``praat`` extra, GPL-3), queried at ``t / 100``
with linear interpolation between Praat frames; undefined -> 0.
"""
from __future__ import annotations

import numpy as np

from evalsuite.errors import InputError
from evalsuite.features.base import Audio, Recipe, register_recipe

__all__ = ["yin_pitch", "rms_db", "frame_centres", "praat_pitch"]

FPS = 100.0


def frame_centres(duration: float, fps: float = FPS) -> np.ndarray:
    """Times ``t / fps`` of the frames of a signal ``duration`` seconds long: ``ceil(duration * fps)`` frames."""
    return np.arange(max(int(np.ceil(duration * fps - 1e-9)), 1)) / fps


def _segments(x: np.ndarray, starts: np.ndarray, length: int) -> np.ndarray:
    """``(len(starts), length)`` slices of ``x`` from each start, zero outside the signal."""
    lo = int(min(starts.min(), 0))
    hi = int(max(starts.max() + length - len(x), 0))
    padded = np.concatenate([np.zeros(-lo), x, np.zeros(hi)])
    idx = (starts - lo)[:, None] + np.arange(length)[None, :]
    return padded[idx]


def yin_pitch(x: np.ndarray, rate: int, centres: np.ndarray, *, fmin: float = 60.0, fmax: float = 500.0,
              threshold: float = 0.3, silence_db: float = -60.0) -> np.ndarray:
    """F0 in Hz (0 when unvoiced) of mono ``x`` at the times ``centres`` (seconds); see the module docstring."""
    if not (0 < fmin < fmax < rate / 2):
        raise InputError(f"pitch range must satisfy 0 < fmin < fmax < rate/2, got {fmin}..{fmax} Hz at {rate} Hz")
    x = np.asarray(x, dtype=np.float64)
    centres = np.asarray(centres, dtype=np.float64)
    tau_min = max(int(np.floor(rate / fmax)), 2)
    tau_max = int(np.ceil(rate / fmin))
    w = int(np.ceil(2.0 * rate / fmin))
    length = w + tau_max + 2
    nfft = 1 << int(np.ceil(np.log2(length + w)))
    out = np.zeros(len(centres))
    gate = 10.0 ** (silence_db / 10.0)
    for b in range(0, len(centres), 256):
        c = centres[b:b + 256]
        seg = _segments(x, np.round(c * rate).astype(np.int64) - length // 2, length)
        spec_all = np.fft.rfft(seg, nfft)
        spec_head = np.fft.rfft(seg[:, :w], nfft)
        r = np.fft.irfft(np.conj(spec_head) * spec_all, nfft)[:, : tau_max + 2]
        sq = np.concatenate([np.zeros((len(seg), 1)), np.cumsum(seg ** 2, axis=1)], axis=1)
        taus = np.arange(tau_max + 2)
        energy_tau = sq[:, taus + w] - sq[:, taus]
        d = np.maximum(energy_tau[:, :1] + energy_tau - 2.0 * r, 0.0)
        cum = np.cumsum(d[:, 1:], axis=1)
        dn = np.ones_like(d)
        with np.errstate(divide="ignore", invalid="ignore"):
            dn[:, 1:] = np.where(cum > 0, d[:, 1:] * taus[1:] / cum, 1.0)
        loud = energy_tau[:, 0] / w >= gate
        for i in np.flatnonzero(loud):
            row = dn[i]
            below = np.flatnonzero(row[tau_min: tau_max + 1] < threshold)
            if below.size == 0:
                continue
            tau = tau_min + int(below[0])
            while tau + 1 <= tau_max and row[tau + 1] < row[tau]:
                tau += 1
            a, m, z = row[tau - 1], row[tau], row[tau + 1]
            den = a - 2.0 * m + z
            shift = 0.5 * (a - z) / den if den > 0 else 0.0
            out[b + i] = rate / (tau + float(np.clip(shift, -1.0, 1.0)))
    return out


def rms_db(x: np.ndarray, rate: int, centres: np.ndarray, *, window: float = 0.04) -> np.ndarray:
    """RMS in dB re full scale over a rectangular window centred at each time in ``centres``."""
    x = np.asarray(x, dtype=np.float64)
    n = max(int(round(window * rate)), 1)
    sq = np.concatenate([[0.0], np.cumsum(x ** 2)])
    start = np.round(np.asarray(centres) * rate).astype(np.int64) - n // 2
    lo = np.clip(start, 0, len(x))
    hi = np.clip(start + n, 0, len(x))
    mean_sq = (sq[hi] - sq[lo]) / n          # zeros outside the signal
    return 10.0 * np.log10(np.maximum(mean_sq, 1e-10))


def praat_pitch(audio: Audio, centres: np.ndarray, *, floor: float = 75.0, ceiling: float = 600.0) -> np.ndarray:
    """Praat's pitch (Hz, 0 undefined) at ``centres``; needs praat-parselmouth."""
    try:
        import parselmouth
    except ImportError:
        raise InputError("recipe 'pitch_praat' needs Praat: pip install 'evalsuite[praat]' "
                         "(praat-parselmouth, GPL-3)") from None
    sound = parselmouth.Sound(audio.mono(), sampling_frequency=float(audio.rate))
    try:
        pitch = sound.to_pitch(pitch_floor=floor, pitch_ceiling=ceiling)
    except parselmouth.PraatError as exc:
        raise InputError(f"Praat cannot compute the pitch of this audio ({exc})", path=audio.path) from None
    f0 = np.array([pitch.get_value_at_time(float(t)) for t in centres], dtype=np.float64)
    return np.nan_to_num(f0, nan=0.0)


def _pitch(audio: Audio, opts: dict) -> np.ndarray:
    centres = frame_centres(audio.duration)
    return yin_pitch(audio.mono(), audio.rate, centres, fmin=opts["fmin"], fmax=opts["fmax"],
                     threshold=opts["threshold"], silence_db=opts["silence_db"])[:, None]


register_recipe(Recipe(
    name="pitch", native_fps=FPS, dim=1,
    reproduces="a permissive YIN-style F0 tracker (de Cheveigne & Kawahara 2002), numpy only",
    quirks="F0 in Hz, 0 when unvoiced; frames centred on t/100 s; not Praat (use pitch_praat for that)",
    compute=lambda audio, transcript, fps, n, opts: _pitch(audio, opts),
    params={"fmin": 60.0, "fmax": 500.0, "threshold": 0.3, "silence_db": -60.0}))

register_recipe(Recipe(
    name="energy", native_fps=FPS, dim=1,
    reproduces="RMS energy in dB re full scale, 0.04 s rectangular windows centred on t/100 s",
    quirks="floor -100 dB; zeros outside the signal count in the mean",
    compute=lambda audio, transcript, fps, n, opts: rms_db(audio.mono(), audio.rate, frame_centres(audio.duration),
                                                         window=opts["window"])[:, None],
    params={"window": 0.04}))

register_recipe(Recipe(
    name="pitch_praat", native_fps=FPS, dim=1, extra="praat",
    reproduces="Praat To Pitch (autocorrelation, floor 75 Hz, ceiling 600 Hz) via praat-parselmouth",
    quirks="mono mix in floating point; queried at t/100 s with Praat's linear interpolation; undefined -> 0",
    compute=lambda audio, transcript, fps, n, opts: praat_pitch(audio, frame_centres(audio.duration),
                                                                floor=opts["floor"], ceiling=opts["ceiling"])[:, None],
    params={"floor": 75.0, "ceiling": 600.0}))
