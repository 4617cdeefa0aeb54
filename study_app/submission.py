"""The answer POST body (``/s/<sid>/answer/<index>``): its schema, and turning it into a validated
:class:`Submission` (pure: no database). This module owns the body; the endpoint and the store use it.

The body is a JSON object with these fields, checked in this order (any other field is refused):

=================  ==========================================================================================
``token``          8-64 letters, digits, ``_`` or ``-``; the same token again is a retry of the same answer
``client_rt_ms``   optional: the browser's response time, an integer in 0..10**9
``answer``         an object, checked by the page's kind (:mod:`study_app.pages`)
``events``         optional: interaction events of the page (:func:`study_app.answers.parse_events`)
``width``          optional: the browser window's width; an integer below the study's ``min_width`` is
                   refused on every page, and page kinds may read it (the consent page does)
=================  ==========================================================================================

:func:`parse_answer_body` checks what needs no plan (fields, token, response time) before the store is
asked; the store calls :func:`validate_submission` inside the transaction that stores the answer, with the
participant's plan pages and a look-up of the media slots the participant has played on the page, so that
the checks and the write see the same state.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from study_app.answers import judge, n_slots, parse_answer, parse_events, parse_token
from study_app.model import Study
from study_app.pages import Outcome, get_kind
from study_app.payload import PayloadError

__all__ = ["ANSWER_BODY_FIELDS", "AnswerBody", "parse_answer_body", "Submission", "validate_submission"]

ANSWER_BODY_FIELDS = ("token", "answer", "events", "client_rt_ms", "width")
MAX_CLIENT_RT_MS = 10**9


@dataclass(frozen=True)
class AnswerBody:
    """An answer body whose plan-independent fields are checked; ``answer`` and ``events`` are checked
    against the plan page by :func:`validate_submission`; ``fields`` are the other fields a page kind may
    read (``width``, when sent)."""
    token: str
    answer: Any = None
    events: Any = None
    client_rt_ms: int | None = None
    fields: dict = field(default_factory=dict)


def parse_answer_body(body: dict) -> AnswerBody:
    """The answer body's fields, token and response time checked (raises :class:`PayloadError`)."""
    extra = sorted(set(body) - set(ANSWER_BODY_FIELDS))
    if extra:
        raise PayloadError(f"unexpected field {extra[0]!r}")
    token = parse_token(body.get("token"))
    client_rt = body.get("client_rt_ms")
    if client_rt is not None and (isinstance(client_rt, bool) or not isinstance(client_rt, int)
                                  or not 0 <= client_rt <= MAX_CLIENT_RT_MS):
        raise PayloadError("client_rt_ms: expected a non-negative integer")
    fields = {k: v for k, v in body.items() if k not in ("answer", "events", "token", "client_rt_ms")}
    return AnswerBody(token=token, answer=body.get("answer"), events=body.get("events"),
                      client_rt_ms=client_rt, fields=fields)


@dataclass(frozen=True)
class Submission:
    data: dict
    outcome: Outcome
    events: list[dict] = field(default_factory=list)
    client_rt_ms: int | None = None


def validate_submission(study: Study, index: int, body: AnswerBody, pages: list[dict],
                        played: Callable[[str], set[int]]) -> Submission:
    """Validate the answer to plan page ``index`` (raises :class:`PayloadError`)."""
    if not 0 <= index < len(pages):
        raise PayloadError("no such page")
    spec = pages[index]
    width = body.fields.get("width")
    if isinstance(width, int) and not isinstance(width, bool) and width < study.min_width:
        # the page covers itself in narrower windows; an answer from one is refused on every page (and so a
        # window too narrow for the study never reserves a plan, see Store.submit)
        raise PayloadError(f"please use a browser window at least {study.min_width} pixels wide")
    data = parse_answer(study, spec, body.answer, body.fields)
    slots = n_slots(spec)
    events = parse_events(body.events, slots)
    if slots:
        kind = "ended" if study.require_full_playback else "play"
        seen = played(kind) | {e["slot"] for e in events if e["kind"] == kind}
        if not set(range(slots)) <= seen:
            what = "to the end " if kind == "ended" else ""
            raise PayloadError(f"please play every {get_kind(spec['type']).media_word} {what}before answering")
    return Submission(data=data, outcome=judge(study, spec, data), events=events,
                      client_rt_ms=body.client_rt_ms)
