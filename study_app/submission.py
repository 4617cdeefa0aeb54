"""Turning a participant's POSTed answer into a validated :class:`Submission` (pure: no database).

The store calls :func:`validate_submission` inside the transaction that stores the answer, with the
participant's plan pages and a look-up of the media slots the participant has played on the page, so that
the checks and the write see the same state.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from study_app.answers import judge, n_slots, parse_answer, parse_events
from study_app.model import Study
from study_app.pages import Outcome, get_kind
from study_app.payload import PayloadError

__all__ = ["Submission", "validate_submission"]


@dataclass(frozen=True)
class Submission:
    data: dict
    outcome: Outcome
    events: list[dict] = field(default_factory=list)
    client_rt_ms: int | None = None


def validate_submission(study: Study, index: int, body: dict, pages: list[dict],
                        played: Callable[[str], set[int]]) -> Submission:
    """Validate the answer to plan page ``index`` (raises :class:`PayloadError`)."""
    if not 0 <= index < len(pages):
        raise PayloadError("no such page")
    spec = pages[index]
    width = body.get("width")
    if isinstance(width, int) and not isinstance(width, bool) and width < study.min_width:
        # the page covers itself in narrower windows; an answer from one is refused on every page (and so a
        # window too narrow for the study never reserves a plan, see Store.submit)
        raise PayloadError(f"please use a browser window at least {study.min_width} pixels wide")
    fields = {k: v for k, v in body.items() if k not in ("answer", "events", "token", "client_rt_ms")}
    data = parse_answer(study, spec, body.get("answer"), fields)
    slots = n_slots(spec)
    events = parse_events(body.get("events"), slots)
    if slots:
        kind = "ended" if study.require_full_playback else "play"
        seen = played(kind) | {e["slot"] for e in events if e["kind"] == kind}
        if not set(range(slots)) <= seen:
            what = "to the end " if kind == "ended" else ""
            raise PayloadError(f"please play every {get_kind(spec['type']).media_word} {what}before answering")
    return Submission(data=data, outcome=judge(study, spec, data), events=events,
                      client_rt_ms=body.get("client_rt_ms"))
