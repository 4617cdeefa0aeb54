"""The study database's tables (SQLAlchemy 2.x declarative models).

UNIQUE constraints carry the store's guarantees (:mod:`study_app.storage`): ``answers.submit_token`` and
``(session_id, page_index)`` of answers, one session per ``(study, participant)``, one copy of each
client event per session, one first-view record per page and one media request per slot.
"""
from __future__ import annotations

import datetime as dt

from sqlalchemy import JSON, Boolean, DateTime, Float, ForeignKey, Integer, String, Text, UniqueConstraint
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

__all__ = ["utcnow", "Base", "StudyRecord", "Plan", "ParticipantSession", "Answer", "PageView", "Event",
           "MediaRequest", "MediaServed", "Entry", "AdminLogout",
           "SessionMark", "StudyFlag"]


def utcnow() -> dt.datetime:
    return dt.datetime.now(dt.timezone.utc).replace(tzinfo=None)


class Base(DeclarativeBase):
    pass


class StudyRecord(Base):
    __tablename__ = "studies"
    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    plans_sha256: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class Plan(Base):
    __tablename__ = "plans"
    __table_args__ = (UniqueConstraint("study", "key"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    study: Mapped[str] = mapped_column(String(64), index=True)
    key: Mapped[str] = mapped_column(String(64))
    position: Mapped[int] = mapped_column(Integer)
    pages: Mapped[list] = mapped_column(JSON)
    status: Mapped[str] = mapped_column(String(16), default="free", index=True)  # free/reserved/used
    session_id: Mapped[str | None] = mapped_column(String(64), nullable=True)
    reserved_until: Mapped[dt.datetime | None] = mapped_column(DateTime, nullable=True)
    times_released: Mapped[int] = mapped_column(Integer, default=0)


class ParticipantSession(Base):
    __tablename__ = "sessions"
    __table_args__ = (UniqueConstraint("study", "participant"),)
    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    study: Mapped[str] = mapped_column(String(64), index=True)
    participant: Mapped[str] = mapped_column(String(128))
    platform: Mapped[str] = mapped_column(String(16))
    platform_data: Mapped[dict] = mapped_column(JSON, default=dict)
    plan_id: Mapped[int | None] = mapped_column(ForeignKey("plans.id"), nullable=True)
    status: Mapped[str] = mapped_column(String(16), default="active")  # active/finished/failed/expired
    end_reason: Mapped[str] = mapped_column(String(32), default="")
    current_page: Mapped[int] = mapped_column(Integer, default=0)
    failed_checks: Mapped[int] = mapped_column(Integer, default=0)
    passed_checks: Mapped[int] = mapped_column(Integer, default=0)
    honeypot: Mapped[bool] = mapped_column(Boolean, default=False)
    user_agent: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    updated_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    finished_at: Mapped[dt.datetime | None] = mapped_column(DateTime, nullable=True)


class Answer(Base):
    __tablename__ = "answers"
    __table_args__ = (UniqueConstraint("session_id", "page_index"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    submit_token: Mapped[str] = mapped_column(String(64), unique=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id"), index=True)
    page_index: Mapped[int] = mapped_column(Integer)
    page_id: Mapped[str] = mapped_column(String(128))
    data: Mapped[dict] = mapped_column(JSON)
    attention_passed: Mapped[bool | None] = mapped_column(Boolean, nullable=True)
    shown_at: Mapped[dt.datetime] = mapped_column(DateTime)
    answered_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    rt_ms: Mapped[int] = mapped_column(Integer)
    client_rt_ms: Mapped[int | None] = mapped_column(Integer, nullable=True)
    events_dropped = 0      # not stored: new events of this answer the caps left out (told to the client)


class PageView(Base):
    """First time a page was shown (response times) and the autosaved draft of its answer."""
    __tablename__ = "page_views"
    __table_args__ = (UniqueConstraint("session_id", "page_index"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id"), index=True)
    page_index: Mapped[int] = mapped_column(Integer)
    shown_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)
    draft: Mapped[dict | None] = mapped_column(JSON, nullable=True)
    draft_at: Mapped[dt.datetime | None] = mapped_column(DateTime, nullable=True)


class Event(Base):
    """Interaction log: play/pause/seek/ended/choice events with media and client times."""
    __tablename__ = "events"
    __table_args__ = (UniqueConstraint("session_id", "client_id"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id"), index=True)
    client_id: Mapped[str] = mapped_column(String(64))
    page_index: Mapped[int] = mapped_column(Integer)
    kind: Mapped[str] = mapped_column(String(16))
    slot: Mapped[int | None] = mapped_column(Integer, nullable=True)
    media_time: Mapped[float | None] = mapped_column(Float, nullable=True)
    client_ms: Mapped[float | None] = mapped_column(Float, nullable=True)
    detail: Mapped[str] = mapped_column(String(200), default="")
    server_time: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class MediaRequest(Base):
    """A media slot of a page that the session fetched from the server (first time): the server's own
    evidence of playback (:mod:`study_app.playback`)."""
    __tablename__ = "media_requests"
    __table_args__ = (UniqueConstraint("session_id", "page_index", "slot"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id"), index=True)
    page_index: Mapped[int] = mapped_column(Integer)
    slot: Mapped[int] = mapped_column(Integer)
    first_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class MediaServed(Base):
    """One media response with a body: the byte range the server sent (inclusive), the file's length and
    when (:mod:`study_app.served`)."""
    __tablename__ = "media_served"
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id"), index=True)
    page_index: Mapped[int] = mapped_column(Integer)
    slot: Mapped[int] = mapped_column(Integer)
    first_byte: Mapped[int] = mapped_column(Integer)
    last_byte: Mapped[int] = mapped_column(Integer)
    total: Mapped[int] = mapped_column(Integer)
    status: Mapped[int] = mapped_column(Integer)
    served_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class Entry(Base):
    """A session created from a client address (a keyed hash of it, never the address itself): the limit
    on new sessions per address counts these."""
    __tablename__ = "session_entries"
    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    study: Mapped[str] = mapped_column(String(64), index=True)
    address: Mapped[str] = mapped_column(String(64), index=True)
    session_id: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow, index=True)


class AdminLogout(Base):
    """An admin login ended by logging out: its cookie's random id, refused from then on by every worker."""
    __tablename__ = "admin_logouts"
    nonce: Mapped[str] = mapped_column(String(64), primary_key=True)
    logged_out_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class SessionMark(Base):
    """What the researcher said about a session during the study: a pilot session (kept out of the export
    by default) or one excluded, with the reason (:mod:`study_app.operations`)."""
    __tablename__ = "session_marks"
    session_id: Mapped[str] = mapped_column(ForeignKey("sessions.id"), primary_key=True)
    pilot: Mapped[bool] = mapped_column(Boolean, default=False)
    excluded: Mapped[bool] = mapped_column(Boolean, default=False)
    reason: Mapped[str] = mapped_column(String(500), default="")
    marked_at: Mapped[dt.datetime] = mapped_column(DateTime, default=utcnow)


class StudyFlag(Base):
    """A switch of a running study, e.g. ``pilot`` (new sessions are pilot sessions) or ``topups`` (how
    many top-up batches of plans were added)."""
    __tablename__ = "study_flags"
    study: Mapped[str] = mapped_column(String(64), primary_key=True)
    name: Mapped[str] = mapped_column(String(32), primary_key=True)
    value: Mapped[str] = mapped_column(String(200), default="")
