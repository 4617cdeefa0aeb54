"""The one WAV reader and writer of evalsuite.

Integer samples are scaled by ``2 ** (bits - 1)`` (int16 / 32768, the convention of soundfile,
librosa and torchaudio), so that -32768 maps to exactly -1.0; 8-bit WAV is unsigned and centred on 128;
float WAV is returned as it is. Samples are always 2-D, ``(N, C)``.
"""
from __future__ import annotations

import os
import pathlib
import warnings

import numpy as np

from evalsuite.errors import InputError

__all__ = ["read_wav", "write_wav", "to_mono"]


def read_wav(path: str | os.PathLike[str], *, raw: bool = False) -> tuple[np.ndarray, int]:
    """``(samples (N, C), sample_rate)`` of a WAV file.

    ``raw=False``: float64 in [-1, 1); ``raw=True``: the file's own samples (e.g. int16), for recipes
    that reproduce integer arithmetic of reference code.
    """
    from scipy.io import wavfile

    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such audio file", path=path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)
            rate, data = wavfile.read(path)
    except (ValueError, OSError, EOFError) as exc:
        raise InputError(f"not a readable WAV file ({exc})", path=path) from None
    data = np.asarray(data)
    if data.ndim == 1:
        data = data[:, None]
    if data.size == 0:
        raise InputError("the WAV file has no samples", path=path)
    if rate <= 0:
        raise InputError(f"the WAV header gives a sample rate of {rate}", path=path)
    if raw:
        return data, int(rate)
    if data.dtype == np.uint8:
        return (data.astype(np.float64) - 128.0) / 128.0, int(rate)
    if data.dtype.kind == "i":
        return data.astype(np.float64) / float(np.iinfo(data.dtype).max + 1), int(rate)
    return data.astype(np.float64), int(rate)


def to_mono(samples: np.ndarray) -> np.ndarray:
    """``(N, C)`` -> ``(N,)`` by averaging channels (float arithmetic)."""
    x = np.asarray(samples, dtype=np.float64)
    return x.mean(axis=1) if x.ndim == 2 else x


def write_wav(path: str | os.PathLike[str], samples: np.ndarray, rate: int) -> None:
    """Write 16-bit PCM: ``round(x * 32768)`` clipped to the int16 range (so :func:`read_wav` returns the
    same values for samples on the 1/32768 grid). ``samples``: ``(N,)`` or ``(N, C)`` floats in [-1, 1]."""
    from scipy.io import wavfile

    x = np.asarray(samples, dtype=np.float64)
    if x.ndim not in (1, 2) or not np.isfinite(x).all():
        raise InputError(f"audio samples must be finite and of shape (N,) or (N, C), got {x.shape}", path=path)
    pcm = np.clip(np.round(x * 32768.0), -32768, 32767).astype(np.int16)
    wavfile.write(str(path), int(rate), pcm)
