"""Shared pieces of the transcript readers: decoding text with precise errors, time strings, and turning
parsed items into a :class:`~evalsuite.corpus.types.Transcript` with line-accurate checks."""
from __future__ import annotations

import math
import os
import pathlib
from dataclasses import dataclass

from evalsuite.corpus.types import Transcript, Word
from evalsuite.errors import InputError

__all__ = ["Item", "read_text", "format_seconds", "to_transcript"]


@dataclass(frozen=True)
class Item:
    """One parsed word: text, start, end, and where it came from (line and/or field) for messages."""

    text: str
    start: float
    end: float
    line: int | None = None
    field: str | None = None
    estimated: bool = False


def read_text(path: str | os.PathLike[str], *, what: str, allow_empty: bool = False) -> str:
    """The file's text: UTF-8 (a BOM is accepted) or UTF-16 with a BOM (Praat writes that for non-ASCII).

    InputError naming the file, line and column of the first byte that is not valid UTF-8, or an empty
    file (unless ``allow_empty``; whitespace only counts as empty).
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError(f"no such {what} file", path=path)
    data = path.read_bytes()
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            text = data.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise InputError(f"invalid UTF-16 text at byte {exc.start}; expected a {what} file", path=path) from None
    else:
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            line = data.count(b"\n", 0, exc.start) + 1
            col = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
            raise InputError(f"column {col}: byte 0x{data[exc.start]:02x} is not valid UTF-8; expected a "
                             f"UTF-8 {what} file", path=path, line=line) from None
    if not text.strip() and not allow_empty:
        raise InputError(f"the file is empty; expected a {what} file with at least one word", path=path)
    return text


def format_seconds(t: float) -> str:
    """Seconds with at most 6 decimals and no trailing zeros: ``0.4``, ``6``, ``12.345678``."""
    s = f"{t:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("", "-0") else s


def parse_seconds(value: str, *, path: str | os.PathLike[str] | None, line: int | None, field: str,
                  expected: str = "a time in seconds such as 1.25") -> float:
    """A decimal number of seconds (plain or exponent notation), finite and >= 0."""
    try:
        t = float(value)
    except (TypeError, ValueError):
        raise InputError(f"expected {expected}, found {value!r}", path=path, line=line, field=field) from None
    if not math.isfinite(t) or t < 0 or value.strip().lower().startswith(("nan", "inf", "+inf", "-inf")):
        raise InputError(f"expected {expected} (finite, >= 0), found {value!r}", path=path, line=line, field=field)
    return t


def to_transcript(items: list[Item], path: str | os.PathLike[str] | None) -> Transcript:
    """Check every item (start <= end, in time order, no overlap) naming its line/field, then build."""
    prev: Item | None = None
    for it in items:
        if it.end < it.start:
            raise InputError(f"word {it.text!r} ends ({format_seconds(it.end)} s) before it starts "
                             f"({format_seconds(it.start)} s); expected start <= end",
                             path=path, line=it.line, field=it.field)
        if prev is not None and it.start < prev.end - 1e-6:
            where = f"line {prev.line}" if prev.line is not None else (prev.field or "the previous word")
            raise InputError(f"word {it.text!r} starts at {format_seconds(it.start)} s, before {prev.text!r} "
                             f"({where}) ends at {format_seconds(prev.end)} s; expected words in time order "
                             "without overlap", path=path, line=it.line, field=it.field)
        prev = it
    return Transcript(tuple(Word(it.text, it.start, it.end, it.estimated) for it in items),
                      source=os.fspath(path) if path is not None else None)
