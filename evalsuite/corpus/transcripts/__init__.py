"""Transcript formats in and out: Google speech-to-text JSON, GENEA TSV, Praat TextGrid, plain text.

``read_transcript(path, format=None)`` and ``write_transcript(transcript, path, format=None)`` pick the
format from the suffix (``.json``, ``.tsv``, ``.TextGrid``, ``.txt``) or by name (``"google_json"``,
``"tsv"``, ``"textgrid"``, ``"text"``). Every reader raises :class:`~evalsuite.errors.InputError` naming the
file, the line (TSV, TextGrid, JSON syntax) or field (JSON), and what was expected.

Each format is a :class:`TranscriptFormat` in the :class:`~evalsuite.registry.Registry` :data:`FORMATS`;
:func:`register_transcript_format` adds one, and an installed package adds one with an entry point in the
group ``evalsuite.transcript_formats`` (``name = "package.module:FORMAT"``, a ``TranscriptFormat``).
"""
from __future__ import annotations

import os
import pathlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from evalsuite.corpus.transcripts.google_json import read_google_json, write_google_json
from evalsuite.corpus.transcripts.plaintext import (
    count_syllables,
    estimate_timings,
    read_plain_text,
    voiced_span,
    write_plain_text,
)
from evalsuite.corpus.transcripts.textgrid import read_textgrid, textgrid_tiers, write_textgrid
from evalsuite.corpus.transcripts.tsv import read_tsv, write_tsv
from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError
from evalsuite.registry import Registry

__all__ = ["FORMATS", "TRANSCRIPT_SUFFIXES", "TranscriptFormat", "register_transcript_format", "transcript_format",
           "transcript_suffixes", "read_transcript", "write_transcript", "count_syllables", "estimate_timings",
           "voiced_span", "textgrid_tiers"]


@dataclass(frozen=True)
class TranscriptFormat:
    """A transcript format: its ``name``, file ``suffixes`` (lower case, the first is written by default),
    other names it answers to (``aliases``), ``read(path, **options) -> Transcript`` and
    ``write(transcript, path, **options)`` (None: read only).

    ``read`` is called with the keyword options ``allow_empty``, ``tier``, ``audio`` and ``span`` (see
    :func:`read_transcript`) and ignores those it has no use for (``**options``)."""

    name: str
    suffixes: tuple[str, ...]
    read: Callable[..., Transcript]
    write: Callable[..., None] | None = None
    aliases: tuple[str, ...] = ()
    description: str = ""


FORMATS: Registry[TranscriptFormat] = Registry("transcript format", "evalsuite.transcript_formats",
                                               base=TranscriptFormat, name_of=lambda f: f.name, field="format")


def register_transcript_format(fmt: TranscriptFormat, *, replace: bool = False) -> TranscriptFormat:
    """Add a format; its name must be new (``replace=True`` swaps an existing one)."""
    return FORMATS.register(fmt.name, fmt, replace=replace)


def _read_text(path: str | os.PathLike[str], *, audio: str | os.PathLike[str] | None = None,
               span: tuple[float, float] | None = None, **_: Any) -> Transcript:
    if audio is None and span is None:
        sibling = pathlib.Path(path).with_suffix(".wav")
        audio = sibling if sibling.is_file() else None
    return read_plain_text(path, audio=audio, span=span)


for _fmt in (
    TranscriptFormat("google_json", (".json",),
                     lambda path, allow_empty=False, **_: read_google_json(path, allow_empty=allow_empty),
                     lambda transcript, path, **_: write_google_json(transcript, path),
                     ("json", "google"), "Google speech-to-text JSON"),
    TranscriptFormat("tsv", (".tsv",), lambda path, allow_empty=False, **_: read_tsv(path, allow_empty=allow_empty),
                     lambda transcript, path, **_: write_tsv(transcript, path),
                     ("genea_tsv",), "GENEA TSV: start, end, word per line"),
    TranscriptFormat("textgrid", (".textgrid",), lambda path, tier=None, **_: read_textgrid(path, tier=tier),
                     write_textgrid, ("praat",), "Praat TextGrid (a word tier)"),
    TranscriptFormat("text", (".txt",), _read_text, lambda transcript, path, **_: write_plain_text(transcript, path),
                     ("plain", "txt"), "plain text; timings spread over the voiced span of the audio"),
):
    register_transcript_format(_fmt)

# the built-in formats' suffixes (transcript_suffixes() adds the installed plug-ins')
TRANSCRIPT_SUFFIXES = tuple(s for f in FORMATS.current().values() for s in f.suffixes)


def transcript_suffixes() -> tuple[str, ...]:
    """The suffixes of every format, installed plug-ins included."""
    return tuple(s for f in FORMATS.values() for s in f.suffixes)


def _format(path: str | os.PathLike[str], format: str | None) -> TranscriptFormat:
    if format is not None:
        key = format.lower()
        if key not in FORMATS:
            key = next((f.name for f in FORMATS.values() if key in f.aliases), format)
        return FORMATS.get(key)
    suffix = pathlib.Path(path).suffix.lower()
    for fmt in FORMATS.values():
        if suffix in fmt.suffixes:
            return fmt
    raise InputError(f"cannot tell the transcript format from the suffix {pathlib.Path(path).suffix!r}; expected "
                     f"one of {', '.join(transcript_suffixes())} or a format name ({', '.join(FORMATS)})", path=path)


def transcript_format(path: str | os.PathLike[str], format: str | None = None) -> str:
    """The format's name: ``format`` if given (aliases: json, praat, txt, ...), else from the suffix."""
    return _format(path, format).name


def read_transcript(path: str | os.PathLike[str], format: str | None = None, *, tier: str | None = None,
                    audio: str | os.PathLike[str] | None = None, span: tuple[float, float] | None = None,
                    allow_empty: bool = False) -> Transcript:
    """Read a transcript.

    Args:
        format: a format name; by default from the suffix.
        tier: TextGrid only: the word tier's name (default ``words``/``word``, else the first interval tier).
        audio, span: plain text only: the WAV whose voiced span the words are spread over (default: a WAV
            of the same stem beside the file), or the span itself in seconds.
        allow_empty: an empty file gives an empty transcript instead of an error (GENEA 2023 has two).
    """
    return _format(path, format).read(path, tier=tier, audio=audio, span=span, allow_empty=allow_empty)


def write_transcript(transcript: Transcript, path: str | os.PathLike[str], format: str | None = None,
                     **options: Any) -> None:
    """Write a transcript (TextGrid options: ``tier`` name, ``xmax``)."""
    fmt = _format(path, format)
    if fmt.write is None:
        raise InputError(f"the transcript format {fmt.name!r} can be read but not written", field="format")
    fmt.write(transcript, path, **options)
