"""The study database's engine and its set-up.

SQLite (the default) runs in WAL mode with ``synchronous=FULL``, a 60 s busy timeout, foreign keys on, and
every writing transaction opened with ``BEGIN IMMEDIATE`` (read-only work, marked with the
``evalsuite_readonly`` execution option, takes no lock). PostgreSQL, given by URL, gets a pre-pinged
connection pool. :func:`init_db` creates the tables and stores a study's plans once.
"""
from __future__ import annotations

import time

from sqlalchemy import create_engine, event
from sqlalchemy.exc import IntegrityError, OperationalError, ProgrammingError
from sqlalchemy.orm import sessionmaker

from study_app.design import plans_digest
from study_app.errors import StudyStateError
from study_app.storage.tables import Base, Plan, StudyRecord

__all__ = ["make_engine", "init_db"]


def make_engine(url: str):
    """Engine for ``url``; SQLite gets WAL, full fsync, a busy timeout and BEGIN IMMEDIATE."""
    if url.startswith("sqlite"):
        engine = create_engine(url, connect_args={"timeout": 60, "check_same_thread": False})

        @event.listens_for(engine, "connect")
        def _sqlite_connect(dbapi_conn, _record):
            # Let SQLAlchemy's "begin" hook start transactions (pysqlite's own BEGIN is deferred,
            # which turns read-then-write transactions into SQLITE_BUSY under concurrency).
            dbapi_conn.isolation_level = None
            cur = dbapi_conn.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA synchronous=FULL")
            cur.execute("PRAGMA busy_timeout=60000")
            cur.execute("PRAGMA foreign_keys=ON")
            cur.close()

        @event.listens_for(engine, "begin")
        def _sqlite_begin(conn):
            # Writers queue for the lock up front; read-only work (video requests, exports)
            # takes no lock at all under WAL.
            readonly = conn.get_execution_options().get("evalsuite_readonly")
            conn.exec_driver_sql("BEGIN" if readonly else "BEGIN IMMEDIATE")
    else:
        engine = create_engine(url, pool_pre_ping=True, pool_size=5, max_overflow=10)
    return engine


def init_db(engine, study, plans: dict):
    """Create tables (if missing) and store the study's plans once.

    Refuses a database whose plans for this study differ from ``plans`` (changing plans in
    the middle of a study would break the balance and the meaning of stored answers).
    """
    for attempt in range(5):
        try:
            Base.metadata.create_all(engine)
            break
        except (OperationalError, IntegrityError, ProgrammingError):
            # Several workers starting at once may race on CREATE TABLE; the loser retries.
            if attempt == 4:
                raise
            time.sleep(0.2 * (attempt + 1))
    digest = plans_digest(plans)
    Session = sessionmaker(engine)
    for attempt in range(5):
        try:
            with Session.begin() as db:
                rec = db.get(StudyRecord, study.id)
                if rec is not None:
                    if rec.plans_sha256 != digest:
                        raise StudyStateError(
                            f"the database already holds different session plans for study "
                            f"{study.id!r}; use a new database or a new study id", field="plans")
                    return
                db.add(StudyRecord(id=study.id, plans_sha256=digest))
                for i, plan in enumerate(plans["plans"]):
                    db.add(Plan(study=study.id, key=plan["key"], position=i, pages=plan["pages"]))
            return
        except IntegrityError:
            time.sleep(0.2 * (attempt + 1))
