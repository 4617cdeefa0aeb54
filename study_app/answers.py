"""Validation of what a participant's browser sends: tokens, interaction events, and answers (through
the page kind of each plan page, :mod:`study_app.pages`).

Every endpoint payload goes through these functions; anything unexpected raises
:class:`PayloadError` (answered with HTTP 422 and the message), never a KeyError.
"""
from __future__ import annotations

import re

from study_app.model import Study
from study_app.pages import Outcome, get_kind
from study_app.payload import PayloadError, int_in, only_keys, require_dict

TOKEN_RE = re.compile(r"^[A-Za-z0-9_-]{8,64}$")
# "unplayable": the participant reports that a video (slot) or every video of the page (slot null) does
# not play; the admin page counts these reports per stimulus.
EVENT_KINDS = ("play", "pause", "seeked", "ended", "choice", "reload", "hidden", "visible", "resize",
               "unplayable")
MAX_EVENTS = 2000


def parse_token(value) -> str:
    if not isinstance(value, str) or not TOKEN_RE.match(value):
        raise PayloadError("token: expected 8-64 characters of letters, digits, '_' or '-'")
    return value


def parse_events(value, n_slots: int) -> list[dict]:
    if value is None:
        return []
    if not isinstance(value, list) or len(value) > MAX_EVENTS:
        raise PayloadError(f"events: expected a list of at most {MAX_EVENTS} events")
    out = []
    for i, e in enumerate(value):
        what = f"events[{i}]"
        require_dict(e, what)
        only_keys(e, ("id", "kind", "slot", "t", "ms", "detail"), what)
        if not isinstance(e.get("id"), str) or not TOKEN_RE.match(e["id"]):
            raise PayloadError(f"{what}.id: expected 8-64 characters of letters, digits, '_' or '-'")
        if e.get("kind") not in EVENT_KINDS:
            raise PayloadError(f"{what}.kind: expected one of {', '.join(EVENT_KINDS)}")
        slot = e.get("slot")
        if slot is not None:
            int_in(slot, 0, max(n_slots - 1, 0), f"{what}.slot")
        for key in ("t", "ms"):
            v = e.get(key)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))
                                  or not -1 <= v <= 1e13):
                raise PayloadError(f"{what}.{key}: expected a number")
        detail = e.get("detail", "")
        if not isinstance(detail, str) or len(detail) > 200:
            raise PayloadError(f"{what}.detail: expected a string of at most 200 characters")
        out.append({"id": e["id"], "kind": e["kind"], "slot": slot, "t": e.get("t"),
                    "ms": e.get("ms"), "detail": detail})
    return out


def n_slots(spec: dict) -> int:
    """Media slots of a plan page (videos or sounds the participant must play)."""
    return get_kind(spec["type"]).n_slots(spec)


def parse_answer(study: Study, spec: dict, answer, fields: dict | None = None) -> dict:
    """Validated answer data for a plan page (raises :class:`PayloadError`); ``fields`` are the request's
    other fields that a kind may read (e.g. the consent page's window ``width``)."""
    return get_kind(spec["type"]).parse_answer(study, spec, require_dict(answer, "answer"), fields or {})


def judge(study: Study, spec: dict, data: dict) -> Outcome:
    """What a validated answer means for the session (attention check, end reason, honeypot)."""
    return get_kind(spec["type"]).outcome(study, spec, data)

