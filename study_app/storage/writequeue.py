"""The write queue of a SQLite database file: writers wait their turn in the kernel, not in SQLite's busy
handler.

SQLite lets one writer in at a time and makes the others poll, sleeping 1, 2, 5, 10, ... 100 ms between tries
(its busy handler), so under load a writer of another process or thread can lose the race again and again
and wait seconds for a lock that is free most of the time. With the queue, every writing transaction of the
engine (:mod:`study_app.storage.engine`) first takes an exclusive ``flock`` on ``<database>-writers`` (each
pooled connection has its own descriptor, so threads of one process queue as processes do) and holds it until
its COMMIT or ROLLBACK: the next writer starts as soon as the lock is released. The queue only orders
writers; SQLite's own lock still guarantees correctness (a process without the queue, e.g. the CLI, falls
back to the busy handler), and the kernel releases the ``flock`` of a killed process.
"""
from __future__ import annotations

import fcntl
import os
import sqlite3
import threading
import time

from study_app import timing

__all__ = ["QueuedConnection", "connection_class"]

_held = threading.local()        # per thread: the queue files whose lock it holds (never waits for itself)


class QueuedConnection(sqlite3.Connection):
    """A sqlite3 connection whose writing transactions take the write queue at ``lock_path`` first
    (:func:`connection_class` makes one subclass per database file)."""

    lock_path = ""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._queue_fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o600)
        self._queued, self._queued_at = False, 0.0

    def lock_writes(self, wait: bool = True) -> bool:
        """Take the write queue (False: another writer holds it and ``wait`` is off). A thread that already
        holds it through another connection does not wait for itself: that connection's BEGIN IMMEDIATE then
        meets SQLite's busy timeout as it would without the queue."""
        held = _held.__dict__.setdefault("paths", set())
        if self._queued or self.lock_path in held:
            return True
        try:
            fcntl.flock(self._queue_fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            return False
        self._queued, self._queued_at = True, time.perf_counter()
        held.add(self.lock_path)
        return True

    def unlock_writes(self) -> None:
        if self._queued:
            self._queued = False
            _held.__dict__.setdefault("paths", set()).discard(self.lock_path)
            fcntl.flock(self._queue_fd, fcntl.LOCK_UN)
            timing.add("held", time.perf_counter() - self._queued_at)

    def commit(self):
        try:
            super().commit()
        finally:
            self.unlock_writes()

    def rollback(self):
        try:
            super().rollback()
        finally:
            self.unlock_writes()

    def close(self):
        try:
            super().close()
        finally:
            self.unlock_writes()
            if self._queue_fd >= 0:
                os.close(self._queue_fd)
                self._queue_fd = -1


def connection_class(database: str) -> type[QueuedConnection]:
    """The connection class (sqlite3's ``factory``) for the database file ``database``."""
    return type("QueuedConnection", (QueuedConnection,), {"lock_path": os.path.abspath(database) + "-writers"})
