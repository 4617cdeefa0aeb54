"""Google speech-to-text JSON, as Gesticulator and Gesture2Vec read it.

A list of results (or an object with ``"results"``), each ``{"alternatives": [{"transcript": ...,
"words": [{"start_time": "0.400s", "end_time": "0.800s", "word": "deep"}, ...]}]}``; only the first
alternative of each result is read. Times are strings with an ``s`` suffix (``"6s"``, ``"0.400s"``); the
newer camelCase ``startTime``/``endTime``, ``startOffset``/``endOffset``, plain numbers and protobuf
``{"seconds": 1, "nanos": 400000000}`` objects are accepted too. Written as Gesticulator's demo files are:
a list of results with ``start_time``/``end_time`` strings (at most 6 decimals).
"""
from __future__ import annotations

import json
import json.decoder
import json.scanner
import os
import re
from typing import Any

from evalsuite.corpus.transcripts._common import Item, format_seconds, read_text, to_transcript
from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError

__all__ = ["read_google_json", "write_google_json"]

_START_KEYS = ("start_time", "startTime", "startOffset", "start_offset")
_END_KEYS = ("end_time", "endTime", "endOffset", "end_offset")
_TIME = re.compile(r"^\s*([0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?s\s*$")
_EXPECTED = 'a duration string such as "0.400s" or "6s"'


def _time(value: Any, path: str | os.PathLike[str], field: str) -> float:
    if isinstance(value, bool):
        raise InputError(f"expected {_EXPECTED}, found {value!r}", path=path, field=field)
    if isinstance(value, (int, float)):
        if value < 0 or value != value or value in (float("inf"),):
            raise InputError(f"expected {_EXPECTED} (finite, >= 0), found {value!r}", path=path, field=field)
        return float(value)
    if isinstance(value, dict) and set(value) <= {"seconds", "nanos"}:
        try:
            t = float(value.get("seconds", 0)) + float(value.get("nanos", 0)) * 1e-9
        except (TypeError, ValueError):
            raise InputError(f"expected {_EXPECTED} or {{'seconds', 'nanos'}}, found {value!r}",
                             path=path, field=field) from None
        if t < 0:
            raise InputError(f"expected a time >= 0, found {value!r}", path=path, field=field)
        return t
    if isinstance(value, str) and _TIME.match(value):
        return float(value.strip()[:-1])
    raise InputError(f"expected {_EXPECTED}, found {value!r}", path=path, field=field)


def _pick(word: dict[str, Any], keys: tuple[str, ...], path: str | os.PathLike[str], where: str) -> float:
    for k in keys:
        if k in word:
            return _time(word[k], path, f"{where}.{k}")
    raise InputError(f"missing {keys[0]!r} (or {', '.join(repr(k) for k in keys[1:])}); expected every word "
                     "to have a start and an end time", path=path, field=where)


class _Located(dict):
    """A JSON object that knows the line it starts on."""

    line = 0


def _line_of(text: str, field: str) -> int | None:
    """The line of the JSON object a field path (``results[0].alternatives[0].words[3].start_time``) names,
    found by parsing again with the standard library's pure-Python scanner, which reports where each object
    starts. Only used to place an error message; None when anything about it fails."""
    decoder: Any = json.JSONDecoder()
    json_object: Any = getattr(json.decoder, "JSONObject", None)
    make_scanner: Any = getattr(json.scanner, "py_make_scanner", None)
    if json_object is None or make_scanner is None:
        return None

    def parse_object(s_and_end: tuple[str, int], strict: bool, scan_once: Any, hook: Any, pairs_hook: Any,
                     memo: Any = None) -> tuple[Any, int]:
        obj, end = json_object(s_and_end, strict, scan_once, None, _Located, memo)
        obj.line = text.count("\n", 0, s_and_end[1]) + 1
        return obj, end

    decoder.parse_object = parse_object
    decoder.scan_once = make_scanner(decoder)
    try:
        node: Any = decoder.decode(text)
    except (ValueError, TypeError, RecursionError):
        return None
    line = None
    for part in re.findall(r"[A-Za-z_]+|\[\d+\]", field):
        if part == "results" and isinstance(node, list):
            continue
        if part.startswith("[") and isinstance(node, list) and int(part[1:-1]) < len(node):
            node = node[int(part[1:-1])]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            break
        line = node.line if isinstance(node, _Located) else line
    return line


def read_google_json(path: str | os.PathLike[str], *, allow_empty: bool = False) -> Transcript:
    text = read_text(path, what="Google speech-to-text JSON", allow_empty=allow_empty)
    try:
        return _read(text, path, allow_empty)
    except InputError as exc:
        if exc.field is None or exc.line is not None:
            raise
        raise InputError(exc.reason, path=path, line=_line_of(text, exc.field), field=exc.field) from None


def _read(text: str, path: str | os.PathLike[str], allow_empty: bool) -> Transcript:
    if not text.strip():
        return Transcript((), source=os.fspath(path))
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"column {exc.colno}: not valid JSON ({exc.msg}); expected Google speech-to-text JSON",
                         path=path, line=exc.lineno) from None
    results = data.get("results") if isinstance(data, dict) else data
    if not isinstance(results, list):
        raise InputError("expected a list of results (or an object with a 'results' list) of "
                         "{'alternatives': [{'words': [...]}]}", path=path)
    items: list[Item] = []
    for r, result in enumerate(results):
        where = f"results[{r}]"
        if not isinstance(result, dict) or not isinstance(result.get("alternatives"), list):
            raise InputError("expected an object with an 'alternatives' list", path=path, field=where)
        if not result["alternatives"]:
            continue
        alt = result["alternatives"][0]
        where += ".alternatives[0]"
        if not isinstance(alt, dict):
            raise InputError("expected an object with a 'words' list", path=path, field=where)
        words = alt.get("words", [])
        if not isinstance(words, list):
            raise InputError("expected 'words' to be a list", path=path, field=where)
        for w, word in enumerate(words):
            wwhere = f"{where}.words[{w}]"
            if not isinstance(word, dict):
                raise InputError("expected an object with 'word', 'start_time' and 'end_time'", path=path,
                                 field=wwhere)
            token = word.get("word")
            if not isinstance(token, str) or not token.strip():
                raise InputError(f"missing or empty 'word' (found {token!r}); expected the word as text",
                                 path=path, field=wwhere)
            items.append(Item(token.strip(), _pick(word, _START_KEYS, path, wwhere),
                              _pick(word, _END_KEYS, path, wwhere), field=wwhere))
    if not items and not allow_empty:
        raise InputError("no words in the file; expected results with timed words", path=path)
    return to_transcript(items, path)


def write_google_json(transcript: Transcript, path: str | os.PathLike[str]) -> None:
    words = [{"start_time": format_seconds(w.start) + "s", "end_time": format_seconds(w.end) + "s", "word": w.text}
             for w in transcript.words]
    data = [{"alternatives": [{"transcript": transcript.text, "words": words}]}]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        json.dump(data, fh, indent=1, ensure_ascii=False)
        fh.write("\n")
