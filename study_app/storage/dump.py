"""A study's whole record read at once, for the admin page and the exports (:meth:`Store.dump`)."""
from __future__ import annotations

from sqlalchemy import func, select

from study_app.served import served_by_page
from study_app.storage.events import EventLog
from study_app.storage.tables import Answer, Event, MediaRequest, ParticipantSession, Plan

__all__ = ["dump"]


def dump(store, study_id: str) -> dict:
    """Sessions, plans and answers of a study. The interaction log is not loaded: ``events`` is an
    :class:`EventLog` that streams it from the database when iterated (raw JSON export), and
    ``event_counts`` the number of events per session; ``media_requests`` and ``media_served`` (slot → bytes
    sent, file length) per (session, page index)."""
    store.media_log.flush()
    with store.ReadSession() as db:
        sessions = db.scalars(select(ParticipantSession).where(
            ParticipantSession.study == study_id).order_by(ParticipantSession.created_at)).all()
        plans = {p.id: p for p in db.scalars(select(Plan).where(Plan.study == study_id))}
        of_study = ParticipantSession.study == study_id
        answers = db.scalars(select(Answer).join(ParticipantSession, Answer.session_id == ParticipantSession.id)
                             .where(of_study).order_by(Answer.session_id, Answer.page_index)).all()
        counts = {sid: n for sid, n in db.execute(
            select(Event.session_id, func.count(Event.id))
            .join(ParticipantSession, Event.session_id == ParticipantSession.id)
            .where(of_study).group_by(Event.session_id))}
        requested: dict[tuple[str, int], set[int]] = {}
        for sid, index, slot in db.execute(
                select(MediaRequest.session_id, MediaRequest.page_index, MediaRequest.slot)
                .join(ParticipantSession, MediaRequest.session_id == ParticipantSession.id).where(of_study)):
            requested.setdefault((sid, index), set()).add(slot)
        return {"sessions": sessions, "plans": plans, "answers": answers, "media_served": served_by_page(db, study_id),
                "events": EventLog(store.ReadSession, study_id), "event_counts": counts, "media_requests": requested}

