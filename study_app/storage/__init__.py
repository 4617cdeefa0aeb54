"""Storage of plans, sessions, answers and interaction logs (SQLAlchemy 2.x).

SQLite (WAL journal, ``synchronous=FULL``, every transaction ``BEGIN IMMEDIATE``) by default,
PostgreSQL by URL. Guarantees:

* an answer is committed before the server acknowledges it;
* ``answers.submit_token`` is UNIQUE and ``(session_id, page_index)`` is UNIQUE: a retried or
  double-clicked submission returns the first acknowledgement and creates nothing; a
  different answer for an already answered page is refused, never written over it;
* one session per participant per study (UNIQUE ``(study, participant)``);
* plans are handed out with a reservation that expires and is re-released.

The parts: :mod:`~study_app.storage.tables` (the SQLAlchemy tables), :mod:`~study_app.storage.engine`
(the engine for a URL, SQLite pragmas, creating the tables and storing a study's plans),
:mod:`~study_app.storage.store` (the operations) and :mod:`~study_app.storage.events` (the interaction
log: caps, reading it back). This package exports the names callers use.
"""
from __future__ import annotations

from study_app.storage.engine import init_db, make_engine
from study_app.storage.events import PLAYBACK_KINDS, EventLog
from study_app.storage.store import Store, SubmitStatus
from study_app.storage.tables import (
    AdminLogout,
    Answer,
    Base,
    Entry,
    Event,
    MediaRequest,
    MediaServed,
    PageView,
    ParticipantSession,
    Plan,
    SessionMark,
    StudyFlag,
    StudyRecord,
    utcnow,
)

__all__ = ["make_engine", "init_db", "Store", "SubmitStatus", "EventLog", "PLAYBACK_KINDS", "utcnow", "Base",
           "StudyRecord", "Plan", "ParticipantSession", "Answer", "PageView", "Event", "MediaRequest", "MediaServed", "Entry",
           "AdminLogout", "SessionMark", "StudyFlag"]
