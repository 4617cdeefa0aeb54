"""The synthetic speaker's voice: espeak-ng, word by word, so that every word's time is known to the sample.

Each distinct (word, emphasised) pair is synthesised once by the ``espeak-ng`` program (a separate
process; calls run in a thread pool), its leading and trailing silence is trimmed, and the clips are
concatenated with short gaps between words and longer pauses between phrases and sentences. A word
spans exactly the samples of its clip, so the transcript's times are exact. Emphasised words are spoken
louder (``-a``) and higher (``-p``).
"""
from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from evalsuite.errors import InputError

__all__ = ["Voice", "espeak_version", "WordBank", "trim_silence", "ESPEAK"]

ESPEAK = "espeak-ng"


@dataclass(frozen=True)
class Voice:
    """espeak-ng settings: voice, rate (words per minute), amplitude and pitch (0-99) of plain and
    emphasised words, and the silence threshold for trimming (fraction of int16 full scale)."""

    voice: str = "en"
    rate: int = 165
    amplitude: int = 90
    pitch: int = 45
    emphasis_amplitude: int = 170
    emphasis_pitch: int = 75
    trim_threshold: float = 0.01
    trim_margin_s: float = 0.004


def _espeak() -> str:
    path = shutil.which(ESPEAK)
    if path is None:
        raise InputError("the espeak-ng program is not installed (Debian/Ubuntu: apt-get install espeak-ng; "
                         "scripts/install-system-packages installs it)")
    return path


def espeak_version() -> str:
    """``espeak-ng --version``'s first line (recorded in corpus.json)."""
    out = subprocess.run([_espeak(), "--version"], capture_output=True, text=True, check=True)
    return out.stdout.strip().splitlines()[0] if out.stdout.strip() else "unknown"


def trim_silence(x: np.ndarray, rate: int, threshold: float, margin_s: float) -> np.ndarray:
    """The clip from ``margin_s`` before its first to ``margin_s`` after its last sample above
    ``threshold`` (fraction of full scale)."""
    loud = np.flatnonzero(np.abs(x.astype(np.float64)) > threshold * 32768.0)
    if loud.size == 0:
        return x[:0]
    m = int(round(margin_s * rate))
    return x[max(0, loud[0] - m): min(len(x), loud[-1] + m + 1)]


def _parse_stream_wav(data: bytes, word: str) -> tuple[np.ndarray, int]:
    """Samples and rate of the WAV espeak-ng writes to stdout (a streaming header: its sizes are
    placeholders, so the samples are everything after the ``data`` chunk's header)."""
    if data[:4] != b"RIFF" or data[8:12] != b"WAVE":
        raise InputError(f"espeak-ng did not write a WAV stream for {word!r}")
    rate = int.from_bytes(data[24:28], "little")
    bits = int.from_bytes(data[34:36], "little")
    channels = int.from_bytes(data[22:24], "little")
    at = data.find(b"data", 12)
    if at < 0 or bits != 16:
        raise InputError(f"espeak-ng wrote an unexpected WAV stream for {word!r} ({bits} bits)")
    body = data[at + 8:]
    samples = np.frombuffer(body[: len(body) // 2 * 2], dtype="<i2").reshape(-1, max(1, channels))[:, 0]
    return samples.astype(np.int16), rate


def _say(word: str, emphasised: bool, voice: Voice) -> tuple[np.ndarray, int]:
    amp = voice.emphasis_amplitude if emphasised else voice.amplitude
    pitch = voice.emphasis_pitch if emphasised else voice.pitch
    cmd = [_espeak(), "--stdout", "-v", voice.voice, "-s", str(voice.rate), "-a", str(amp), "-p", str(pitch), word]
    out = subprocess.run(cmd, capture_output=True, check=False)
    if out.returncode != 0 or not out.stdout:
        raise InputError(f"espeak-ng failed on {word!r}: {out.stderr.decode(errors='replace').strip()}")
    data, rate = _parse_stream_wav(out.stdout, word)
    return trim_silence(data, rate, voice.trim_threshold, voice.trim_margin_s), rate


class WordBank:
    """Trimmed int16 clips of ``(word, emphasised)`` pairs, synthesised once each (:meth:`add`)."""

    def __init__(self, voice: Voice, jobs: int = 2):
        self.voice, self.jobs = voice, jobs
        self.clips: dict[tuple[str, bool], np.ndarray] = {}
        self.rate: int | None = None

    def add(self, items: Iterable[tuple[str, bool]]) -> None:
        todo = sorted({it for it in items if it not in self.clips})
        if not todo:
            return
        with ThreadPoolExecutor(max_workers=max(1, self.jobs)) as pool:
            for key, (clip, rate) in zip(todo, pool.map(lambda k: _say(k[0], k[1], self.voice), todo)):
                if clip.size == 0:
                    raise InputError(f"espeak-ng produced silence for {key[0]!r}")
                if self.rate is not None and rate != self.rate:
                    raise InputError(f"espeak-ng returned sample rates {self.rate} and {rate}")
                self.rate = rate
                self.clips[key] = clip

    def __getitem__(self, key: tuple[str, bool]) -> np.ndarray:
        return self.clips[key]
