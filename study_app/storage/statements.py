"""The statements of the participant requests (page view, answer, video), built once with bound parameters:
building a statement costs more CPU than SQLite running it (``benchmarks/study_request_cost.py``)."""
from __future__ import annotations

from sqlalchemy import bindparam, select
from sqlalchemy.orm import defer

from study_app.storage.tables import Answer, Event, PageView, ParticipantSession, Plan

__all__ = ["SESSION_ROW", "SESSION_AND_PLAN", "SESSION_AND_PLAN_LOCKED", "SESSION_STATE", "PAGES", "VIEW",
           "VIEW_SHOWN", "PLAYED", "ANSWER_BY_TOKEN", "SLOTS_WITH"]

# a session's columns and its plan's status and reservation end, as one row (parameter ``sid``)
SESSION_ROW = select(*ParticipantSession.__table__.c, Plan.status.label("plan_status"),
                     Plan.reserved_until.label("plan_reserved_until")).outerjoin(
    Plan, Plan.id == ParticipantSession.plan_id).where(ParticipantSession.id == bindparam("sid"))
# the session and its plan as ORM objects, the plan's pages left unread (``sid``); locked: the session row
SESSION_AND_PLAN = (select(ParticipantSession, Plan).outerjoin(Plan, Plan.id == ParticipantSession.plan_id)
                    .where(ParticipantSession.id == bindparam("sid")).options(defer(Plan.pages)))
SESSION_AND_PLAN_LOCKED = SESSION_AND_PLAN.with_for_update(of=ParticipantSession)
# what a video request checks (``sid``)
SESSION_STATE = select(ParticipantSession.id, ParticipantSession.status, ParticipantSession.current_page,
                       ParticipantSession.plan_id).where(ParticipantSession.id == bindparam("sid"))
PAGES = select(Plan.pages).where(Plan.id == bindparam("plan"))
_ON_PAGE = (PageView.session_id == bindparam("sid"), PageView.page_index == bindparam("index"))
VIEW = select(PageView.shown_at, PageView.draft).where(*_ON_PAGE)        # a page's first view (``sid``, ``index``)
VIEW_SHOWN = select(PageView.shown_at).where(*_ON_PAGE)
PLAYED = select(Event.kind, Event.slot).where(Event.session_id == bindparam("sid"),
                                              Event.page_index == bindparam("index"),
                                              Event.kind.in_(("play", "ended")))
SLOTS_WITH = select(Event.slot).where(Event.session_id == bindparam("sid"), Event.page_index == bindparam("index"),
                                      Event.kind == bindparam("kind"))
ANSWER_BY_TOKEN = select(Answer).where(Answer.submit_token == bindparam("token"))
