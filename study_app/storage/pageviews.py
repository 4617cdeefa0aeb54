"""A participant's page view, read by :meth:`study_app.storage.store.Store.view_current_page`: without any
lock when nothing needs writing, else in one writing transaction that creates the page's first-view record."""
from __future__ import annotations

import datetime as dt
from typing import NamedTuple

from sqlalchemy import insert

from study_app.errors import StudyStateError
from study_app.storage.statements import PAGES, PLAYED, SESSION_ROW, VIEW
from study_app.storage.tables import PageView, utcnow

__all__ = ["current_page", "view_current_page"]


def _session_row(db, session_id: str):
    """The session's columns and its plan's status and reservation end, as one row (no ORM object: a page
    view only reads them)."""
    return db.execute(SESSION_ROW, {"sid": session_id}).first()


def current_page(store, db, session_id: str, now, write: bool):
    """(session, plan pages, first-view record, played slots) of a session's current page in ``db``, None
    for an unknown session; without ``write``, False when something must be written first (the page's
    first view, or an expired reservation). The session is a row of its columns, the first-view record one
    of ``shown_at`` and ``draft``."""
    sess = _session_row(db, session_id)
    if sess is None:
        return None
    if sess.status == "active" and sess.plan_status == "reserved" and sess.plan_reserved_until < now:
        if not write:
            return False
        store.release_expired(db, sess.study, now)
        sess = _session_row(db, session_id)
    if sess.plan_id is None:
        pages = store._pages(sess, None)
    else:
        pages = store.pages_of(sess.plan_id, lambda: db.scalar(PAGES, {"plan": sess.plan_id}))
        if pages is None:
            raise StudyStateError(f"session {sess.id} refers to plan {sess.plan_id}, which the database lacks")
    view = None
    played: dict[str, set] = {"play": set(), "ended": set()}
    if sess.status == "active":
        index = sess.current_page
        view = db.execute(VIEW, {"sid": session_id, "index": index}).first()
        if view is None:
            if not write:
                return False
            db.execute(insert(PageView).values(session_id=session_id, page_index=index, shown_at=now))
            view = FirstView(now, None)
        for kind, slot in db.execute(PLAYED, {"sid": session_id, "index": index}):
            played[kind].add(slot)
    return sess, pages, view, played


class FirstView(NamedTuple):
    """A page's first-view record as a page view returns it when it created it."""

    shown_at: dt.datetime
    draft: dict | None


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
