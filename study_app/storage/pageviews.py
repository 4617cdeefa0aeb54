"""A participant's page view, read by :meth:`study_app.storage.store.Store.view_current_page`: without any
lock when nothing needs writing, else in one writing transaction that creates the page's first-view record."""
from __future__ import annotations

from sqlalchemy import select

from study_app.storage.tables import Event, PageView, ParticipantSession

__all__ = ["current_page"]


def current_page(store, db, session_id: str, now, write: bool):
    """(session, plan pages, first-view record, played slots) of a session's current page in ``db``, None
    for an unknown session; without ``write``, False when something must be written first (the page's
    first view, or an expired reservation)."""
    sess = db.get(ParticipantSession, session_id)
    if sess is None:
        return None
    if store._expiry_due(db, sess, now):
        if not write:
            return False
        store.release_expired(db, sess.study, now)
    pages = store._pages(db, sess)
    view = None
    played: dict[str, set] = {"play": set(), "ended": set()}
    if sess.status == "active":
        index = sess.current_page
        view = db.scalars(select(PageView).where(PageView.session_id == session_id,
                                                 PageView.page_index == index)).first()
        if view is None:
            if not write:
                return False
            view = PageView(session_id=session_id, page_index=index, shown_at=now)
            db.add(view)
        for kind, slot in db.execute(select(Event.kind, Event.slot).where(
                Event.session_id == session_id, Event.page_index == index,
                Event.kind.in_(("play", "ended")))):
            played[kind].add(slot)
    return sess, pages, view, played
