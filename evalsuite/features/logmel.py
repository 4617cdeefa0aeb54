"""Gesticulator's 64-band log-mel spectrogram (Kucherenko et al., ICMI 2020; ``calculate_spectrogram`` in its
``data_processing/tools.py``), computed with numpy/scipy instead of librosa (which pulls numba).

What the original does, and what this recipe does:

1. ``librosa.load(path)``: channels averaged (float), resampled to **22,050 Hz**. Here:
   :func:`scipy.signal.resample_poly` (Kaiser window, beta 5). librosa 0.7 resampled with resampy's
   ``kaiser_best`` (later versions: soxr), so values differ slightly, most near the band edges and in the
   first and last few milliseconds (against librosa 0.11 on a 44.1 kHz recording: log-mel within 1e-5 with
   its ``res_type='polyphase'``, within 0.004 with its default soxr_hq).
2. ``librosa.feature.melspectrogram(y, sr=22050, window=scipy.signal.hanning, hop_length=int(0.1 * 22050 / 2),
   fmin=100, fmax=7500, n_mels=64)`` with librosa's defaults otherwise: ``n_fft = 2048``, ``win_length =
   n_fft``, ``center=True`` with **reflect** padding of ``n_fft // 2`` (librosa 0.7; 0.10 pads with zeros),
   power 2. The quirks kept: the hop is **1102 samples** (0.04998 s, so the native rate is 22050 / 1102 =
   20.009 fps, which the original treats as 20 fps), and ``scipy.signal.hanning`` is called as ``window(2048)``,
   the **symmetric** Hann window (librosa's own ``'hann'`` would be periodic).
3. Mel filterbank as ``librosa.filters.mel`` by default: Slaney's mel scale (linear below 1 kHz, logarithmic
   above), 66 points evenly spaced in mel from 100 to 7500 Hz, triangles over the FFT bin frequencies,
   each scaled by ``2 / (f[i+2] - f[i])`` (Slaney area normalisation).
4. ``log(|S| + 1e-10)`` of the power mel spectrogram -> ``(1 + len(y) // 1102, 64)``.

librosa computes in float32; this recipe in float64 (relative differences around 1e-6 before the log).
Frame ``t`` is centred on ``t * 1102 / 22050`` s.
"""
from __future__ import annotations

from math import gcd

import numpy as np

from evalsuite.features.base import Audio, Recipe, register_recipe

__all__ = ["SR", "HOP", "N_FFT", "N_MELS", "hz_to_mel_slaney", "mel_to_hz_slaney", "mel_filterbank", "gesticulator_logmel"]

SR = 22050
N_FFT = 2048
HOP = int(0.1 * SR / 2)          # 1102
N_MELS, FMIN, FMAX = 64, 100.0, 7500.0

_F_SP = 200.0 / 3
_MIN_LOG_HZ = 1000.0
_MIN_LOG_MEL = _MIN_LOG_HZ / _F_SP
_LOGSTEP = np.log(6.4) / 27.0


def hz_to_mel_slaney(f: np.ndarray | float) -> np.ndarray:
    f = np.asarray(f, dtype=np.float64)
    lin = f / _F_SP
    with np.errstate(divide="ignore"):
        log = _MIN_LOG_MEL + np.log(np.maximum(f, 1e-300) / _MIN_LOG_HZ) / _LOGSTEP
    return np.where(f >= _MIN_LOG_HZ, log, lin)


def mel_to_hz_slaney(m: np.ndarray | float) -> np.ndarray:
    m = np.asarray(m, dtype=np.float64)
    return np.where(m >= _MIN_LOG_MEL, _MIN_LOG_HZ * np.exp(_LOGSTEP * (m - _MIN_LOG_MEL)), _F_SP * m)


def mel_filterbank(sr: int = SR, n_fft: int = N_FFT, n_mels: int = N_MELS, fmin: float = FMIN,
                   fmax: float = FMAX) -> np.ndarray:
    """``(n_mels, 1 + n_fft // 2)`` Slaney-style triangular filters with area normalisation."""
    fft_f = np.linspace(0.0, sr / 2.0, 1 + n_fft // 2)
    mel_f = mel_to_hz_slaney(np.linspace(hz_to_mel_slaney(fmin), hz_to_mel_slaney(fmax), n_mels + 2))
    fdiff = np.diff(mel_f)
    ramps = mel_f[:, None] - fft_f[None, :]
    lower = -ramps[:-2] / fdiff[:-1, None]
    upper = ramps[2:] / fdiff[1:, None]
    weights = np.maximum(0.0, np.minimum(lower, upper))
    return weights * (2.0 / (mel_f[2:] - mel_f[:-2]))[:, None]


def resample_to(x: np.ndarray, rate: int, target: int = SR) -> np.ndarray:
    """``scipy.signal.resample_poly`` from ``rate`` to ``target`` (identity when equal)."""
    if rate == target:
        return np.asarray(x, dtype=np.float64)
    from scipy.signal import resample_poly

    g = gcd(int(rate), int(target))
    return resample_poly(np.asarray(x, dtype=np.float64), target // g, rate // g)


def gesticulator_logmel(audio: Audio) -> np.ndarray:
    """``(1 + n // 1102, 64)`` log-mel frames of the audio resampled to 22,050 Hz (see the module docstring)."""
    y = resample_to(audio.mono(), audio.rate)
    pad = N_FFT // 2
    if len(y) <= pad:   # numpy's reflect padding needs more samples than the pad: pad with zeros first
        y = np.concatenate([y, np.zeros(pad + 1 - len(y))])
    padded = np.pad(y, pad, mode="reflect")
    n_frames = 1 + (len(padded) - N_FFT) // HOP
    window = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(N_FFT) / (N_FFT - 1))   # symmetric Hann
    basis = mel_filterbank()
    out = np.empty((n_frames, N_MELS))
    for b in range(0, n_frames, 512):
        idx = np.arange(b, min(b + 512, n_frames))[:, None] * HOP + np.arange(N_FFT)[None, :]
        power = np.abs(np.fft.rfft(padded[idx] * window, axis=1)) ** 2
        out[b:b + len(idx)] = power @ basis.T
    return np.log(np.abs(out) + 1e-10)


register_recipe(Recipe(
    name="logmel_gesticulator", native_fps=SR / HOP, dim=N_MELS,
    reproduces="Gesticulator (Kucherenko et al., ICMI 2020) calculate_spectrogram: 64 log-mel bands, 100-7500 Hz, "
               "22,050 Hz, hop 0.05 s",
    quirks="hop int(0.05 * 22050) = 1102 samples (native 20.009 fps, treated as 20 by the original); symmetric "
           "Hann window of 2048; reflect padding; log(S + 1e-10) of power; resampling by scipy resample_poly "
           "instead of resampy/soxr (small differences); float64 instead of float32",
    compute=lambda audio, transcript, fps, n, opts: gesticulator_logmel(audio)))
