"""The layout registry and the one place segments are assembled and checked.

A layout is one function ``read(root, builder)`` registered with :func:`register_layout` (its name, a
``detect(root) -> bool`` and a one-line description). The function finds the files and calls
``builder.add(...)`` per segment; :class:`CorpusBuilder` reads headers (never samples or frames), checks
that audio and motion durations agree, records what is missing, and applies the mismatch policy.
"""
from __future__ import annotations

import contextlib
import os
import pathlib
import warnings
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

from evalsuite.corpus.readers.headers import motion_info, wav_info
from evalsuite.corpus.transcripts import read_transcript
from evalsuite.corpus.types import Corpus, Segment, Stream, Transcript, canonical_split
from evalsuite.errors import InputError
from evalsuite.registry import Registry

__all__ = ["Layout", "LAYOUTS", "ReadOptions", "CorpusBuilder", "register_layout", "MISMATCH_POLICIES",
           "mismatch_policy", "current_mismatch_policy"]

MISMATCH_POLICIES = ("error", "warn", "skip")
_POLICY: ContextVar[tuple[str, str] | None] = ContextVar("evalsuite_corpus_on_mismatch", default=None)


@contextlib.contextmanager
def mismatch_policy(on_mismatch: str, option: str = "--on-mismatch") -> Iterator[None]:
    """Within the block, ``load_corpus`` calls that name no ``on_mismatch`` (however deep: a generator, a
    metric family) apply ``on_mismatch``, and the duration-mismatch error names ``option``, the command-line
    option of the running command that sets it."""
    if on_mismatch not in MISMATCH_POLICIES:
        raise InputError(f"on_mismatch must be one of {', '.join(MISMATCH_POLICIES)}, got {on_mismatch!r}",
                         field=option)
    token = _POLICY.set((on_mismatch, option))
    try:
        yield
    finally:
        _POLICY.reset(token)


def current_mismatch_policy() -> tuple[str, str | None]:
    """``(on_mismatch, option)`` set by the innermost :func:`mismatch_policy`, else ``("error", None)``."""
    return _POLICY.get() or ("error", None)


@dataclass(frozen=True)
class ReadOptions:
    """``on_mismatch``: what to do with a segment whose audio and motion durations differ by more than
    ``max(tolerance, tolerance_rel * longer duration)``: ``'error'`` (default), ``'warn'`` (keep it, with a
    warning and a record) or ``'skip'`` (leave it out, with a record). ``motion_fps`` is the rate of motion
    files that store none (``.npy``, ``.csv``). ``option``: the command-line option that sets ``on_mismatch``
    in the command being run (named by the mismatch error), None outside a command."""

    on_mismatch: str = "error"
    tolerance: float = 0.5
    tolerance_rel: float = 0.02
    motion_fps: float | None = None
    option: str | None = None

    def __post_init__(self) -> None:
        if self.on_mismatch not in MISMATCH_POLICIES:
            raise InputError(f"on_mismatch must be one of {', '.join(MISMATCH_POLICIES)}, got {self.on_mismatch!r}",
                             field="on_mismatch")
        if not (self.tolerance >= 0 and self.tolerance_rel >= 0):
            raise InputError("tolerances must be >= 0", field="tolerance")

    def limit(self, a: float, b: float) -> float:
        return max(self.tolerance, self.tolerance_rel * max(a, b))


@dataclass(frozen=True)
class Layout:
    name: str
    detect: Callable[[pathlib.Path], bool]
    read: Callable[[pathlib.Path, CorpusBuilder], None]
    description: str


# installed packages add layouts with entry points in the group evalsuite.corpus_layouts (docs/architecture.md)
LAYOUTS: Registry[Layout] = Registry("layout", "evalsuite.corpus_layouts", base=Layout, name_of=lambda lay: lay.name,
                                     field="layout")


def register_layout(name: str, *, detect: Callable[[pathlib.Path], bool], description: str
                    ) -> Callable[[Callable[[pathlib.Path, CorpusBuilder], None]],
                                  Callable[[pathlib.Path, CorpusBuilder], None]]:
    """Decorator: register ``read(root, builder)`` as the reader of layout ``name``."""
    def wrap(read: Callable[[pathlib.Path, CorpusBuilder], None]) -> Callable[[pathlib.Path, CorpusBuilder], None]:
        LAYOUTS.register(name, Layout(name, detect, read, description), replace=True)
        return read
    return wrap


def _rel(path: pathlib.Path | None, root: pathlib.Path) -> str | None:
    if path is None:
        return None
    try:
        return os.fspath(path.relative_to(root))
    except ValueError:
        return os.fspath(path)


class CorpusBuilder:
    """Collects segments of one corpus; see the module docstring."""

    def __init__(self, root: pathlib.Path, layout: str, options: ReadOptions):
        self.root, self.layout, self.options = root, layout, options
        self.segments: list[Segment] = []
        self.meta: dict[str, Any] = {"mismatches": [], "skipped": [], "missing": {}}

    def transcript(self, path: pathlib.Path | None, *, allow_empty: bool = False,
                   audio: pathlib.Path | None = None) -> Transcript | None:
        if path is None:
            return None
        return read_transcript(path, allow_empty=allow_empty, audio=audio)

    def stream(self, audio: pathlib.Path | None, transcript: pathlib.Path | None, motion: pathlib.Path | None,
               *, allow_empty: bool = False) -> Stream:
        """A stream (e.g. the interlocutor's) with its transcript read; missing files become None."""
        audio = audio if audio is not None and audio.is_file() else None
        motion = motion if motion is not None and motion.is_file() else None
        transcript = transcript if transcript is not None and transcript.is_file() else None
        return Stream(audio, self.transcript(transcript, allow_empty=allow_empty, audio=audio), motion)

    def add(self, seg_id: str, *, audio: pathlib.Path | None, motion: pathlib.Path | None,
            transcript: pathlib.Path | None = None, speaker: str | None = None, split: str | None = None,
            interlocutor: Stream | None = None, labels: pathlib.Path | None = None,
            require_audio: bool = True, allow_empty_transcript: bool = False,
            meta: dict[str, Any] | None = None) -> None:
        """Add one segment. ``audio``/``motion``/``transcript`` are the paths the layout expects (they may not
        exist): a missing audio file where ``require_audio`` is an error naming the expected path; other
        missing parts are recorded in ``segment.meta['missing']``."""
        meta = dict(meta or {})
        if audio is None or not audio.is_file():
            if require_audio:
                what = f"motion {_rel(motion, self.root)}" if motion is not None else f"segment {seg_id!r}"
                expected = f"expected its audio at {_rel(audio, self.root)}" if audio is not None else \
                    "expected a WAV file of the same name"
                raise InputError(f"{what} has no audio file; {expected}", path=audio or motion or self.root)
            audio = None
        motion = motion if motion is not None and motion.is_file() else None
        transcript = transcript if transcript is not None and transcript.is_file() else None
        labels = labels if labels is not None and labels.is_file() else None
        missing = [name for name, p in (("audio", audio), ("transcript", transcript), ("motion", motion)) if p is None]
        if interlocutor is not None:
            missing += [f"interlocutor {n}" for n in ("audio", "transcript", "motion")
                        if getattr(interlocutor, n) is None]
        a_info = wav_info(audio) if audio is not None else None
        m_info = motion_info(motion, self.options.motion_fps) if motion is not None else None
        if a_info is not None:
            meta.update(audio_rate=a_info.rate, audio_channels=a_info.channels, audio_duration=a_info.duration)
        if m_info is not None:
            meta.update(motion_fps=m_info.fps, motion_frames=m_info.frames, motion_duration=m_info.duration)
        pairs = [(seg_id, audio, motion, a_info, m_info)]
        if interlocutor is not None and interlocutor.audio is not None and interlocutor.motion is not None:
            pairs.append((f"{seg_id} (interlocutor)", interlocutor.audio, interlocutor.motion,
                          wav_info(interlocutor.audio), motion_info(interlocutor.motion, self.options.motion_fps)))
        for name, a_path, m_path, a, m in pairs:
            if a is None or m is None or m.duration is None:
                continue
            record = self._durations_agree(name, a_path, m_path, a.duration, m.duration)
            if record is not None and record["action"] == "skip":
                self.meta["skipped"].append(seg_id)
                return
            if record is not None:
                meta.setdefault("mismatch", record)
        if missing:
            meta["missing"] = missing
            for name in missing:
                self.meta["missing"][name] = self.meta["missing"].get(name, 0) + 1
        words = self.transcript(transcript, allow_empty=allow_empty_transcript, audio=audio)
        duration = a_info.duration if a_info is not None else (
            m_info.duration if m_info is not None and m_info.duration is not None else
            (words.end if words is not None else None))
        self.segments.append(Segment(seg_id, Stream(audio, words, motion), duration=duration, speaker=speaker,
                                     split=canonical_split(split), interlocutor=interlocutor, labels=labels,
                                     meta=meta))

    def _durations_agree(self, seg_id: str, audio: pathlib.Path | None, motion: pathlib.Path | None,
                         a: float, m: float) -> dict[str, Any] | None:
        """None when the durations agree; else the mismatch record (or InputError under 'error')."""
        limit = self.options.limit(a, m)
        if abs(a - m) <= limit:
            return None
        opt = self.options
        record = {"segment": seg_id, "audio": _rel(audio, self.root), "motion": _rel(motion, self.root),
                  "audio_duration": a, "motion_duration": m, "tolerance": limit, "action": opt.on_mismatch}
        message = (f"segment {seg_id!r}: audio {_rel(audio, self.root)} lasts {a:.3f} s but motion "
                   f"{_rel(motion, self.root)} lasts {m:.3f} s; expected them to agree within {limit:.3f} s "
                   f"(max({opt.tolerance:g} s, {100 * opt.tolerance_rel:g} %))")
        if opt.on_mismatch == "error":
            hint = (f"rerun with {opt.option} warn (keep such segments, listed) or {opt.option} skip (leave them "
                    "out)" if opt.option else "load with on_mismatch='warn' or 'skip' (`evalsuite corpus info "
                    "DIR` lists every mismatch)")
            raise InputError(f"{message}; fix the files or {hint}", path=audio)
        self.meta["mismatches"].append(record)
        if opt.on_mismatch == "warn":
            warnings.warn(message, stacklevel=3)
        return record

    def build(self, meta: dict[str, Any] | None = None) -> Corpus:
        full = dict(self.meta)
        full.update(meta or {})
        full["options"] = {"on_mismatch": self.options.on_mismatch, "tolerance": self.options.tolerance,
                           "tolerance_rel": self.options.tolerance_rel}
        return Corpus(self.root, self.layout, tuple(sorted(self.segments, key=lambda s: s.id)), meta=full)
