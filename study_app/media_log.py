"""The record of which media slots a session fetched (the server's evidence for :mod:`study_app.playback`).

A video request must not wait for the database: it records its slot once (a memory set remembers what is
recorded), without waiting for the disk (SQLite ``synchronous=NORMAL`` for that transaction: in WAL mode it
survives a crash of the server, not of the machine; PostgreSQL ``synchronous_commit`` off), and on SQLite
without waiting for the write lock either: when another writer holds it, the record is queued and a
background thread of the process writes the queue in one transaction a moment later. A server killed in
that moment loses those records (the page may then be flagged); answers are never written this way.

The bytes sent per media response (``media_served``, :mod:`study_app.served`) go through the same writer
(:meth:`MediaLog.served`), so a video response never waits for a write lock either. Behind nginx
(``MEDIA_SERVER = "nginx"``) the app does not send the bytes: :meth:`flush` first reads what nginx logged
(:mod:`study_app.media_nginx`, ``access_log``).
"""
from __future__ import annotations

import atexit
import logging
import os
import sqlite3
import threading
import time
import weakref

from sqlalchemy.exc import DBAPIError, IntegrityError

__all__ = ["MediaLog"]

log = logging.getLogger(__name__)
INSERT = ("INSERT OR IGNORE INTO media_requests (session_id, page_index, slot, first_at) VALUES (?, ?, ?, ?)")
INSERT_SERVED = ("INSERT INTO media_served (session_id, page_index, slot, first_byte, last_byte, total, status, "
                 "served_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?)")


class MediaLog:
    def __init__(self, engine, session_factory, model, access_log: str | None = None) -> None:
        """``session_factory``: sessions whose writes need no fsync of their own (the store's ``RelaxedSession``:
        on PostgreSQL ``synchronous_commit`` off); ``access_log``: nginx's media log to read on :meth:`flush`
        (default ``EVALSUITE_MEDIA_ACCESS_LOG``)."""
        from study_app.storage.tables import MediaServed  # not at the top: the storage package imports this
        self.engine, self.Session, self.model, self.served_model = engine, session_factory, model, MediaServed
        self.access_log = access_log or os.environ.get("EVALSUITE_MEDIA_ACCESS_LOG") or None
        self.sqlite = engine.dialect.name == "sqlite"
        self.recorded: set[tuple[str, int, int]] = set()
        self._pending: list[tuple[str, tuple]] = []        # (SQLite statement, row)
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        _LOGS.add(self)

    def record(self, session_id: str, page_index: int, slot: int, now) -> None:
        key = (session_id, page_index, slot)
        if key in self.recorded:
            return
        row = (*key, now)
        try:
            if self.sqlite:
                if not self._sqlite_insert(INSERT, [row], wait=False):
                    self._defer(INSERT, row)
            elif self.engine.dialect.name == "postgresql":
                from sqlalchemy.dialects.postgresql import insert as pg_insert
                with self.Session.begin() as db:      # relaxed: synchronous_commit off (the engine)
                    db.execute(pg_insert(self.model).values(session_id=session_id, page_index=page_index,
                                                            slot=slot, first_at=now).on_conflict_do_nothing())
            else:
                try:
                    with self.Session.begin() as db:
                        db.add(self.model(session_id=session_id, page_index=page_index, slot=slot, first_at=now))
                except IntegrityError:
                    pass        # a concurrent request (another range of the same video) recorded it
        except (DBAPIError, sqlite3.Error) as exc:
            # The video is served all the same; a later request of it records it.
            log.warning("could not record a media request of session %s: %s", session_id, exc)
            return
        if len(self.recorded) > 200_000:
            self.recorded.clear()
        self.recorded.add(key)

    def served(self, session_id: str, page_index: int, slot: int, first: int, last: int, total: int,
               status: int, now) -> None:
        """Record the byte range ``first..last`` (inclusive) of a ``total``-byte file sent with ``status``,
        without waiting: queued for the background writer (written within ~50 ms, or by :meth:`flush`)."""
        self._defer(INSERT_SERVED, (session_id, page_index, slot, first, last, total, status, now))

    def flush(self) -> None:
        """Write what is queued now, after what nginx logged (exports call this, so that they see this
        process's records)."""
        if self.access_log:
            from study_app.media_nginx import ingest
            ingest(self, self.access_log)
        with self._lock:
            pending, self._pending = self._pending, []
        for sql in dict.fromkeys(q for q, _row in pending):
            rows = [row for q, row in pending if q == sql]
            try:
                self.write(sql, rows)
            except (DBAPIError, sqlite3.Error) as exc:
                log.warning("could not record %d media rows: %s", len(rows), exc)

    def write(self, sql: str, rows: list) -> None:
        """Write ``rows`` of ``sql`` (:data:`INSERT` or :data:`INSERT_SERVED`) now, waiting for the lock."""
        if self.sqlite:
            self._sqlite_insert(sql, rows, wait=True)
        elif sql is INSERT_SERVED:
            self.insert_served(rows)
        else:
            for s, p, k, t in rows:
                self.record(s, p, k, t)

    def write_requests(self, rows: list) -> None:
        """Write ``media_requests`` rows (session, page, slot, first time) now; a slot already recorded stays."""
        self.write(INSERT, rows)

    def write_served(self, rows: list) -> None:
        """Write ``media_served`` rows (session, page, slot, first, last, total, status, time) now."""
        self.write(INSERT_SERVED, rows)

    def insert_served(self, rows: list) -> None:
        """Write ``media_served`` rows in one transaction (PostgreSQL: without waiting for the disk)."""
        names = ("session_id", "page_index", "slot", "first_byte", "last_byte", "total", "status", "served_at")
        with self.Session.begin() as db:          # relaxed: synchronous_commit off (the engine)
            db.add_all([self.served_model(**dict(zip(names, row))) for row in rows])

    def _defer(self, sql: str, row: tuple) -> None:
        with self._lock:
            self._pending.append((sql, row))
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._run, name="evalsuite-media-log", daemon=True)
                self._thread.start()

    def _run(self) -> None:
        idle = 0
        while idle < 100:                     # ends after ~5 s without work; started again on demand
            time.sleep(0.05)
            with self._lock:
                busy = bool(self._pending)
            if busy:
                idle = 0
                self.flush()
            else:
                idle += 1

    def _sqlite_insert(self, sql: str, rows: list, wait: bool) -> bool:
        """Insert ``rows`` in one transaction; without ``wait``, give up at once (False) if another writer
        holds the lock."""
        raw = self.engine.raw_connection()
        restored = False
        try:
            con = raw.dbapi_connection
            cur = con.cursor()
            cur.execute("PRAGMA synchronous=NORMAL")          # not allowed inside a transaction
            if not wait:
                cur.execute("PRAGMA busy_timeout=0")
            try:
                # the engine's write queue first (study_app.storage.engine); commit() and rollback() leave it
                lock = getattr(con, "lock_writes", None)
                if lock is not None and not lock(wait):
                    return False
                cur.execute("BEGIN IMMEDIATE")
                cur.executemany(sql, [(*r[:-1], r[-1].strftime("%Y-%m-%d %H:%M:%S.%f")) for r in rows])
                con.commit()
                return True
            except sqlite3.OperationalError as exc:
                con.rollback()
                if not wait and "locked" in str(exc):
                    return False
                raise
            finally:
                cur.execute("PRAGMA synchronous=FULL")
                cur.execute("PRAGMA busy_timeout=60000")
                restored = True
                cur.close()
        finally:
            if not restored:
                raw.invalidate()      # never hand a connection with the weaker settings back to the pool
            raw.close()


_LOGS: weakref.WeakSet[MediaLog] = weakref.WeakSet()


@atexit.register
def _flush_all() -> None:                     # a server stopped normally writes its queue first
    for media_log in _LOGS:
        media_log.flush()
