"""Transcript formats in and out: Google speech-to-text JSON, GENEA TSV, Praat TextGrid, plain text.

``read_transcript(path, format=None)`` and ``write_transcript(transcript, path, format=None)`` pick the
format from the suffix (``.json``, ``.tsv``, ``.TextGrid``, ``.txt``) or by name (``"google_json"``,
``"tsv"``, ``"textgrid"``, ``"text"``). Every reader raises :class:`~evalsuite.errors.InputError` naming the
file, the line (TSV, TextGrid, JSON syntax) or field (JSON), and what was expected.
"""
from __future__ import annotations

import os
import pathlib
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

__all__ = ["FORMATS", "TRANSCRIPT_SUFFIXES", "transcript_format", "read_transcript", "write_transcript",
           "count_syllables", "estimate_timings", "voiced_span", "textgrid_tiers"]

# name -> suffixes (lower case); the first suffix is the one written by default.
FORMATS: dict[str, tuple[str, ...]] = {
    "google_json": (".json",),
    "tsv": (".tsv",),
    "textgrid": (".textgrid",),
    "text": (".txt",),
}
_ALIASES = {"json": "google_json", "google": "google_json", "genea_tsv": "tsv", "praat": "textgrid",
            "plain": "text", "txt": "text"}
TRANSCRIPT_SUFFIXES = tuple(s for sufs in FORMATS.values() for s in sufs)


def transcript_format(path: str | os.PathLike[str], format: str | None = None) -> str:
    """The format's name: ``format`` if given (aliases: json, praat, txt, ...), else from the suffix."""
    if format is not None:
        name = _ALIASES.get(format.lower(), format.lower())
        if name not in FORMATS:
            raise InputError(f"unknown transcript format {format!r}; expected one of {', '.join(FORMATS)}",
                             field="format")
        return name
    suffix = pathlib.Path(path).suffix.lower()
    for name, sufs in FORMATS.items():
        if suffix in sufs:
            return name
    raise InputError(f"cannot tell the transcript format from the suffix {pathlib.Path(path).suffix!r}; expected "
                     f"one of {', '.join(TRANSCRIPT_SUFFIXES)} or a format name ({', '.join(FORMATS)})", path=path)


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
    name = transcript_format(path, format)
    if name == "google_json":
        return read_google_json(path, allow_empty=allow_empty)
    if name == "tsv":
        return read_tsv(path, allow_empty=allow_empty)
    if name == "textgrid":
        return read_textgrid(path, tier=tier)
    if audio is None and span is None:
        sibling = pathlib.Path(path).with_suffix(".wav")
        audio = sibling if sibling.is_file() else None
    return read_plain_text(path, audio=audio, span=span)


def write_transcript(transcript: Transcript, path: str | os.PathLike[str], format: str | None = None,
                     **options: Any) -> None:
    """Write a transcript (TextGrid options: ``tier`` name, ``xmax``)."""
    name = transcript_format(path, format)
    if name == "google_json":
        write_google_json(transcript, path)
    elif name == "tsv":
        write_tsv(transcript, path)
    elif name == "textgrid":
        write_textgrid(transcript, path, **options)
    else:
        write_plain_text(transcript, path)
