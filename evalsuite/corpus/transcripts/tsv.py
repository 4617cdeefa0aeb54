"""GENEA 2022/2023 word TSV: one line per annotation, ``start<TAB>end<TAB>text``, times in decimal seconds,
no header (a first line ``start<TAB>end<TAB>word`` is tolerated). Some GENEA annotations hold several words
("you know"); each line is kept as one :class:`~evalsuite.corpus.types.Word`. Two GENEA 2023 files are
empty because the speaker says nothing; the GENEA readers accept that (``allow_empty``)."""
from __future__ import annotations

import os

from evalsuite.corpus.transcripts._common import Item, format_seconds, parse_seconds, read_text, to_transcript
from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError

__all__ = ["read_tsv", "write_tsv"]

_HEADER = {"start", "start_time", "begin", "onset"}


def read_tsv(path: str | os.PathLike[str], *, allow_empty: bool = False) -> Transcript:
    text = read_text(path, what="GENEA TSV transcript", allow_empty=allow_empty)
    items: list[Item] = []
    for n, raw in enumerate(text.splitlines(), start=1):
        line = raw.rstrip("\r\n")
        if not line.strip():
            continue
        fields = line.split("\t")
        if n == 1 and fields[0].strip().lower() in _HEADER:
            continue
        if len(fields) < 3:
            raise InputError(f"expected 3 tab-separated fields (start, end, word), found {len(fields)}: {line!r}",
                             path=path, line=n)
        if len(fields) > 3:
            raise InputError(f"expected 3 tab-separated fields (start, end, word), found {len(fields)}; "
                             "a word may not contain a tab", path=path, line=n)
        start = parse_seconds(fields[0].strip(), path=path, line=n, field="start (field 1)")
        end = parse_seconds(fields[1].strip(), path=path, line=n, field="end (field 2)")
        word = fields[2].strip()
        if not word:
            raise InputError("field 3 (word) is empty; expected the spoken text", path=path, line=n)
        items.append(Item(word, start, end, line=n))
    if not items and not allow_empty and text.strip():
        raise InputError("no words in the file; expected lines of start<TAB>end<TAB>word", path=path)
    return to_transcript(items, path)


def write_tsv(transcript: Transcript, path: str | os.PathLike[str]) -> None:
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        for w in transcript.words:
            if "\t" in w.text or "\n" in w.text:
                raise InputError(f"word {w.text!r} holds a tab or newline, which TSV cannot store", path=path)
            fh.write(f"{format_seconds(w.start)}\t{format_seconds(w.end)}\t{w.text}\n")
