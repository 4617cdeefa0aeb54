"""``results.csv``: one row per judgement of a study (``docs/results_format.md``).

Written by the study app's export (:mod:`study_app.export`, all of :data:`COLUMNS` in this order), read by
``evalsuite analyze`` (:mod:`evalsuite.analysis.io`), which needs :data:`REQUIRED` and fills absent optional
columns with empty values (so results from other tools need only the required ones).
"""
from __future__ import annotations

__all__ = ["COLUMNS", "REQUIRED"]

COLUMNS = ("study", "participant", "platform", "session", "session_status", "page", "page_type",
           "trial", "question", "scale", "segment", "condition", "condition_a", "condition_b",
           "position_a", "answer", "strength", "role", "rt_ms", "is_training", "is_attention_check",
           "attention_expected", "attention_passed", "shown_at", "answered_at", "reasons",
           "playback_implausible", "playback_reason", "audio_a", "audio_b")
# Optional: ``playback_implausible`` (0/1, empty for pages without media) is the study server's judgement that
# a page's media were not really played (a video never fetched, or less time on the page than the clips
# last); ``playback_reason`` says why (e.g. ``unwatched: bytes 1/2,345,678 served``); ``evalsuite analyze``
# can exclude sessions on it and reports the reasons. ``audio_a``/``audio_b`` (pairwise): the speech segment
# each side's video played (empty in a muted block); they differ on audio-mismatch pages.
# Columns the analysis cannot do without.
REQUIRED = ("study", "participant", "session", "session_status", "page", "page_type", "question",
            "condition", "condition_a", "condition_b", "answer", "is_training", "is_attention_check",
            "attention_passed")
