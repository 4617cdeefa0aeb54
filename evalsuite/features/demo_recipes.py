"""The Aud2Repr2Pose English demo's input as recipes: ``aud2repr2pose_demo`` (``(T, 30)`` = 26 MFCC + 4 Praat
prosody features at 20 fps) and ``aud2repr2pose_demo_windows`` (``(T, 61, 30)``, the padded windows the
published model reads). Both are :mod:`evalsuite.features.aud2repr2pose_demo` (every quirk documented there);
they need the ``praat`` extra. The original reads a file: audio given as ``(samples, rate)`` is written to a
temporary 16-bit WAV first (floats in [-1, 1) rounded to ``x * 32768``; integer arrays written as they are).
The windows recipe keeps the native 20 fps (it refuses another rate: the model was trained at 20 fps);
``n_frames`` crops or edge-pads the windows after they are built.
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

from evalsuite.errors import InputError
from evalsuite.features.aud2repr2pose_demo import demo_features, demo_windows
from evalsuite.features.base import Audio, Recipe, register_recipe

__all__ = ["demo_recipe_features"]


def demo_recipe_features(audio: Audio) -> np.ndarray:
    """``(N, 30)`` of a file, or of samples written to a temporary WAV."""
    if audio.path is not None:
        return demo_features(audio.path)
    from scipy.io import wavfile

    x = audio.samples
    if x.dtype.kind == "f":
        x = np.clip(np.round(x * 32768.0), -32768, 32767).astype(np.int16)
    elif x.dtype.kind not in "iu":  # pragma: no cover - load_audio refuses other kinds
        raise InputError(f"audio samples must be integers or floats, got {x.dtype}")
    fd, tmp = tempfile.mkstemp(suffix=".wav")
    os.close(fd)
    try:
        wavfile.write(tmp, audio.rate, x if x.shape[1] > 1 else x[:, 0])
        return demo_features(tmp)
    finally:
        os.unlink(tmp)


def _windows(audio: Audio, fps: float | None) -> np.ndarray:
    return demo_windows(demo_recipe_features(audio))


_QUIRKS = ("MFCC: 66.7 ms windows every 16.7 ms with nfft 512 (truncates), stereo (L + R) / 2 wraps in int16, "
           "[0::3] to 20 fps; Praat pitch and intensity every 5.555555555 ms, log-normalised, derivatives per "
           "millisecond, averaged over 9 queries; padding row computed at 44.1 kHz")

register_recipe(Recipe(
    name="aud2repr2pose_demo", native_fps=20.0, dim=30, extra="praat",
    reproduces="the published Aud2Repr2Pose English demo (Kucherenko et al., 'Moving fast and slow', IJHCI 2021; "
               "speech-driven-hand-gesture-generation-demo): 26 MFCC + 4 prosody features at 20 fps",
    quirks=_QUIRKS,
    compute=lambda audio, transcript, fps, n, opts: demo_recipe_features(audio)))

register_recipe(Recipe(
    name="aud2repr2pose_demo_windows", native_fps=20.0, dim=(61, 30), extra="praat",
    reproduces="the model input of the published Aud2Repr2Pose English demo: 61-frame windows (30 past, current, "
               "30 future) of its 30 features, padded with the MFCC of silence at 44.1 kHz",
    quirks=_QUIRKS + "; only 20 fps", resamplable=False,
    compute=lambda audio, transcript, fps, n, opts: _windows(audio, fps)))
