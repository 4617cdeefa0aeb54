"""The interaction log in the database: events stored once each, within the caps of the session policy,
and read back in batches.

Playback events (``play``, ``ended``: what the server's playback check reads) and the others are capped
apart (:class:`~study_app.policy.Rules` ``events_per_page`` and ``events_per_session``, each for playback
events and for the others), so that a long slider drag can never crowd out the record that a video was
played.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator

from sqlalchemy import bindparam, case, func, insert, select
from sqlalchemy.orm import Session

from study_app.policy import Rules
from study_app.storage.statements import SLOTS_WITH
from study_app.storage.tables import Event, ParticipantSession

__all__ = ["PLAYBACK_KINDS", "add_events", "slots_with", "EventLog"]

PLAYBACK_KINDS = ("play", "ended")     # the events the server's playback check reads


_KNOWN = select(Event.client_id).where(Event.session_id == bindparam("sid"),
                                      Event.client_id.in_(bindparam("ids", expanding=True)))
# one statement counts both groups (playback or not) on the page and in the session
_PLAYBACK, _ON_PAGE = Event.kind.in_(PLAYBACK_KINDS), Event.page_index == bindparam("index")
_COUNTS = select(func.count(case((_PLAYBACK & _ON_PAGE, 1))), func.count(case((_PLAYBACK, 1))),
                 func.count(case((~_PLAYBACK & _ON_PAGE, 1))), func.count(case((~_PLAYBACK, 1)))
                 ).where(Event.session_id == bindparam("sid"))


def add_events(db: Session, rules: Rules, session_id: str, page_index: int,
               events: list[dict]) -> tuple[int, str]:
    """Store the events of page ``page_index`` not seen before (by client id), up to the caps of ``rules``;
    returns how many new events the caps dropped and which cap (``"page"``/``"session"``, else "")."""
    if not events:
        return 0, ""
    ids = [e["id"] for e in events]
    known = set(db.scalars(_KNOWN, {"sid": session_id, "ids": ids}))
    new = []
    for e in events:
        if e["id"] in known:
            continue  # a retried batch: the log keeps one copy of each event
        known.add(e["id"])
        new.append(e)
    if not new:
        return 0, ""
    counts = db.execute(_COUNTS, {"sid": session_id, "index": page_index}).one()
    room, limit = {}, {}
    for group, (on_this_page, in_session) in ((True, counts[0:2]), (False, counts[2:4])):
        page_room = rules.events_per_page - on_this_page
        session_room = rules.events_per_session - in_session
        room[group] = max(0, min(page_room, session_room))
        limit[group] = "session" if session_room < page_room else "page"
    dropped, which = 0, ""
    rows = []
    for e in new:
        group = e["kind"] in PLAYBACK_KINDS
        if not room[group]:
            dropped += 1
            which = limit[group]
            continue
        room[group] -= 1
        rows.append({"session_id": session_id, "client_id": e["id"], "page_index": page_index,
                     "kind": e["kind"], "slot": e.get("slot"), "media_time": e.get("t"),
                     "client_ms": e.get("ms"), "detail": e.get("detail", "")})
    if rows:
        # append-only rows: one executemany, not the ORM's unit of work
        db.execute(insert(Event), rows)
    return dropped, which


def slots_with(db: Session, session_id: str, page_index: int, kind: str) -> set[int]:
    """The media slots of a page with a logged event of ``kind``."""
    return set(db.scalars(SLOTS_WITH, {"sid": session_id, "index": page_index, "kind": kind}))


class EventLog:
    """A study's interaction log, read from the database in batches each time it is iterated (never all
    rows at once). ``read_session`` makes read-only database sessions (:attr:`Store.ReadSession`)."""

    def __init__(self, read_session: Callable[[], Session], study_id: str, batch: int = 2000):
        self.read_session, self.study_id, self.batch = read_session, study_id, batch

    def __iter__(self) -> Iterator[Event]:
        stmt = (select(Event).join(ParticipantSession, Event.session_id == ParticipantSession.id)
                .where(ParticipantSession.study == self.study_id).order_by(Event.id)
                .execution_options(yield_per=self.batch))
        with self.read_session() as db:
            for event in db.scalars(stmt):
                yield event
                db.expunge(event)
