"""The speech features of the published Aud2Repr2Pose English demo (Kucherenko et al., "Moving fast and
slow"), reproduced with every quirk of the original code (facts from the golden README of its run):

* **MFCC** (python_speech_features 0.6 ``mfcc``, window 0.0667 s, step 0.0167 s, 26 coefficients, defaults
  otherwise: ``nfft = 512`` keeps only the first 512 samples of each window, column 0 is the log frame
  energy), computed on the file's own sample rate and integer scale; a stereo file is mixed as
  ``(L + R) / 2`` **in int16**, so ``L + R`` wraps around where it overflows; the 60-fps frames are
  subsampled ``[0::3]`` to 20 fps.
* **Prosody** from Praat (through praat-parselmouth: the optional ``praat`` extra, GPL-3) on the file as it is
  (both channels): pitch (To Pitch, defaults) and intensity (To Intensity, defaults) queried every
  ``ts = 5.555555555 ms`` (not exactly 1/180 s); NaN -> 0; ``pitch_norm = max(ln(f0 + 1) - 4, 0)``,
  ``intensity_norm = max(ln(I_dB) - 3, 0)``; derivatives per millisecond (``dx = 1000 ts``), the first 0;
  the four tracks averaged over blocks of 9 queries (tail dropped) -> 20 fps.
* **Assembly**: ``N = min(n_mfcc, n_prosody)``; 30 features per frame; 30 padding rows before and after, each
  the MFCC of silence **at 44.1 kHz** (whatever the input rate) + four zeros; 61-frame windows, stride 1.

Shapes: :func:`demo_features` -> ``(N, 30)``; :func:`demo_windows` -> ``(N, 61, 30)`` (what the model reads).
"""
from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np

from evalsuite.audio import read_wav
from evalsuite.errors import InputError

__all__ = ["DemoFeatures", "demo_mfcc", "demo_prosody", "demo_features", "demo_windows", "silence_row",
           "CONTEXT", "TIME_STEP"]

WINLEN, WINSTEP, NUMCEP = 0.06666666666, 0.0166666666, 26
TIME_STEP = 0.005555555555        # the original's WINDOW_LENGTH / 1000
BLOCK = 9                          # prosody queries averaged per 20-fps frame
CONTEXT = 30                       # frames of context on each side (61-frame windows)
PAD_RATE = 44100                   # the original computes its padding row from a 44.1 kHz silence file


def _mfcc(signal: np.ndarray, rate: int) -> np.ndarray:
    # python_speech_features logs that each frame is longer than nfft: that truncation is the recipe
    from evalsuite.features.mfcc import psf_mfcc

    return psf_mfcc(signal, rate, winlen=WINLEN, winstep=WINSTEP, numcep=NUMCEP)


def _mono_int16_wrap(raw: np.ndarray) -> np.ndarray:
    """The original's channel mix: ``(L + R) / 2`` with ``L + R`` in the file's integer type (wraps)."""
    if raw.shape[1] == 1:
        return raw[:, 0]
    if raw.shape[1] != 2:
        raise InputError(f"the demo recipe reads mono or stereo WAV, got {raw.shape[1]} channels")
    with np.errstate(over="ignore"):
        return (raw[:, 0] + raw[:, 1]) / 2


def demo_mfcc(path: str | os.PathLike[str]) -> np.ndarray:
    """``(n_mfcc, 26)`` MFCC at 20 fps as the demo computes them (see the module docstring)."""
    raw, rate = read_wav(path, raw=True)
    if raw.dtype.kind not in "iu":
        raise InputError("the demo recipe reproduces integer arithmetic: expected an integer PCM WAV file",
                         path=path)
    return _mfcc(_mono_int16_wrap(raw), rate)[0::3]


def silence_row() -> np.ndarray:
    """``(30,)`` padding row: MFCC frame 0 of silence at 44.1 kHz, then four zero prosody values."""
    return _silence_row().copy()


@functools.lru_cache(maxsize=1)
def _silence_row() -> np.ndarray:
    frame = _mfcc(np.zeros(int(round(WINLEN * PAD_RATE)) + 1, dtype=np.int16), PAD_RATE)[0]
    return np.concatenate([frame, np.zeros(4)])


def demo_prosody(path: str | os.PathLike[str], *, per_query: bool = False) -> np.ndarray:
    """``(n_prosody, 4)`` = [intensity_norm, d intensity, pitch_norm, d pitch] at 20 fps (``per_query``:
    the ``(K, 4)`` tracks at the Praat query rate before averaging). Needs praat-parselmouth."""
    try:
        import parselmouth
    except ImportError:
        raise InputError("the aud2repr2pose_demo recipe computes pitch and intensity with Praat: "
                         "pip install 'evalsuite[praat]' (praat-parselmouth, GPL-3)") from None
    try:
        sound = parselmouth.Sound(os.fspath(path))
    except parselmouth.PraatError as exc:
        raise InputError(f"Praat cannot read this audio ({exc})", path=path) from None
    pitch = sound.to_pitch(time_step=TIME_STEP)
    intensity = sound.to_intensity(time_step=TIME_STEP)
    times = np.arange(0, sound.get_total_duration() - TIME_STEP, TIME_STEP)
    f0 = np.array([pitch.get_value_at_time(t) for t in times], dtype=np.float64)
    db = np.array([intensity.get_value(t) for t in times], dtype=np.float64)
    f0 = np.nan_to_num(f0, nan=0.0)
    db = np.maximum(np.nan_to_num(db, nan=0.0), np.finfo(np.float64).eps)
    with np.errstate(divide="ignore"):
        pitch_norm = np.maximum(np.log(f0 + 1) - 4, 0)
        intensity_norm = np.maximum(np.log(db) - 3, 0)
    dx = 1000 * TIME_STEP   # per millisecond, as the original

    def derivative(x: np.ndarray) -> np.ndarray:
        d = np.zeros_like(x)
        d[1:] = (x[1:] - x[:-1]) / dx
        return d

    tracks = np.stack([intensity_norm, derivative(intensity_norm), pitch_norm, derivative(pitch_norm)], axis=1)
    if per_query:
        return tracks
    n = len(tracks) // BLOCK
    return tracks[: n * BLOCK].reshape(n, BLOCK, 4).mean(axis=1)


@dataclass(frozen=True)
class DemoFeatures:
    """The demo's features of one file and the windows its speech encoder reads."""

    features: np.ndarray   # (N, 30)
    windows: np.ndarray    # (N, 61, 30)


def demo_features(path: str | os.PathLike[str]) -> np.ndarray:
    """``(N, 30)`` = 26 MFCC + 4 prosody features at 20 fps, ``N = min(n_mfcc, n_prosody)``."""
    mfcc = demo_mfcc(path)
    prosody = demo_prosody(path)
    n = min(len(mfcc), len(prosody))
    return np.concatenate([mfcc[:n], prosody[:n]], axis=1)


def demo_windows(features: np.ndarray) -> np.ndarray:
    """``(N, 30)`` -> ``(N, 61, 30)``: each frame with 30 frames of context on each side, padded with
    :func:`silence_row`."""
    pad = np.tile(silence_row(), (CONTEXT, 1))
    padded = np.concatenate([pad, np.asarray(features, dtype=np.float64), pad])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * CONTEXT + 1, axis=0)
    return np.ascontiguousarray(windows.transpose(0, 2, 1))
