"""The study database's engine and its set-up.

SQLite (the default) runs in WAL mode with ``synchronous=FULL``, a 60 s busy timeout, foreign keys on, and
every writing transaction opened with ``BEGIN IMMEDIATE`` (read-only work, marked with the
``evalsuite_readonly`` execution option, takes no lock). PostgreSQL, given by URL, gets a connection pool
that pings a connection before handing it out when it sat unused for :data:`PING_AFTER_IDLE_S` seconds.
:func:`init_db` creates the tables and stores a study's plans once.

A SQLite database file gets the write queue (:mod:`study_app.storage.writequeue`): writers of every process
and thread wait for their turn in the kernel instead of polling in SQLite's busy handler. A writing session
with the ``evalsuite_relaxed`` execution option (a record that acknowledges nothing, e.g. a page's first
view) commits with ``synchronous=NORMAL``: no fsync of its own, durable through a crash of the server
(WAL), and through a crash of the machine once the next FULL commit (any answer) has synced the log; on
PostgreSQL with ``synchronous_commit`` off for that transaction. Answers are never written so.
``EVALSUITE_SQLITE_WRITE_QUEUE=0`` turns the queue off (``benchmarks/study_load.py --no-write-queue``
compares).
"""
from __future__ import annotations

import os
import time

from sqlalchemy import create_engine, event, make_url
from sqlalchemy.exc import IntegrityError, OperationalError, ProgrammingError
from sqlalchemy.orm import sessionmaker

from study_app import timing
from study_app.design import plans_digest
from study_app.errors import StudyStateError
from study_app.storage.tables import Base, Plan, StudyRecord
from study_app.storage.writequeue import connection_class

__all__ = ["make_engine", "init_db", "WRITE_QUEUE_ENV"]

WRITE_QUEUE_ENV = "EVALSUITE_SQLITE_WRITE_QUEUE"      # "0": no write queue (to compare with it, benchmarks)


PING_AFTER_IDLE_S = 5.0


def _ping_when_idle(engine) -> None:
    """Test a pooled connection with a round trip before use only when it sat in the pool for over
    :data:`PING_AFTER_IDLE_S` seconds (SQLAlchemy's ``pool_pre_ping`` pings on every check-out: a busy server's
    requests check out several times each, and each ping costs the app and the database a round trip). A dead
    connection is replaced (``DisconnectionError``: the pool retries with a fresh one). One that died within the
    last seconds fails its statement instead; SQLAlchemy then drops the pool's older connections, and the
    participant's browser retries the request with the same submit token (docs/study_app.md)."""
    from sqlalchemy.exc import DisconnectionError

    @event.listens_for(engine, "checkin")
    def _checked_in(_dbapi_connection, record):
        record.info["evalsuite_idle_since"] = time.monotonic()

    @event.listens_for(engine, "checkout")
    def _checked_out(dbapi_connection, record, _proxy):
        since = record.info.get("evalsuite_idle_since")
        if since is None or time.monotonic() - since <= PING_AFTER_IDLE_S:
            return                      # new, or back in the pool a moment ago
        try:
            engine.dialect.do_ping(dbapi_connection)      # the ping pool_pre_ping sends (no transaction left open)
        except engine.dialect.loaded_dbapi.Error as exc:
            raise DisconnectionError(f"pooled connection failed its ping: {exc}") from exc


def make_engine(url: str):
    """Engine for ``url``; SQLite gets WAL, full fsync, a busy timeout, BEGIN IMMEDIATE and (a database file)
    the write queue."""
    if url.startswith("sqlite"):
        connect_args: dict = {"timeout": 60, "check_same_thread": False}
        database = make_url(url).database
        queue = os.environ.get(WRITE_QUEUE_ENV, "1") != "0"
        if queue and database and database != ":memory:" and not database.startswith("file:"):
            connect_args["factory"] = connection_class(database)
        engine = create_engine(url, connect_args=connect_args)

        @event.listens_for(engine, "connect")
        def _sqlite_connect(dbapi_conn, record):
            # Let SQLAlchemy's "begin" hook start transactions (pysqlite's own BEGIN is deferred,
            # which turns read-then-write transactions into SQLITE_BUSY under concurrency).
            dbapi_conn.isolation_level = None
            cur = dbapi_conn.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA synchronous=FULL")
            cur.execute("PRAGMA busy_timeout=60000")
            cur.execute("PRAGMA foreign_keys=ON")
            cur.close()
            record.info["evalsuite_synchronous"] = "FULL"

        @event.listens_for(engine, "begin")
        def _sqlite_begin(conn):
            # Writers queue for the lock up front; read-only work (video requests, exports)
            # takes no lock at all under WAL.
            options = conn.get_execution_options()
            readonly = options.get("evalsuite_readonly")
            if not readonly:
                # records that are no acknowledgement (a page's first view) may skip the fsync
                # ("evalsuite_relaxed": synchronous=NORMAL, see the module's docstring); everything else FULL
                sync = "NORMAL" if options.get("evalsuite_relaxed") else "FULL"
                info = conn.connection.info
                if info.get("evalsuite_synchronous") != sync:
                    conn.exec_driver_sql(f"PRAGMA synchronous={sync}")
                    info["evalsuite_synchronous"] = sync
                lock = getattr(conn.connection.dbapi_connection, "lock_writes", None)
                if lock is not None:
                    timing.timed("lock", lock)       # the write queue (see the module's docstring)
            conn.exec_driver_sql("BEGIN" if readonly else "BEGIN IMMEDIATE")
    else:
        engine = create_engine(url, pool_size=5, max_overflow=10)
        _ping_when_idle(engine)
        if engine.dialect.name == "postgresql":
            @event.listens_for(engine, "begin")
            def _pg_begin(conn):
                if conn.get_execution_options().get("evalsuite_relaxed"):
                    # the commit does not wait for the WAL flush (an answer's transaction always does)
                    conn.exec_driver_sql("SET LOCAL synchronous_commit TO OFF")
    if timing.enabled():
        timing.instrument_engine(engine)
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
