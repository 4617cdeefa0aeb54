"""A participant's page view, read by :meth:`study_app.storage.store.Store.view_current_page`: without any
lock when nothing needs writing, else in one writing transaction that creates the page's first-view record."""
from __future__ import annotations

from sqlalchemy import select

from study_app.storage.tables import Event, PageView, utcnow

__all__ = ["current_page", "view_current_page"]


def current_page(store, db, session_id: str, now, write: bool):
    """(session, plan pages, first-view record, played slots) of a session's current page in ``db``, None
    for an unknown session; without ``write``, False when something must be written first (the page's
    first view, or an expired reservation)."""
    sess, plan = store.session_and_plan(db, session_id)
    if sess is None:
        return None
    if store._expiry_due(sess, plan, now):
        if not write:
            return False
        store.release_expired(db, sess.study, now)
    pages = store._pages(sess, plan)
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


def view_current_page(store, session_id: str):
    """A page view: the session, its plan, the current page's first-view record (created now if new,
    with the autosaved draft) and the slots already played / played to the end. Returns None for an
    unknown session.

    Read without any lock when there is nothing to write (the page was shown before and the reservation
    holds; tried first only when this process showed the session's current page before, else the read is
    skipped as the page is most likely new); otherwise one writing transaction, which skips the fsync
    (``RelaxedSession``): the first-view time acknowledges nothing to the participant, so a page view never
    waits behind answers' fsyncs."""
    now = utcnow()
    if session_id in store._viewed:
        # This process showed the session's current page before (a reload, or the page after a refused
        # answer): most likely nothing needs writing. Otherwise (a new page) go straight to the write.
        with store.ReadSession() as db:
            seen = current_page(store, db, session_id, now, write=False)
        if seen is not False:
            return seen
    with store.RelaxedSession.begin() as db:
        seen = current_page(store, db, session_id, now, write=True)
    if len(store._viewed) > 100_000:
        store._viewed.clear()        # a hint: bounded memory matters more
    store._viewed.add(session_id)
    return seen
