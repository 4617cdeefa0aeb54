"""Text features per frame from a :class:`~evalsuite.corpus.types.Transcript`: word identity and Gesticulator's
five timing features. Frame ``t`` is the time ``t / fps``; a word covers ``[start, end)``.

**Word identity** (:func:`word_ids`): the index of the frame's word in a :class:`Vocabulary` built from a
corpus' transcripts; ``0`` in silence, ``1`` for a word not in the vocabulary, words from ``2`` (most frequent
first, ties alphabetical). Words are normalised by :func:`normalize_word` (lower case, surrounding punctuation
removed). ``Transcript.word_at_frames`` gives the position of the word in the transcript instead (-1 in
silence).

**Timing features** (:func:`timing_features`), ``(T, 5)`` = elapsed time in the word, remaining time,
word duration, progress, syllables per unit time; all five are 0 in silence (Gesticulator's
``silence_extra_features``). Two conventions:

* ``"gesticulator"`` (default) -- as Gesticulator's ``parse_json_transcript`` computes them (Kucherenko et al.,
  ICMI 2020, Table 1): word times truncated to whole deciseconds (``int(t * 10)``: 0.57 s -> 5, not
  rounded), features computed on a 10-fps grid **in deciseconds**: in decisecond frame ``k``
  of a word ``[s, e)`` (``s <= k < e``), elapsed ``= k + 1 - s`` (counted from 1), remaining ``= e - k``
  (``elapsed + remaining = duration + 1``), duration ``= e - s``, progress ``= elapsed / duration`` (so 1.0 in
  the word's last frame), speed = syllables per **decisecond** (the paper's table says per second; the code
  divides by deciseconds). Then each 10-fps frame is repeated to the requested rate (frame ``t`` takes
  decisecond frame ``floor(t * 10 / fps)``): at 20 fps, Gesticulator's 2x upsampling exactly.
* ``"seconds"`` -- the same quantities in continuous time at the requested rate: elapsed ``= tau - start``,
  remaining ``= end - tau``, duration ``= end - start`` in seconds, progress ``= elapsed / duration`` in
  [0, 1), speed in syllables per second.

Syllables are counted by :func:`count_syllables`, evalsuite's own heuristic (vowel groups, a silent final
``e``, ``-le``, ``-ed``/``-es`` endings); it agrees with Gesticulator's counter on ordinary words but is not a
copy of it, so rare words can differ by one.
"""
from __future__ import annotations

import json
import os
import pathlib
import re
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError
from evalsuite.features.base import Recipe, register_recipe

__all__ = ["normalize_word", "count_syllables", "Vocabulary", "word_ids", "timing_features", "SILENCE", "UNKNOWN",
           "n_frames_for", "frames_needed"]

SILENCE, UNKNOWN = 0, 1
_VOWELS = "aeiouy"


def normalize_word(text: str) -> str:
    """Lower case with surrounding punctuation removed (``"High."`` -> ``"high"``; ``"don't"`` kept)."""
    return text.lower().strip("\"'.,!?;:()[]{}-`").strip()


def count_syllables(word: str) -> int:
    """Syllables of an English word by rule (at least 1 for any word with a letter)."""
    w = re.sub(r"[^a-z]", "", normalize_word(word))
    if not w:
        return 0
    if len(w) <= 3:
        return 1
    n = len(re.findall(r"[aeiouy]+", w))
    if n > 1 and w.endswith("e") and not w.endswith(("le", "ee", "ie", "ye")):
        n -= 1                                            # silent final e: "make", "five" (not "table")
    elif n > 1 and w.endswith(("ed", "es")) and not w.endswith(("ted", "ded", "ses", "zes", "ces", "ges", "xes",
                                                                  "shes", "ches", "ies")):
        n -= 1                                            # "jumped", "makes" (not "wanted", "boxes")
    return max(n, 1)


@dataclass(frozen=True)
class Vocabulary:
    """Word -> id: 0 silence, 1 unknown, the words from 2."""

    words: tuple[str, ...]

    @classmethod
    def build(cls, transcripts: Iterable[Transcript], *, min_count: int = 1, max_size: int | None = None) -> Vocabulary:
        """From a corpus' transcripts: normalised words seen at least ``min_count`` times, most frequent first
        (ties alphabetical), at most ``max_size``."""
        counts: Counter[str] = Counter()
        for t in transcripts:
            counts.update(w for w in (normalize_word(x.text) for x in t.words) if w)
        ranked = sorted((w for w, c in counts.items() if c >= min_count), key=lambda w: (-counts[w], w))
        return cls(tuple(ranked[:max_size] if max_size is not None else ranked))

    def __len__(self) -> int:
        return len(self.words) + 2

    def index(self, word: str) -> int:
        return self._lookup.get(normalize_word(word), UNKNOWN)

    @property
    def _lookup(self) -> dict[str, int]:
        cached = self.__dict__.get("_cache")
        if cached is None:
            cached = {w: i + 2 for i, w in enumerate(self.words)}
            object.__setattr__(self, "_cache", cached)
        return cached

    def save(self, path: str | os.PathLike[str]) -> None:
        pathlib.Path(path).write_text(json.dumps({"silence": SILENCE, "unknown": UNKNOWN, "words": list(self.words)},
                                                 indent=0), encoding="utf-8")

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Vocabulary:
        try:
            data = json.loads(pathlib.Path(path).read_text(encoding="utf-8"))
            words = data["words"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise InputError(f"not a vocabulary file ({exc})", path=path) from None
        if not isinstance(words, list) or not all(isinstance(w, str) for w in words):
            raise InputError("expected a list of words", path=path, field="words")
        return cls(tuple(words))


def n_frames_for(transcript: Transcript, fps: float) -> int:
    """Frames that cover the transcript: ``ceil(end * fps)``."""
    return int(np.ceil(transcript.end * fps - 1e-9))


def word_ids(transcript: Transcript, vocabulary: Vocabulary, fps: float, n_frames: int | None = None) -> np.ndarray:
    """``(T,)`` int64 vocabulary ids per frame (0 silence, 1 unknown)."""
    n = n_frames_for(transcript, fps) if n_frames is None else int(n_frames)
    at = transcript.word_at_frames(fps, n)
    table = np.array([SILENCE] + [vocabulary.index(w.text) for w in transcript.words], dtype=np.int64)
    return table[at + 1]


def timing_features(transcript: Transcript, fps: float, n_frames: int | None = None, *,
                    convention: str = "gesticulator") -> np.ndarray:
    """``(T, 5)`` float64 (elapsed, remaining, duration, progress, syllable rate); see the module docstring."""
    if fps <= 0:
        raise InputError(f"the frame rate must be positive, got {fps!r}", field="fps")
    n = n_frames_for(transcript, fps) if n_frames is None else int(n_frames)
    out = np.zeros((n, 5))
    if convention == "seconds":
        tau = np.arange(n) / float(fps)
        at = transcript.word_at_frames(fps, n)
        for i, w in enumerate(transcript.words):
            sel = at == i
            if not sel.any():
                continue
            dur = w.end - w.start
            out[sel, 0] = tau[sel] - w.start
            out[sel, 1] = w.end - tau[sel]
            out[sel, 2] = dur
            out[sel, 3] = (tau[sel] - w.start) / dur
            out[sel, 4] = count_syllables(w.text) / dur
        return out
    if convention != "gesticulator":
        raise InputError(f"unknown timing convention {convention!r}; expected 'gesticulator' or 'seconds'",
                         field="convention")
    k_of_t = np.floor(np.arange(n) * 10.0 / fps + 1e-9).astype(np.int64)
    deci = np.zeros((int(k_of_t.max()) + 1 if n else 0, 5))
    for w in transcript.words:
        s, e = int(float(w.start) * 10), int(float(w.end) * 10)
        d = e - s
        if d <= 0:
            continue
        k = np.arange(s, min(e, len(deci)))
        if len(k) == 0:
            continue
        elapsed = k + 1 - s
        deci[k] = np.stack([elapsed, e - k, np.full(len(k), d), elapsed / d,
                            np.full(len(k), count_syllables(w.text) / d)], axis=1)
    if n:
        out[:] = deci[k_of_t]
    return out


def frames_needed(audio, transcript: Transcript, fps: float, n: int | None) -> int:
    """Frames to compute: ``n_frames`` when given, else the audio's duration, else the transcript's end."""
    if n is not None:
        return int(n)
    if audio is not None:
        return int(np.ceil(audio.duration * fps - 1e-9))
    return n_frames_for(transcript, fps)


def _timing(audio, transcript: Transcript, fps: float, n: int | None, opts: dict) -> np.ndarray:
    return timing_features(transcript, fps, frames_needed(audio, transcript, fps, n), convention=opts["convention"])


register_recipe(Recipe(
    name="text_timing", native_fps=None, dim=5, needs_audio=False, needs_transcript=True, default_fps=20.0,
    reproduces="Gesticulator's five word-timing features (Kucherenko et al., ICMI 2020, Table 1; parse_json_transcript)",
    quirks="convention 'gesticulator': deciseconds, 10-fps grid repeated to the rate asked, times truncated with "
           "int(t * 10), elapsed counted from 1, speed in syllables per decisecond; 'seconds': continuous time",
    compute=_timing,
    params={"convention": "gesticulator"}))
