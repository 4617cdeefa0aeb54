"""The corpus data model: segments of (speech audio, transcript with word timings, motion).

Everything that reads, writes, synthesises or feeds a generator speaks these types:

* :class:`Word` -- one word with start and end in seconds from the segment's start;
* :class:`Transcript` -- the words of one speaker in one segment, in time order;
* :class:`Stream` -- one speaker's audio, transcript and motion (the main agent, or the interlocutor of
  a dyadic corpus such as GENEA 2023);
* :class:`Segment` -- one recording: the main agent's stream plus id, speaker, split, optional
  interlocutor and per-frame labels;
* :class:`Corpus` -- the segments of a folder, with the layout they were read from and train/val/test
  splits.

Files are referenced by path and loaded on demand (:meth:`Segment.load_audio`, :meth:`Segment.load_motion`),
so listing a corpus of hours of data is cheap. Times are seconds; durations of audio come from the WAV
header.
"""
from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evalsuite.errors import InputError

__all__ = ["Word", "Transcript", "Stream", "Segment", "Corpus", "SPLITS", "canonical_split"]

# Canonical split names, and the spellings corpora use for them (GENEA 2022/23: trn/val/tst).
SPLITS = ("train", "val", "test")
_SPLIT_ALIASES = {"train": "train", "trn": "train", "training": "train",
                  "val": "val", "valid": "val", "validation": "val", "dev": "val",
                  "test": "test", "tst": "test", "testing": "test"}


def canonical_split(name: str | None) -> str | None:
    """``'trn'`` -> ``'train'``, ``'tst'`` -> ``'test'``; ``None`` and unknown names pass through."""
    if name is None:
        return None
    return _SPLIT_ALIASES.get(name.lower(), name)


@dataclass(frozen=True)
class Word:
    """A word with its time span in seconds. ``estimated`` marks timings not measured from the audio
    (e.g. spread over the voiced span by syllable counts, as Gesticulator does for plain text)."""

    text: str
    start: float
    end: float
    estimated: bool = False

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass(frozen=True)
class Transcript:
    """The words of one speaker in one segment, sorted by start time, not overlapping."""

    words: tuple[Word, ...]
    source: str | None = None  # the file it was read from, for messages

    def __post_init__(self) -> None:
        prev_end = 0.0
        for i, w in enumerate(self.words):
            where = f"word {i + 1} ({w.text!r})"
            if not (np.isfinite(w.start) and np.isfinite(w.end)):
                raise InputError(f"{where}: times must be finite numbers, got {w.start!r}..{w.end!r}",
                                 path=self.source)
            if w.start < 0 or w.end < w.start:
                raise InputError(f"{where}: expected 0 <= start <= end, got {w.start:g}..{w.end:g} s",
                                 path=self.source)
            if w.start < prev_end - 1e-6:
                raise InputError(f"{where}: starts at {w.start:g} s, before the previous word ends "
                                 f"({prev_end:g} s); words must be in time order and not overlap",
                                 path=self.source)
            prev_end = w.end

    @property
    def text(self) -> str:
        return " ".join(w.text for w in self.words)

    @property
    def estimated(self) -> bool:
        """True when any word's timing is estimated rather than measured."""
        return any(w.estimated for w in self.words)

    @property
    def end(self) -> float:
        return self.words[-1].end if self.words else 0.0

    def __len__(self) -> int:
        return len(self.words)

    def word_at_frames(self, fps: float, n_frames: int) -> np.ndarray:
        """``(n_frames,)`` int: index of the word spoken at each frame's time ``t / fps``, -1 in silence."""
        t = np.arange(n_frames) / float(fps)
        out = np.full(n_frames, -1, dtype=np.int64)
        for i, w in enumerate(self.words):
            out[(t >= w.start) & (t < w.end)] = i
        return out

    def shifted(self, offset: float) -> Transcript:
        """The same words ``offset`` seconds later (for cutting and concatenating segments)."""
        return Transcript(tuple(dataclasses.replace(w, start=w.start + offset, end=w.end + offset)
                                for w in self.words), self.source)


@dataclass(frozen=True)
class Stream:
    """One speaker's recording: any of audio (WAV), transcript and motion (BVH or positions) may be
    missing (ZEGGS has no transcripts; a generator's input has no motion)."""

    audio: pathlib.Path | None = None
    transcript: Transcript | None = None
    motion: pathlib.Path | None = None


@dataclass(frozen=True)
class Segment:
    """One recording of a corpus.

    ``duration`` is the audio's duration in seconds when there is audio (else the motion's, else the
    transcript's end). ``labels`` is a per-frame CSV (``frame, phase, kind, keyword``) where the corpus
    has them (the synthetic speaker). ``meta`` holds layout-specific extras (e.g. GENEA 2023's
    ``finger_incl``) and whatever a reader wants to keep.
    """

    id: str
    main: Stream
    duration: float | None = None
    speaker: str | None = None
    split: str | None = None
    interlocutor: Stream | None = None
    labels: pathlib.Path | None = None
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    # Shortcuts to the main agent's stream: what nearly every caller wants.
    @property
    def audio(self) -> pathlib.Path | None:
        return self.main.audio

    @property
    def transcript(self) -> Transcript | None:
        return self.main.transcript

    @property
    def motion(self) -> pathlib.Path | None:
        return self.main.motion

    def load_audio(self) -> tuple[np.ndarray, int]:
        """``(samples (N, C) float64 in [-1, 1), sample_rate)`` of the main agent's audio."""
        from evalsuite.audio import read_wav

        if self.main.audio is None:
            raise InputError(f"segment {self.id!r} has no audio")
        return read_wav(self.main.audio)

    def load_motion(self, **kwargs: Any) -> Any:
        """The main agent's :class:`evalsuite.motion.Motion` (keyword arguments go to ``load_motion``)."""
        from evalsuite.motion.io import load_motion

        if self.main.motion is None:
            raise InputError(f"segment {self.id!r} has no motion")
        return load_motion(self.main.motion, **kwargs)


@dataclass(frozen=True)
class Corpus:
    """The segments of one corpus folder, in a stable order (sorted by id)."""

    root: pathlib.Path
    layout: str
    segments: tuple[Segment, ...]
    meta: dict[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        seen: set[str] = set()
        for s in self.segments:
            if s.id in seen:
                raise InputError(f"two segments have the id {s.id!r}; segment ids must be unique",
                                 path=self.root)
            seen.add(s.id)

    def __iter__(self) -> Iterator[Segment]:
        return iter(self.segments)

    def __len__(self) -> int:
        return len(self.segments)

    def get(self, segment_id: str) -> Segment:
        for s in self.segments:
            if s.id == segment_id:
                return s
        raise InputError(f"no segment {segment_id!r} in the corpus", path=self.root)

    def split(self, name: str | Sequence[str]) -> tuple[Segment, ...]:
        """Segments of one split (or several): ``'train'``/``'trn'``, ``'val'``, ``'test'``/``'tst'``.
        ``'all'`` gives every segment."""
        names = [name] if isinstance(name, str) else list(name)
        if "all" in names:
            return self.segments
        wanted = {canonical_split(n) for n in names}
        known = {s.split for s in self.segments}
        missing = sorted(str(n) for n in wanted if n not in known)
        if missing:
            have = ", ".join(sorted(str(k) for k in known)) or "none"
            raise InputError(f"no segments in split {', '.join(missing)} (splits here: {have})", path=self.root)
        return tuple(s for s in self.segments if s.split in wanted)

    @property
    def speakers(self) -> tuple[str, ...]:
        return tuple(sorted({s.speaker for s in self.segments if s.speaker is not None}))

    def with_segments(self, segments: Sequence[Segment]) -> Corpus:
        return dataclasses.replace(self, segments=tuple(segments))
