"""Our transcript as the Google Speech-to-Text JSON that the original Gesticulator reads.

The original reads a JSON list of recognition results, each ``{"alternatives": [{"transcript": ..., "words":
[{"start_time": "0.400s", "end_time": "0.800s", "word": "deep"}, ...]}]}``, takes the first alternative's words,
turns the times into deciseconds and embeds a sentence each time a word ends with ``.``, ``!`` or ``?``; words
after the last such word are never embedded. So the last word of a segment must end with one of them: a full
stop is added when it does not.
"""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from evalsuite.corpus.types import Transcript, Word

__all__ = ["google_asr_json", "seconds_string", "SENTENCE_END"]

SENTENCE_END = (".", "!", "?")


def seconds_string(t: float) -> str:
    """``1.5`` -> ``"1.500s"`` (Google ASR's duration notation, millisecond precision, never negative)."""
    return f"{max(0.0, float(t)):.3f}s"


def google_asr_json(transcript: Transcript | Iterable[Word] | None) -> list[dict[str, Any]]:
    """One recognition result holding every word of the segment (empty words dropped, times clamped so that
    they never go backwards); the last word ends with ``.``, ``!`` or ``?`` (a ``.`` is appended otherwise).
    An empty or missing transcript gives ``[]``."""
    words = transcript.words if isinstance(transcript, Transcript) else tuple(transcript or ())
    entries: list[dict[str, Any]] = []
    prev_end = 0.0
    for w in sorted(words, key=lambda w: (w.start, w.end)):
        text = " ".join(w.text.split())
        if not text:
            continue
        start = max(prev_end, float(w.start))
        end = max(start, float(w.end))
        prev_end = end
        entries.append({"start_time": seconds_string(start), "end_time": seconds_string(end), "word": text})
    if not entries:
        return []
    if not entries[-1]["word"].endswith(SENTENCE_END):
        entries[-1]["word"] += "."
    return [{"alternatives": [{"transcript": " ".join(e["word"] for e in entries), "words": entries}]}]
