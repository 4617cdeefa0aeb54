"""The bytes the server sent for each media request, and how much of each file a session received.

Every media response that carries a body is recorded (``media_served``: session, page, slot, the first and
last byte of the range sent, the file's length, the HTTP status and the time). The coverage of a slot is the
union of its ranges: a slot counts as fully served only when the union covers every byte of the file
(:mod:`study_app.playback` then judges the page). When the app sends the
media itself the range is queued for the media log's writer (:mod:`study_app.media_log`); behind nginx
(``X-Accel-Redirect``) nginx sends the bytes and its access log says which, read by
:mod:`study_app.media_nginx` (docs/study_app.md, "What counts as watched"; docs/deploy.md).
"""
from __future__ import annotations

import logging

from sqlalchemy import select

from study_app.storage.tables import MediaServed, ParticipantSession, utcnow

__all__ = ["record_served", "served_range", "coverage", "served_by_page", "fully_served"]

log = logging.getLogger(__name__)


def served_range(resp) -> tuple[int, int, int] | None:
    """(first byte, last byte inclusive, file length) of a media response's body, or None without one."""
    if resp.status_code == 206 and resp.content_range is not None and resp.content_range.stop is not None:
        cr = resp.content_range
        return int(cr.start), int(cr.stop) - 1, int(cr.length)
    if resp.status_code == 200 and resp.content_length:
        return 0, int(resp.content_length) - 1, int(resp.content_length)
    return None


def record_served(store, session_id: str, page_index: int, slot: int, resp) -> None:
    """Record the range a media response sends (nothing for HEAD, 304 or 416 answers), through the media
    log's queued writer (:meth:`study_app.media_log.MediaLog.served`): the response never waits for it."""
    rng = served_range(resp)
    if rng is None:
        return
    first, last, total = rng
    store.media_log.served(session_id, page_index, slot, first, last, total, resp.status_code, utcnow())


def coverage(ranges: list[tuple[int, int]]) -> int:
    """Number of distinct bytes in the union of inclusive ranges ``[(first, last), ...]``."""
    covered, end = 0, -1
    for first, last in sorted(ranges):
        if last <= end:
            continue
        covered += last - max(first, end + 1) + 1
        end = last
    return covered


def served_by_page(db, study_id: str) -> dict[tuple[str, int], dict[int, tuple[int, int]]]:
    """(session, page index) → {slot: (distinct bytes served, file length)} for one study."""
    ranges: dict[tuple[str, int, int], list[tuple[int, int]]] = {}
    totals: dict[tuple[str, int, int], int] = {}
    for sid, index, slot, first, last, total in db.execute(
            select(MediaServed.session_id, MediaServed.page_index, MediaServed.slot, MediaServed.first_byte,
                   MediaServed.last_byte, MediaServed.total)
            .join(ParticipantSession, MediaServed.session_id == ParticipantSession.id)
            .where(ParticipantSession.study == study_id)):
        ranges.setdefault((sid, index, slot), []).append((first, last))
        totals[(sid, index, slot)] = max(total, totals.get((sid, index, slot), 0))
    out: dict[tuple[str, int], dict[int, tuple[int, int]]] = {}
    for (sid, index, slot), rs in ranges.items():
        out.setdefault((sid, index), {})[slot] = (coverage(rs), totals[(sid, index, slot)])
    return out


def fully_served(store, session_id: str, page_index: int, slot: int) -> bool:
    """Whether every byte of this slot's file was already sent to the session (the "play once" rule)."""
    store.media_log.flush()                # this process's queued records first
    with store.ReadSession() as db:
        rows = db.execute(select(MediaServed.first_byte, MediaServed.last_byte, MediaServed.total).where(
            MediaServed.session_id == session_id, MediaServed.page_index == page_index,
            MediaServed.slot == slot)).all()
    return bool(rows) and coverage([(a, b) for a, b, _t in rows]) >= max(t for _a, _b, t in rows)
