"""Praat TextGrid word tiers, long ("ooTextFile" with ``xmin = ...`` labels) and short text formats.

Both formats are the same sequence of values (strings, numbers, the ``<exists>`` flag); the long format
only adds labels (``xmin =``, ``intervals [3]:``), which this reader skips, the way Praat reads text files.
So one tokenizer with line numbers reads both and every error names the line. UTF-8 or UTF-16 (with a BOM,
as Praat writes files with non-ASCII text). Empty intervals are silences and are not words. The tier is
chosen by name (``tier=``); by default the one called ``words`` (or ``word``, any case), else the first
interval tier. Written in the long format with one interval tier (silences filled in as empty intervals).
"""
from __future__ import annotations

import bisect
import os
import re
from dataclasses import dataclass

from evalsuite.corpus.transcripts._common import Item, format_seconds, read_text, to_transcript
from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError

__all__ = ["read_textgrid", "write_textgrid", "textgrid_tiers"]

_TOKEN = re.compile(r'(?P<str>"(?:[^"]|"")*")|(?P<open>")|(?P<comment>![^\n]*)|(?P<flag><[A-Za-z]+>)'
                    r"|(?P<br>\[[^\]\n]*\])|(?P<word>[A-Za-z_][\w?]*)"
                    r"|(?P<num>[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)|(?P<other>\S)")


@dataclass
class _Tok:
    kind: str  # "str", "num", "flag"
    value: str
    line: int


@dataclass
class _Tier:
    cls: str
    name: str
    items: list[Item]


class _Reader:
    def __init__(self, text: str, path: str | os.PathLike[str]):
        self.path = path
        newlines = [m.start() for m in re.finditer("\n", text)]
        self.toks: list[_Tok] = []
        for m in _TOKEN.finditer(text):
            kind = m.lastgroup or ""
            line = bisect.bisect_left(newlines, m.start()) + 1
            if kind == "open":
                raise InputError("a string is opened with \" but never closed", path=path, line=line)
            if kind == "str":
                self.toks.append(_Tok("str", m.group()[1:-1].replace('""', '"'), line))
            elif kind in ("num", "flag"):
                self.toks.append(_Tok(kind, m.group(), line))
            elif kind == "word":
                # a label (xmin =, intervals: size, item [1]:, tiers? <exists>, File type =) is followed by
                # a letter or one of = : [ < ; anything else is a value someone forgot to quote
                rest = text[m.end():m.end() + 200].lstrip(" \t")
                if not rest or not (rest[0].isalpha() or rest[0] in "=:[<"):
                    raise InputError(f"found unquoted text {m.group()!r}; expected a quoted string or a number",
                                     path=path, line=line)
        self.pos = 0
        self.last_line = len(newlines) + 1

    def _next(self, expected: str) -> _Tok:
        if self.pos >= len(self.toks):
            raise InputError(f"the file ends early; expected {expected}", path=self.path, line=self.last_line)
        tok = self.toks[self.pos]
        self.pos += 1
        return tok

    def string(self, expected: str) -> str:
        tok = self._next(expected)
        if tok.kind != "str":
            raise InputError(f"expected {expected} (a quoted string), found {tok.value!r}", path=self.path,
                             line=tok.line)
        return tok.value

    def number(self, expected: str) -> tuple[float, int]:
        tok = self._next(expected)
        if tok.kind != "num":
            raise InputError(f"expected {expected} (a number), found {tok.value!r}", path=self.path, line=tok.line)
        return float(tok.value), tok.line

    def count(self, expected: str) -> int:
        value, line = self.number(expected)
        if value != int(value) or value < 0:
            raise InputError(f"expected {expected} (a whole number >= 0), found {value:g}", path=self.path, line=line)
        return int(value)

    def peek_flag(self) -> bool:
        if self.pos < len(self.toks) and self.toks[self.pos].kind == "flag":
            self.pos += 1
            return True
        return False


def _parse(text: str, path: str | os.PathLike[str]) -> list[_Tier]:
    rd = _Reader(text, path)
    if rd.string('File type = "ooTextFile"') != "ooTextFile":
        raise InputError('expected the header File type = "ooTextFile"', path=path, line=1)
    if rd.string('Object class = "TextGrid"') != "TextGrid":
        raise InputError('expected Object class = "TextGrid"', path=path, line=2)
    rd.number("the TextGrid's xmin")
    rd.number("the TextGrid's xmax")
    rd.peek_flag()  # tiers? <exists>
    n_tiers = rd.count("the number of tiers (size)")
    tiers = []
    for t in range(n_tiers):
        cls = rd.string(f'tier {t + 1}\'s class ("IntervalTier" or "TextTier")')
        name = rd.string(f"tier {t + 1}'s name")
        rd.number(f"tier {name!r}'s xmin")
        rd.number(f"tier {name!r}'s xmax")
        n = rd.count(f"the number of items of tier {name!r}")
        items = []
        for i in range(n):
            if cls == "IntervalTier":
                start, line = rd.number(f"xmin of interval {i + 1} of tier {name!r}")
                end, _ = rd.number(f"xmax of interval {i + 1} of tier {name!r}")
                label = rd.string(f"text of interval {i + 1} of tier {name!r}")
                if start < 0:
                    raise InputError(f"interval {i + 1} of tier {name!r} starts at {start:g}; expected a time >= 0",
                                     path=path, line=line)
                if label.strip():
                    items.append(Item(label.strip(), start, end, line=line))
            elif cls == "TextTier":
                rd.number(f"time of point {i + 1} of tier {name!r}")
                rd.string(f"mark of point {i + 1} of tier {name!r}")
            else:
                raise InputError(f'tier {t + 1} has class {cls!r}; expected "IntervalTier" or "TextTier"',
                                 path=path, line=rd.toks[rd.pos - 1].line)
        tiers.append(_Tier(cls, name, items))
    return tiers


def textgrid_tiers(path: str | os.PathLike[str]) -> list[tuple[str, str]]:
    """``[(name, class), ...]`` of a TextGrid's tiers."""
    return [(t.name, t.cls) for t in _parse(read_text(path, what="Praat TextGrid"), path)]


def read_textgrid(path: str | os.PathLike[str], *, tier: str | None = None) -> Transcript:
    tiers = _parse(read_text(path, what="Praat TextGrid"), path)
    intervals = [t for t in tiers if t.cls == "IntervalTier"]
    names = ", ".join(repr(t.name) for t in tiers) or "none"
    if tier is not None:
        chosen = [t for t in intervals if t.name == tier]
        if not chosen:
            raise InputError(f"no interval tier named {tier!r}; the file's tiers: {names}", path=path, field="tier")
    else:
        chosen = [t for t in intervals if t.name.lower() == "words"] or \
                 [t for t in intervals if t.name.lower() == "word"] or intervals[:1]
        if not chosen:
            raise InputError(f"no interval tier; expected a word tier (tiers: {names})", path=path)
    return to_transcript(chosen[0].items, path)


def _q(s: str) -> str:
    return '"' + s.replace('"', '""') + '"'


def write_textgrid(transcript: Transcript, path: str | os.PathLike[str], *, tier: str = "words",
                   xmax: float | None = None) -> None:
    end = max(transcript.end, xmax or 0.0)
    spans: list[tuple[float, float, str]] = []
    t = 0.0
    for w in transcript.words:
        if w.start > t + 1e-9:
            spans.append((t, w.start, ""))
        spans.append((w.start, w.end, w.text))
        t = w.end
    if end > t + 1e-9 or not spans:
        spans.append((t, end, ""))
    f = format_seconds
    lines = ['File type = "ooTextFile"', 'Object class = "TextGrid"', "", "xmin = 0", f"xmax = {f(end)}",
             "tiers? <exists>", "size = 1", "item []:", "    item [1]:", '        class = "IntervalTier"',
             f"        name = {_q(tier)}", "        xmin = 0", f"        xmax = {f(end)}",
             f"        intervals: size = {len(spans)}"]
    for i, (a, b, text) in enumerate(spans, start=1):
        lines += [f"        intervals [{i}]:", f"            xmin = {f(a)}", f"            xmax = {f(b)}",
                  f"            text = {_q(text)}"]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")
