"""Plain-text transcripts: words without times, timed the way Gesticulator times plain text.

The words (split on white space, punctuation kept: Gesticulator splits sentences on ``. ! ?``) are spread
over the **voiced span** of the audio, each word's duration proportional to its syllable count, one word
after the other without pauses; every word is marked ``estimated=True``.

* Syllables: the larger of the hyphenation count of ``pyphen`` (en_US, breaks allowed next to the first and
  last letter) and a count of vowel groups (``a e i o u y``, a final silent ``e`` dropped); at least 1.
  Hyphenation alone undercounts some words ("area"), vowel groups alone some others ("learning" counts 2 by
  both). Without pyphen installed the vowel-group count is used.
* Voiced span: the audio (mixed to mono) in 20 ms frames; the span runs from the first to the last frame
  whose RMS is within ``threshold_db`` (default 35 dB) of the loudest frame. Without audio, pass the span.
"""
from __future__ import annotations

import os
import re
from functools import lru_cache
from typing import Any

import numpy as np

from evalsuite.corpus.transcripts._common import Item, read_text, to_transcript
from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError

__all__ = ["count_syllables", "voiced_span", "estimate_timings", "read_plain_text", "write_plain_text"]

_VOWEL_GROUP = re.compile(r"[aeiouy]+")


@lru_cache(maxsize=1)
def _pyphen() -> Any:
    try:
        import pyphen
    except ImportError:  # pragma: no cover - pyphen is a dependency; the fallback keeps working without it
        return None
    return pyphen.Pyphen(lang="en_US", left=1, right=1)


def count_syllables(word: str) -> int:
    """Syllables of one word (>= 1); see the module docstring."""
    letters = re.sub(r"[^a-z]", "", word.lower())
    if not letters:
        return 1
    groups = len(_VOWEL_GROUP.findall(letters))
    if letters.endswith("e") and not letters.endswith(("le", "ee", "ye")) and groups > 1:
        groups -= 1
    dic = _pyphen()
    hyph = len(dic.positions(letters)) + 1 if dic is not None else 0
    return max(1, groups, hyph)


def voiced_span(samples: np.ndarray, rate: int, *, threshold_db: float = 35.0,
                frame: float = 0.02) -> tuple[float, float]:
    """``(start, end)`` seconds of the voiced part of ``samples`` ((N,) or (N, C)); ``(0, duration)`` when
    the audio is silent throughout."""
    x = np.asarray(samples, dtype=np.float64)
    if x.ndim == 2:
        x = x.mean(axis=1)
    hop = max(1, int(round(frame * rate)))
    n = len(x) // hop
    duration = len(x) / float(rate)
    if n == 0:
        return 0.0, duration
    rms = np.sqrt(np.mean(x[: n * hop].reshape(n, hop) ** 2, axis=1))
    peak = float(rms.max())
    if peak <= 0:
        return 0.0, duration
    voiced = np.flatnonzero(rms >= peak * 10 ** (-threshold_db / 20))
    return float(voiced[0] * hop / rate), float(min(duration, (voiced[-1] + 1) * hop / rate))


def estimate_timings(words: list[str], start: float, end: float, source: str | None = None) -> Transcript:
    """Words spread over ``[start, end]``, durations proportional to syllable counts, all estimated."""
    if end < start:
        raise InputError(f"the span ends ({end:g} s) before it starts ({start:g} s)", path=source)
    syl = np.array([count_syllables(w) for w in words], dtype=np.float64)
    if not len(words):
        return Transcript((), source=source)
    edges = start + (end - start) * np.concatenate([[0.0], np.cumsum(syl)]) / syl.sum()
    edges[-1] = end
    items = [Item(w, float(edges[i]), float(edges[i + 1]), estimated=True) for i, w in enumerate(words)]
    return to_transcript(items, source)


def read_plain_text(path: str | os.PathLike[str], *, audio: str | os.PathLike[str] | None = None,
                    span: tuple[float, float] | None = None) -> Transcript:
    """Words of a plain-text file timed over the voiced span of ``audio`` (or the given ``span``)."""
    words = read_text(path, what="plain-text transcript").split()
    if span is None:
        if audio is None:
            raise InputError("a plain-text transcript has no times; give the audio (audio=...) to estimate them "
                             "from, or the voiced span (span=(start, end))", path=path)
        from evalsuite.audio import read_wav

        samples, rate = read_wav(audio)
        span = voiced_span(samples, rate)
    return estimate_timings(words, span[0], span[1], os.fspath(path))


def write_plain_text(transcript: Transcript, path: str | os.PathLike[str]) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(transcript.text + "\n")
