"""Speech audio for videos: read (WAV or anything ffmpeg decodes), write WAV, cut, trim, synthesise.

Samples are float32 in [-1, 1], shape ``(n, channels)``.
"""
from __future__ import annotations

import pathlib
import subprocess

import numpy as np

from evalsuite.audio import read_wav
from evalsuite.audio import write_wav as _write_wav
from evalsuite.errors import InputError


def read_audio(path) -> tuple[np.ndarray, int]:
    """``(samples (n, channels) float32, sample_rate)`` of an audio file.

    WAV is read directly; other formats (mp3, flac, m4a, ...) are decoded with the ffmpeg
    that imageio-ffmpeg ships.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such audio file", path=path)
    if path.suffix.lower() == ".wav":
        samples, rate = read_wav(path)
        return samples.astype(np.float32), rate
    return decode_audio(path)


def decode_audio(path, sample_rate: int | None = None, channels: int | None = None) -> tuple[np.ndarray, int]:
    """Decode the first audio stream of any media file with ffmpeg (float32)."""
    import imageio_ffmpeg

    rate = sample_rate or _probe_audio_rate(path) or 44100
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(path), "-vn", "-f", "f32le",
           "-acodec", "pcm_f32le", "-ar", str(rate)]
    ch = channels or 1
    cmd += ["-ac", str(ch), "-"]
    proc = subprocess.run(cmd, capture_output=True)
    if proc.returncode != 0:
        raise InputError(f"ffmpeg could not decode audio: {proc.stderr.decode(errors='replace').strip()[-300:]}",
                         path=path)
    data = np.frombuffer(proc.stdout, dtype=np.float32).reshape(-1, ch)
    return data.copy(), rate


def _probe_audio_rate(path) -> int | None:
    from renderers.media_probe import probe

    info = probe(path)
    return info.get("audio_rate")


def write_wav(path, samples: np.ndarray, rate: int) -> None:
    """Write 16-bit PCM WAV (:func:`evalsuite.audio.write_wav`)."""
    _write_wav(path, np.clip(np.asarray(samples, dtype=np.float64), -1.0, 1.0), rate)


def cut_audio(samples: np.ndarray, rate: int, start: float = 0.0, end: float | None = None,
              label: str = "") -> np.ndarray:
    """Samples from ``start`` to ``end`` seconds: sample ``round(start * rate)`` up to ``round(end * rate)``.

    The same window as a motion cut, so speech stays in sync with the cut motion. An ``end``
    past the audio's end keeps what there is (the caller compares lengths); a ``start`` at or
    past it is an :class:`InputError`.
    """
    first = int(round(start * rate))
    if start < 0 or first >= len(samples):
        raise InputError(f"{label + ': ' if label else ''}the cut starts at {start:.3f} s but the audio lasts "
                         f"{len(samples) / rate:.3f} s", field="start")
    last = len(samples) if end is None else int(round(end * rate))
    return samples[first:last]


def fit_length(samples: np.ndarray, n_samples: int) -> np.ndarray:
    """Trim to ``n_samples`` or pad with silence at the end."""
    if len(samples) >= n_samples:
        return samples[:n_samples]
    pad = np.zeros((n_samples - len(samples),) + samples.shape[1:], dtype=samples.dtype)
    return np.concatenate([samples, pad])


def speech_like_audio(seconds: float, rate: int = 16000, seed: int = 0) -> np.ndarray:
    """Synthetic 'speech': syllable-rate tone bursts with pauses (mono float32 ``(n, 1)``).

    Harmonic bursts of 120-250 Hz fundamental, 4-6 bursts per second with a raised-cosine
    envelope, grouped into phrases separated by short silences. For tests and demos: it
    has speech's rhythm without needing any recorded speech.
    """
    rng = np.random.default_rng(seed)
    n = int(round(seconds * rate))
    t = np.arange(n) / rate
    syll_rate = rng.uniform(4.0, 6.0)
    f0 = rng.uniform(120.0, 250.0) * (1.0 + 0.08 * np.sin(2 * np.pi * 0.7 * t))
    phase = 2 * np.pi * np.cumsum(f0) / rate
    voice = sum(np.sin(k * phase) / k for k in range(1, 6))
    envelope = np.clip(np.sin(np.pi * syll_rate * t), 0.0, None) ** 2
    phrase = (np.sin(2 * np.pi * 0.25 * t + rng.uniform(0, 2 * np.pi)) > -0.6).astype(np.float64)
    signal = 0.3 * voice * envelope * phrase
    return signal.astype(np.float32)[:, None]


def distort_audio(samples: np.ndarray, rate: int, seed: int = 0) -> np.ndarray:
    """Heavily distorted audio for attention checks.

    Hard clipping after +30 dB gain, 45 Hz ring modulation, 4-bit quantisation and white
    noise at about the speech level: still audibly 'the same clip', but obviously broken.
    """
    rng = np.random.default_rng(seed)
    x = np.asarray(samples, dtype=np.float64)
    t = (np.arange(len(x)) / rate)[:, None]
    level = float(np.sqrt(np.mean(x ** 2))) or 0.1
    y = np.clip(x * 30.0 / max(level * 10.0, 1e-6), -1.0, 1.0)
    y = y * np.sin(2 * np.pi * 45.0 * t)
    y = np.round(y * 8.0) / 8.0
    y = 0.6 * y + 0.35 * rng.standard_normal(x.shape)
    return np.clip(y, -1.0, 1.0).astype(np.float32)
