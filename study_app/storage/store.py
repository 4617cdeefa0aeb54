"""The store: every database operation of the study app, each one transaction (the guarantees they keep
are listed in :mod:`study_app.storage`)."""
from __future__ import annotations

import datetime as dt
import enum
import secrets
import time

from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError, OperationalError
from sqlalchemy.orm import sessionmaker

from study_app.errors import StudyStateError
from study_app.media_log import MediaLog
from study_app.policy import Rules, SessionState, after_answer, plan_after_end
from study_app.storage import statements as sq
from study_app.storage.dump import dump
from study_app.storage.events import add_events, slots_with
from study_app.storage.pageviews import view_current_page
from study_app.storage.tables import Answer, Entry, MediaRequest, PageView, ParticipantSession, Plan, utcnow

__all__ = ["Store", "SubmitStatus"]


class SubmitStatus(str, enum.Enum):
    """What :meth:`Store.submit` did with an answer (the value is what the answer endpoint reports)."""

    STORED = "stored"          # stored now
    DUPLICATE = "duplicate"    # this token was seen before: the first answer is returned
    AHEAD = "ahead"            # a page after the session's current one
    MISSING = "missing"        # no such session
    CONFLICT = "conflict"      # the page already has a different answer, or is not the current page
    FULL = "full"              # a session without a plan answered its first page and no plan is free


class Store:
    """All database operations of the app; each method is one transaction."""

    def __init__(self, engine, rules: Rules | None = None, entry_pages: list[dict] | None = None,
                 fixed_pages: bool = False):
        """``rules``: the study's session policy settings (:class:`study_app.policy.Rules`);
        ``entry_pages``: what a session without a plan shows (:func:`study_app.design.entry_pages`; None:
        every session reserves its plan when it is created); ``fixed_pages``: no plan's pages ever change
        once stored (a study without adaptive blocks), so each plan's pages are read from the database once
        per process and kept (plans added later, e.g. by a top-up, have new ids and are read when first
        used)."""
        self.engine = engine
        self.fixed_pages = fixed_pages
        self._pages_of: dict[int, list[dict]] = {}
        # Sessions whose current page this process showed (a hint only: which transaction to try first in
        # view_current_page); forgotten when a session answers.
        self._viewed: set[str] = set()
        self.rules = rules or Rules()
        self.entry_pages = entry_pages
        self.Session = sessionmaker(engine, expire_on_commit=False)
        # For reads only: never writes, so on SQLite it does not take the write lock.
        self.ReadSession = sessionmaker(engine.execution_options(evalsuite_readonly=True),
                                        expire_on_commit=False)
        # For records that acknowledge nothing (a page's first view, the media log): no fsync of their own
        # (study_app.storage.engine, "evalsuite_relaxed").
        self.RelaxedSession = sessionmaker(engine.execution_options(evalsuite_relaxed=True),
                                           expire_on_commit=False)
        self.media_log = MediaLog(engine, self.RelaxedSession, MediaRequest)
        self.is_postgres = engine.dialect.name == "postgresql"

    def _locked(self, stmt):
        return stmt.with_for_update() if self.is_postgres else stmt

    # --- sessions and plan reservations -------------------------------------------------

    def release_expired(self, db, study_id: str, now: dt.datetime):
        """Expire sessions whose reservation ran out and free their plans."""
        expired = db.scalars(self._locked(select(Plan).where(
            Plan.study == study_id, Plan.status == "reserved", Plan.reserved_until < now))).all()
        for plan in expired:
            sess = db.get(ParticipantSession, plan.session_id) if plan.session_id else None
            if sess is not None and sess.status == "active":
                sess.status, sess.end_reason, sess.updated_at = "expired", "reservation_expired", now
            plan.status, plan.session_id, plan.reserved_until = "free", None, None
            plan.times_released += 1

    def start_session(self, study, participant: str, platform: str, platform_data: dict,
                      user_agent: str, address: str = ""):
        """Create a session for a participant id (or find theirs).

        Returns ``(session, state)``: ``"existing"`` (the participant already has a session for this study,
        returned unchanged so that the caller resumes or refuses), ``"created"``, ``"full"`` (no plan is
        free; nothing created) or ``"throttled"`` (``address``, a keyed hash of the client address, created
        ``study.new_sessions_per_address`` sessions within the window; nothing created). A new session holds
        no plan when the store has ``entry_pages``: it reserves one when its first page is answered
        (:meth:`submit`); otherwise the plan is reserved now.
        """
        now = utcnow()
        for _attempt in range(3):
            try:
                with self.Session.begin() as db:
                    existing = db.scalars(select(ParticipantSession).where(
                        ParticipantSession.study == study.id,
                        ParticipantSession.participant == participant)).first()
                    if existing is not None:
                        plan = db.get(Plan, existing.plan_id) if existing.plan_id is not None else None
                        self._check_expiry(db, existing, plan, now)
                        return existing, "existing"
                    limit = study.new_sessions_per_address
                    if limit and address and self.recent_entries(db, study, address, now)[0] >= limit:
                        return None, "throttled"
                    self.release_expired(db, study.id, now)
                    plan = self._free_plan(db, study.id)
                    if plan is None:
                        return None, "full"
                    sess = ParticipantSession(
                        id=secrets.token_urlsafe(18), study=study.id, participant=participant,
                        platform=platform, platform_data=platform_data, plan_id=None,
                        user_agent=user_agent[:1000], created_at=now, updated_at=now)
                    db.add(sess)
                    db.flush()
                    if address:
                        db.add(Entry(study=study.id, address=address, session_id=sess.id, created_at=now))
                    if self.entry_pages is None:
                        self._reserve(db, sess, plan, now)
                return sess, "created"
            except IntegrityError:
                # Same participant entering twice at the same moment: the other request won.
                continue
        raise RuntimeError("could not start a session")

    def recent_entries(self, db, study, address: str, now: dt.datetime) -> tuple[int, int]:
        """(sessions created from ``address`` within the study's window, seconds until the oldest of them
        leaves the window)."""
        since = now - dt.timedelta(minutes=study.new_sessions_window_minutes)
        n, oldest = db.execute(select(func.count(Entry.id), func.min(Entry.created_at)).where(
            Entry.study == study.id, Entry.address == address, Entry.created_at >= since)).one()
        wait = 0 if oldest is None else max(1, int((oldest - since).total_seconds()) + 1)
        return int(n), wait

    def retry_after(self, study, address: str) -> int:
        """Seconds until ``address`` may create a session again."""
        with self.ReadSession() as db:
            return self.recent_entries(db, study, address, utcnow())[1]

    def _free_plan(self, db, study_id: str) -> Plan | None:
        stmt = (select(Plan).where(Plan.study == study_id, Plan.status == "free")
                .order_by(Plan.position).limit(1))
        if self.is_postgres:
            stmt = stmt.with_for_update(skip_locked=True)
        return db.scalars(stmt).first()

    def _reserve(self, db, sess: ParticipantSession, plan: Plan, now: dt.datetime) -> None:
        sess.plan_id = plan.id
        plan.status, plan.session_id = "reserved", sess.id
        plan.reserved_until = now + dt.timedelta(minutes=self.rules.reservation_minutes)

    def has_free_plan(self, study_id: str) -> bool:
        """Whether a new participant could get a plan now (a free one, or one whose reservation ran out)."""
        now = utcnow()
        with self.ReadSession() as db:
            return db.scalar(select(Plan.id).where(Plan.study == study_id, (Plan.status == "free") | (
                (Plan.status == "reserved") & (Plan.reserved_until < now))).limit(1)) is not None

    def session_and_plan(self, db, session_id: str, lock: bool = False):
        """(session, its plan or None) in one statement, (None, None) for an unknown session; the plan's pages
        are read only when asked for (:meth:`pages_of`). ``lock``: lock the session row (PostgreSQL)."""
        stmt = sq.SESSION_AND_PLAN_LOCKED if lock and self.is_postgres else sq.SESSION_AND_PLAN
        row = db.execute(stmt, {"sid": session_id}).first()
        if row is None:
            return None, None
        sess, plan = row
        if plan is None and sess.plan_id is not None:
            raise StudyStateError(f"session {sess.id} refers to plan {sess.plan_id}, which the database lacks")
        return sess, plan

    def pages_of(self, plan_id: int, read) -> list[dict]:
        """A plan's pages, ``read()`` unless kept: they are kept per process when they never change
        (``fixed_pages``). Callers never modify them."""
        pages = self._pages_of.get(plan_id) if self.fixed_pages else None
        if pages is None:
            pages = read()
            if self.fixed_pages and pages is not None:
                self._pages_of[plan_id] = pages
        return pages

    def _pages(self, sess, plan: Plan | None) -> list[dict]:
        """The pages a session shows: its plan's, or the entry pages while it holds no plan."""
        if plan is None:
            if self.entry_pages is None:
                raise StudyStateError(f"session {sess.id} holds no plan and this study has no entry pages")
            return self.entry_pages
        return self.pages_of(plan.id, lambda: plan.pages)

    @staticmethod
    def _expiry_due(sess, plan, now) -> bool:
        """Whether the session's plan reservation ran out (and :meth:`release_expired` must run)."""
        if sess.status != "active" or plan is None:
            return False
        return plan.status == "reserved" and plan.reserved_until < now

    def _check_expiry(self, db, sess, plan, now):
        if self._expiry_due(sess, plan, now):
            self.release_expired(db, sess.study, now)

    def load(self, session_id: str):
        """(session, plan pages) of a participant's session, or (None, None)."""
        now = utcnow()
        with self.Session.begin() as db:
            sess, plan = self.session_and_plan(db, session_id)
            if sess is None:
                return None, None
            self._check_expiry(db, sess, plan, now)
            return sess, self._pages(sess, plan)

    def read_session(self, session_id: str):
        """(session, plan pages) without touching reservations (read-only, no lock); the session is a row of
        its ``id``, ``status``, ``current_page`` and ``plan_id`` only (no ORM object: a video request's check)."""
        with self.ReadSession() as db:
            sess = db.execute(sq.SESSION_STATE, {"sid": session_id}).first()
            if sess is None:
                return None, None
            pages = None if sess.plan_id is None else self.pages_of(
                sess.plan_id, lambda: db.scalar(sq.PAGES, {"plan": sess.plan_id}))
            if pages is None and sess.plan_id is not None:
                raise StudyStateError(f"session {sess.id} refers to plan {sess.plan_id}, which the database lacks")
            return sess, pages if pages is not None else self._pages(sess, None)

    def view_current_page(self, session_id: str):
        """A page view (:func:`study_app.storage.pageviews.view_current_page`)."""
        return view_current_page(self, session_id)

    def save_draft(self, session_id: str, page_index: int, draft: dict) -> bool:
        with self.Session.begin() as db:
            sess = db.get(ParticipantSession, session_id)
            if sess is None or sess.status != "active" or sess.current_page != page_index:
                return False
            view = db.scalars(select(PageView).where(PageView.session_id == session_id,
                                                     PageView.page_index == page_index)).first()
            if view is None:
                view = PageView(session_id=session_id, page_index=page_index, shown_at=utcnow())
                db.add(view)
            view.draft, view.draft_at = draft, utcnow()
            return True

    def log_events(self, session_id: str, page_index: int, events: list[dict]) -> tuple[int, str]:
        """Store a batch of events (see :func:`study_app.storage.events.add_events`); returns how many the caps dropped, and which."""
        for _attempt in range(3):
            try:
                with self.Session.begin() as db:
                    # The session row is the lock that keeps concurrent batches within the caps.
                    db.scalars(self._locked(select(ParticipantSession.id).where(
                        ParticipantSession.id == session_id))).first()
                    return add_events(db, self.rules, session_id, page_index, events)
            except IntegrityError:
                continue
        raise RuntimeError("could not store the events")

    def record_media_request(self, session_id: str, page_index: int, slot: int) -> None:
        """Note that the session fetched this media slot once (:class:`study_app.media_log.MediaLog`)."""
        self.media_log.record(session_id, page_index, slot, utcnow())

    def submit(self, session_id: str, page_index: int, token: str, validate):
        """Store the answer to page ``page_index`` once, idempotently.

        ``validate(pages, played)`` (see :func:`study_app.submission.validate_submission`) returns the
        :class:`~study_app.submission.Submission` or raises; ``played(kind)`` gives the media slots with an
        event of that kind on the page. The session then moves on as :func:`study_app.policy.after_answer`
        says. Returns ``(status, answer, session)`` with a :class:`SubmitStatus` (``answer`` is the stored
        answer for STORED, the first one for DUPLICATE, else None; ``session`` is None for MISSING).
        """
        for attempt in range(3):
            try:
                with self.Session.begin() as db:
                    # Lock the session first, then look for the token: a concurrent retry that
                    # waited for the lock then sees the committed first answer.
                    sess, plan = self.session_and_plan(db, session_id, lock=True)
                    if sess is None:
                        return SubmitStatus.MISSING, None, None
                    prior = db.scalars(sq.ANSWER_BY_TOKEN, {"token": token}).first()
                    if prior is not None:
                        if prior.session_id != session_id or prior.page_index != page_index:
                            return SubmitStatus.CONFLICT, None, sess
                        return SubmitStatus.DUPLICATE, prior, sess
                    now = utcnow()
                    self._check_expiry(db, sess, plan, now)
                    if sess.status == "active" and page_index > sess.current_page:
                        return SubmitStatus.AHEAD, None, sess
                    if sess.status != "active" or sess.current_page != page_index:
                        return SubmitStatus.CONFLICT, None, sess
                    if sess.plan_id is None:
                        # The participant really starts (answers the first page, e.g. gives consent): only
                        # now is a plan reserved. Rolled back with the answer if the answer is refused.
                        self.release_expired(db, sess.study, now)
                        free = self._free_plan(db, sess.study)
                        if free is None:
                            return SubmitStatus.FULL, None, sess
                        self._reserve(db, sess, free, now)
                        plan = free
                    pages = self.pages_of(plan.id, lambda held=plan: held.pages)
                    sub = validate(pages, lambda kind: slots_with(db, session_id, page_index, kind))
                    dropped, _ = add_events(db, self.rules, session_id, page_index, sub.events)
                    shown = db.scalar(sq.VIEW_SHOWN, {"sid": session_id, "index": page_index}) or now
                    answer = Answer(submit_token=token, session_id=session_id, page_index=page_index,
                                    page_id=pages[page_index]["page"], data=sub.data,
                                    attention_passed=sub.outcome.attention, shown_at=shown, answered_at=now,
                                    rt_ms=max(0, int((now - shown).total_seconds() * 1000)),
                                    client_rt_ms=sub.client_rt_ms)
                    db.add(answer)
                    answer.events_dropped = dropped     # reported to the client, not stored
                    state = SessionState(sess.current_page, sess.passed_checks, sess.failed_checks)
                    move = after_answer(state, sub.outcome, pages, self.rules)
                    sess.current_page, sess.updated_at = move.current_page, now
                    sess.passed_checks, sess.failed_checks = move.passed_checks, move.failed_checks
                    if move.honeypot:
                        sess.honeypot = True
                    if move.ended:
                        self._end(sess, plan, move.status, move.end_reason, now)
                    else:
                        # Sliding reservation: an active participant keeps their plan.
                        plan.reserved_until = now + dt.timedelta(minutes=self.rules.reservation_minutes)
                if sess.status == "active":
                    self._viewed.discard(session_id)      # its next page is new: written at its first view
                else:
                    self._viewed.add(session_id)          # an ended session's page writes nothing: read first
                return SubmitStatus.STORED, answer, sess
            except IntegrityError:
                # A concurrent duplicate (same token, or same page) won the race: re-read.
                continue
            except OperationalError:
                # PostgreSQL deadlock victim (an expiring reservation at the same moment) or a
                # SQLite lock timeout: nothing was written, try again.
                if attempt == 2:
                    raise
                time.sleep(0.05)
        raise RuntimeError("could not store the answer")

    def _end(self, sess, plan, status, reason, now):
        sess.status, sess.end_reason, sess.finished_at = status, reason, now
        if plan_after_end(status, self.rules, reason) == "used":
            plan.status, plan.reserved_until = "used", None
        else:
            # A failed participant's data is excluded, so their plan goes to someone else.
            plan.status, plan.session_id, plan.reserved_until = "free", None, None
            plan.times_released += 1

    # --- admin / export -------------------------------------------------------------------

    def dump(self, study_id: str) -> dict:
        """Sessions, plans, answers and logs of a study (:func:`study_app.storage.dump.dump`)."""
        return dump(self, study_id)
